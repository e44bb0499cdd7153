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
};

// Throws InputError naming the option for a bad value.
void RegisterBuiltinTiers(TierRegistry& registry, const BuiltinTierOptions& options = {});

}  // namespace gonogo
