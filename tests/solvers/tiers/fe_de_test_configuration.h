// The fe-de configuration the tier's tests run: the tiny preset, ci with the procedure cut to
// 0.45 s (a curve in about 35-45 s alone on the shared 2-core machine).
#pragma once

#include "solvers/tiers/fe_de_tier.h"

namespace gonogo::tiers {

inline FeDeOptions TinyFeDeOptions() { return FeDeOptions::Preset("tiny"); }

}  // namespace gonogo::tiers
