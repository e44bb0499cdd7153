#include "solvers/tiers/builtin_tiers.h"

#include <memory>

#include "solvers/tiers/bekker_tier.h"
#include "solvers/tiers/empirical_tier.h"
#include "solvers/tiers/fe_ann_tier.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/fe_classic_tier.h"
#include "solvers/tiers/surrogate_registry.h"

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
  tiers::FeAnnOptions fe_ann;
  fe_ann.fe_de = fe_de;
  fe_ann.distance_threshold = options.fe_ann_distance_threshold;
  fe_ann.spread_threshold = options.fe_ann_spread_threshold;
  fe_ann.pressure_floor_pa = options.fe_ann_pressure_floor_pa;
  fe_ann.fallback_enabled = options.fe_ann_fallback;
  fe_ann.return_after_steps = options.fe_ann_return_after_steps;
  std::shared_ptr<const tiers::SurrogateModelSource> models;
  if (options.models_dir.empty()) {
    models = std::make_shared<tiers::ListedSurrogateModels>(
        std::vector<tiers::SurrogateModelRecord>{});
  } else {
    models = std::make_shared<tiers::SurrogateRegistry>(options.models_dir);
  }
  registry.Register(std::make_unique<tiers::FeAnnTier>(fe_ann, models));
}

}  // namespace gonogo
