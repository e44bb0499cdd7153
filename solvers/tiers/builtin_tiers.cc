#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/rig/fe_classic_tier.h"
#include "solvers/terramech/bekker_tier.h"
#include "solvers/terramech/empirical_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<terramech::EmpiricalTier>());
  registry.Register(std::make_unique<terramech::BekkerTier>());
  registry.Register(std::make_unique<rig::FeClassicTier>());
}

}  // namespace gonogo
