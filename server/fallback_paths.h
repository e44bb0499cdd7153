// The fe-ann tier's fallback paths kept as training data: where a curve's points left the
// surrogate's envelope, their RVEs answered them (solvers/ann/ann_material.h), and those paths,
// from each point's settled RVE to its last step on it, are what the model was missing. A curve
// task hands them on (TaskResult::training_histories); they are stored, the moment the task ends,
// in the soil's dataset (cache/dataset_store.h) as histories of kind "fallback" and role
// training, keyed by the curve's cache key and their place in its run, with the model and the
// curve in their name. `gonogo train --fallback-paths-share F` trains on them beside the recipe's
// paths (server/train_job.cc).
#pragma once

#include <string>

#include "cache/database.h"
#include "server/curve_resolver.h"

namespace gonogo::server {

inline constexpr char kFallbackPathKind[] = "fallback";

// Stores `result.training_histories` of the curve `task` (computed by `tier`) in the dataset of
// its soil at the configuration `fe_de_preset` whose RVE code is `rve_version`; the dataset is the
// one the histories' recorded variables name ("+coordination_number"). A history whose key is
// stored already stays as it is. Returns how many were stored. A request whose soil is not a
// catalogue soil of the RVE keeps nothing (no dataset to train from is named by it).
int KeepFallbackPaths(cache::Database& db, const std::string& fe_de_preset,
                      const std::string& rve_version, const CurveTask& task,
                      const TaskResult& result);

}  // namespace gonogo::server
