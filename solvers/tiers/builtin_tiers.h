// Every traction tier gonogo ships, registered in one place.
#pragma once

#include <string>

#include "solvers/common/tier.h"

namespace gonogo {

// What a deployment chooses about the built-in tiers (server flags).
struct BuiltinTierOptions {
  std::string fe_de_preset = "default";  // tiers::FeDeOptions::Preset
  int fe_de_ranks = 2;                   // MPI ranks of one fe-de task (--ranks-per-task)
  int fe_de_threads = 1;                 // OpenMP threads per rank of an fe-de task
  double fe_de_checkpoint_every_s = 60;  // wall seconds between an fe-de task's checkpoints
  // The fe-ann tier's model registry (surrogate_registry.h: <data dir>/models); empty: no models
  // (every fe-ann request is then refused with the command that trains one).
  std::string models_dir;
  // The fe-ann tier's guard (fe_ann_tier.h FeAnnOptions): thresholds that flag a point (0: each
  // model's own) and whether a flagged point falls back to its RVE. Part of the tier's version,
  // so curves computed otherwise are cached apart.
  double fe_ann_distance_threshold = 0;
  double fe_ann_spread_threshold = 0;
  double fe_ann_pressure_floor_pa = 0;  // mean compression below which a point is flagged; 0: none
  bool fe_ann_fallback = true;
  int fe_ann_return_after_steps = 0;  // 0: a fallen-back point stays on its RVE
};

// Throws InputError naming the option for a bad value.
void RegisterBuiltinTiers(TierRegistry& registry, const BuiltinTierOptions& options = {});

}  // namespace gonogo
