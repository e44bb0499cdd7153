#include "server/fallback_paths.h"

#include <chrono>
#include <cstdio>

#include "cache/dataset_store.h"
#include "solvers/ann/strain_history.h"
#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/soil_catalogue.h"

namespace gonogo::server {

int KeepFallbackPaths(cache::Database& db, const std::string& fe_de_preset,
                      const std::string& rve_version, const CurveTask& task,
                      const TaskResult& result) {
  if (result.training_histories.empty()) return 0;
  const tiers::CatalogueEntry* soil = tiers::BuiltinSoilCatalogue().Find(
      task.request.soil.soil_name, dem::rve::kRveSoilModel);
  if (soil == nullptr) return 0;
  const std::string soil_text = CanonicalText(soil->parameters);
  cache::DatasetStore store(db);
  const int64_t now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  const std::size_t count = result.training_histories.size();
  int stored = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::string& bytes = result.training_histories[k];
    const ann::StrainHistory history = ann::ParseHistory(bytes);
    cache::StoredHistory row;
    row.history_key = "gonogo-fallback-path-v1;curve=" + task.key + ";n=" + std::to_string(k);
    row.dataset = cache::DatasetId(soil->soil, fe_de_preset, soil_text);
    for (const std::string& name : history.internal_variable_names) row.dataset += "+" + name;
    row.soil_name = soil->soil;
    row.soil_parameters = soil_text;
    row.fe_de_preset = fe_de_preset;
    row.rve_version = rve_version;
    row.path_kind = kFallbackPathKind;
    char name[160];
    std::snprintf(name, sizeof name, "fallback %zu of %zu, model %s, %g x %g m wheel at %g N",
                  k + 1, count, task.request.surrogate_model.c_str(), task.request.tyre.diameter_m,
                  task.request.tyre.width_m, task.request.wheel_load_n);
    row.path_name = name;
    row.role = cache::kTrainingRole;
    row.steps = static_cast<int64_t>(history.steps());
    row.history = bytes;
    row.code_version = GONOGO_VERSION;
    row.computed_by = result.computed_by;
    // The curve's seconds shared among its paths (most of an fe-ann run is its fallbacks).
    row.compute_seconds = result.compute_seconds / static_cast<double>(count);
    row.created_unix_ms = now_ms;
    stored += store.Put(row) ? 1 : 0;
  }
  return stored;
}

}  // namespace gonogo::server
