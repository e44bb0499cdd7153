// Every traction tier gonogo ships, registered in one place.
#pragma once

#include "solvers/common/tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry);

}  // namespace gonogo
