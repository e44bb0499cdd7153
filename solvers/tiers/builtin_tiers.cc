#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/rig/fe_classic_tier.h"
#include "solvers/tiers/bekker_tier.h"
#include "solvers/tiers/empirical_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<tiers::EmpiricalTier>());
  registry.Register(std::make_unique<tiers::BekkerTier>());
  registry.Register(std::make_unique<rig::FeClassicTier>());
}

}  // namespace gonogo
