#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/tiers/bekker_tier.h"
#include "solvers/tiers/empirical_tier.h"
#include "solvers/tiers/fe_classic_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<tiers::EmpiricalTier>());
  registry.Register(std::make_unique<tiers::BekkerTier>());
  registry.Register(std::make_unique<tiers::FeClassicTier>());
}

}  // namespace gonogo
