#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/terramech/empirical_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<terramech::EmpiricalTier>());
}

}  // namespace gonogo
