#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/terramech/bekker_tier.h"
#include "solvers/terramech/empirical_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<terramech::EmpiricalTier>());
  registry.Register(std::make_unique<terramech::BekkerTier>());
}

}  // namespace gonogo
