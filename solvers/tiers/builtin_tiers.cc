#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/tiers/bekker_tier.h"
#include "solvers/tiers/empirical_tier.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/fe_classic_tier.h"

namespace gonogo {

void RegisterBuiltinTiers(TierRegistry& registry, const BuiltinTierOptions& options) {
  registry.Register(std::make_unique<tiers::EmpiricalTier>());
  registry.Register(std::make_unique<tiers::BekkerTier>());
  registry.Register(std::make_unique<tiers::FeClassicTier>());
  tiers::FeDeOptions fe_de = tiers::FeDeOptions::Preset(options.fe_de_preset);
  fe_de.ranks = options.fe_de_ranks;
  fe_de.threads = options.fe_de_threads;
  fe_de.checkpoint_every_s = options.fe_de_checkpoint_every_s;
  registry.Register(std::make_unique<tiers::FeDeTier>(fe_de));
}

}  // namespace gonogo
