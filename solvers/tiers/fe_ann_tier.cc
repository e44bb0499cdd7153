#include "solvers/tiers/fe_ann_tier.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "solvers/ann/ann_material.h"
#include "solvers/common/errors.h"
#include "solvers/tiers/surrogate_training.h"

namespace gonogo::tiers {

namespace {

constexpr char kTrainHint[] =
    "train and register one with `gonogo train --soil NAME` (a job on the server's pool), or "
    "offline with `gonogo-ann --soil NAME --preset PRESET --register DATA_DIR` "
    "(solvers/ann/README.md)";

// A threshold to the 4 significant digits a version names (VersionOf's %.4g), so that two
// thresholds under one version, and so one cache key, are one threshold.
double ToVersionDigits(double threshold) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", threshold);
  return std::strtod(text, nullptr);
}

// The version of a curve computed with `options`: the fallback and the thresholds change what a
// model answers (the model's id is in the key apart).
std::string VersionOf(const FeAnnOptions& options) {
  std::string version = "fe-ann-3";  // 2: stresses capped at the tensile limit; 3: and the cone
  if (options.fe_de.preset != "default") version += "-" + options.fe_de.preset;
  if (!options.fallback_enabled) version += "-nofallback";
  if (options.distance_threshold > 0 || options.spread_threshold > 0) {
    char text[64];
    std::snprintf(text, sizeof text, "-d%.4g-s%.4g", options.distance_threshold,
                  options.spread_threshold);
    version += text;
  }
  if (options.pressure_floor_pa > 0) {
    char text[32];
    std::snprintf(text, sizeof text, "-p%.4g", options.pressure_floor_pa);
    version += text;
  }
  if (options.return_after_steps > 0) {
    version += "-return" + std::to_string(options.return_after_steps);
  }
  return version;
}

// How many of `fallbacks` each of the guard's tests flagged.
FallbackFlagCounts FlagsOf(const std::vector<ann::FallbackLog::Event>& fallbacks) {
  FallbackFlagCounts flagged;
  for (const ann::FallbackLog::Event& event : fallbacks) {
    flagged.beyond_distance += event.beyond_distance ? 1 : 0;
    flagged.beyond_spread += event.beyond_spread ? 1 : 0;
    flagged.below_pressure_floor += event.below_pressure_floor ? 1 : 0;
  }
  return flagged;
}

// A running curve's fallbacks in words, for its job's progress: "12 points fallen back to their
// RVEs (flagged: distance 12, spread 1), 2 sent back (RVEs 143 s, network 54 s)". The fallbacks
// are what makes an fe-ann curve long, and which test flagged them says which threshold to look at.
std::string ProgressNote(const AnnProgress& progress) {
  char seconds[96];
  std::snprintf(seconds, sizeof seconds, "RVEs %.0f s, network %.0f s", progress.fallback_seconds,
                progress.network_seconds);
  std::string note;
  if (progress.fallbacks == 0) {
    note = "no point fallen back to its RVE";
  } else if (progress.fallbacks == 1) {
    note = "1 point fallen back to its RVE";
  } else {
    note = std::to_string(progress.fallbacks) + " points fallen back to their RVEs";
  }
  if (progress.fallbacks > 0) {
    note += " (" + FallbackFlagsPhrase(progress.fallbacks_flagged) + ")";
  }
  if (progress.returns > 0) note += ", " + std::to_string(progress.returns) + " sent back";
  return note + " (" + seconds + ")";
}

}  // namespace

std::string FallbackFlagsPhrase(const FallbackFlagCounts& flagged) {
  std::string phrase = "flagged: distance " + std::to_string(flagged.beyond_distance) +
                       ", spread " + std::to_string(flagged.beyond_spread);
  if (flagged.below_pressure_floor > 0) {
    phrase += ", pressure floor " + std::to_string(flagged.below_pressure_floor);
  }
  return phrase;
}

void FeAnnOptions::Validate(const std::string& p) const {
  fe_de.Validate(p + "fe_de.");
  Require(std::isfinite(distance_threshold) && distance_threshold >= 0, p + "distance_threshold",
          "must be >= 0 (0: the model's own)");
  Require(std::isfinite(spread_threshold) && spread_threshold >= 0, p + "spread_threshold",
          "must be >= 0 (0: the model's own)");
  Require(std::isfinite(pressure_floor_pa) && pressure_floor_pa >= 0, p + "pressure_floor_pa",
          "must be >= 0 Pa (0: no floor)");
  Require(return_after_steps >= 0, p + "return_after_steps", "must be >= 0 (0: never)");
  Require(return_after_steps == 0 || fallback_enabled, p + "return_after_steps",
          "a point returns from its fallback, which is off");
}

FeAnnTier::FeAnnTier(FeAnnOptions options, std::shared_ptr<const SurrogateModelSource> models)
    : options_(std::move(options)), fe_de_(options_.fe_de), models_(std::move(models)) {
  options_.Validate("fe_ann.");
  if (models_ == nullptr) throw InputError("fe_ann.models", "a model source is required");
}

std::string FeAnnTier::Version() const { return VersionOf(options_); }

std::string FeAnnTier::VersionFor(const TractionRequest& request) const {
  return VersionOf(OptionsFor(request, ""));
}

FeAnnOptions FeAnnTier::OptionsFor(const TractionRequest& request,
                                   const std::string& prefix) const {
  const SurrogateGuard& guard = request.surrogate_guard;
  guard.Validate(prefix + "surrogate_guard.");
  FeAnnOptions options = options_;
  if (guard.distance_threshold) options.distance_threshold = *guard.distance_threshold;
  if (guard.spread_threshold) options.spread_threshold = *guard.spread_threshold;
  if (guard.pressure_floor_pa) options.pressure_floor_pa = *guard.pressure_floor_pa;
  if (guard.fallback_enabled) options.fallback_enabled = *guard.fallback_enabled;
  // A request that turns the fallback off has nothing to return from.
  if (!options.fallback_enabled && !guard.return_after_steps) options.return_after_steps = 0;
  if (guard.return_after_steps) options.return_after_steps = *guard.return_after_steps;
  options.distance_threshold = ToVersionDigits(options.distance_threshold);
  options.spread_threshold = ToVersionDigits(options.spread_threshold);
  options.pressure_floor_pa = ToVersionDigits(options.pressure_floor_pa);
  Require(options.return_after_steps == 0 || options.fallback_enabled,
          prefix + "surrogate_guard.return_after_steps",
          "a point returns from its fallback, which this server turns off (gonogo-server "
          "--fe-ann-no-fallback); set surrogate_guard.fallback_enabled too");
  return options;
}

TierDescription FeAnnTier::Describe() const {
  return {"the fe-de rig and soil bin with a neural surrogate of the soil's RVE (an ensemble of "
          "networks, libtorch) at every integration point, falling back to the RVE where an input "
          "leaves the training envelope (" + options_.fe_de.preset + " configuration)",
          "soil name (dem-hertz-mindlin catalogue rows) or parameters, with a registered "
          "surrogate model for them; tyre diameter and width; wheel load",
          "seconds to minutes on one core (more where points fall back)",
          {"dem-hertz-mindlin"}};
}

TierNeeds FeAnnTier::Needs(const TractionRequest& /*request*/) const {
  TierNeeds needs;
  needs.ranks = 1;
  needs.threads = options_.fe_de.threads;
  needs.expected_seconds = options_.fe_de.preset == "default" ? 600 : 20;
  return needs;
}

void FeAnnTier::ValidateSoil(const SoilState& soil, const std::string& field) const {
  fe_de_.ValidateSoil(soil, field);
}

SurrogateModelRecord FeAnnTier::Choose(const TractionRequest& request,
                                       const std::string& prefix) const {
  const std::string soil =
      CanonicalText(fe_de_.ResolveSoil(request.soil, prefix + "soil"));
  const std::string& preset = options_.fe_de.preset;
  if (!request.surrogate_model.empty()) {
    const std::optional<SurrogateModelRecord> named = models_->Find(request.surrogate_model);
    Require(named.has_value(), prefix + "surrogate_model",
            "no registered model '" + request.surrogate_model + "' (gonogo models lists them)");
    Require(named->soil_parameters == soil, prefix + "surrogate_model",
            "model '" + named->id + "' was trained on another soil");
    Require(named->fe_de_preset == preset, prefix + "surrogate_model",
            "model '" + named->id + "' was trained on RVEs of the " + named->fe_de_preset +
                " configuration; this server runs " + preset);
    return *named;
  }
  const std::optional<SurrogateModelRecord> best = models_->Best(soil, preset);
  if (!best) {
    throw PreconditionError(prefix + "surrogate_model",
                            "no surrogate model is registered for this soil at the " + preset +
                                " configuration; " + kTrainHint);
  }
  return *best;
}

void FeAnnTier::ResolveChoices(TractionRequest& request, const std::string& prefix) const {
  request.surrogate_model = Choose(request, prefix).id;
  if (request.surrogate_guard.Empty()) return;
  // Whole, so that the request says what computes it wherever it goes (a worker rank).
  const FeAnnOptions options = OptionsFor(request, prefix);
  request.surrogate_guard.distance_threshold = options.distance_threshold;
  request.surrogate_guard.spread_threshold = options.spread_threshold;
  request.surrogate_guard.pressure_floor_pa = options.pressure_floor_pa;
  request.surrogate_guard.fallback_enabled = options.fallback_enabled;
  request.surrogate_guard.return_after_steps = options.return_after_steps;
}

std::shared_ptr<const ann::SurrogateEnsemble> FeAnnTier::Load(
    const SurrogateModelRecord& record, const FeAnnOptions& options) const {
  char thresholds[96];
  std::snprintf(thresholds, sizeof thresholds, "|%.17g|%.17g|%.17g", options.distance_threshold,
                options.spread_threshold, options.pressure_floor_pa);
  const std::string name = record.id + thresholds;
  std::lock_guard<std::mutex> lock(loaded_mutex_);
  auto it = loaded_.find(name);
  if (it != loaded_.end()) return it->second;
  auto ensemble =
      std::make_shared<ann::SurrogateEnsemble>(ann::SurrogateEnsemble::Load(record.directory));
  if (options.distance_threshold > 0 || options.spread_threshold > 0) {
    ensemble->SetThresholds(options.distance_threshold > 0 ? options.distance_threshold
                                                           : ensemble->distance_threshold(),
                            options.spread_threshold > 0 ? options.spread_threshold
                                                         : ensemble->spread_threshold());
  }
  if (options.pressure_floor_pa > 0) ensemble->SetPressureFloor(options.pressure_floor_pa);
  loaded_[name] = ensemble;
  return ensemble;
}

AnnRunReport FeAnnTier::Run(TractionRequest request, const ComputeContext& context,
                             const AnnProgressReport& on_progress,
                             std::vector<ann::StrainHistory>* fallback_paths) const {
  request.Validate();
  const SurrogateModelRecord record = Choose(request, "");
  const FeAnnOptions options = OptionsFor(request, "");
  const auto load_start = std::chrono::steady_clock::now();
  const std::shared_ptr<const ann::SurrogateEnsemble> ensemble = Load(record, options);
  const double load_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - load_start).count();

  ann::AnnMaterialOptions material_options;
  material_options.fallback_enabled = options.fallback_enabled;
  material_options.return_after_steps = options.return_after_steps;
  // What a model carrying internal variables takes from a point's settled RVE.
  material_options.internal_variables = RveFabricVariables();
  material_options.record_fallback_paths = fallback_paths != nullptr;
  std::shared_ptr<const ann::AnnMaterial> material;
  const PointStandInFactory make_stand_in =
      [&](std::shared_ptr<const dem::rve::RveMaterial> template_rve) {
        material = std::make_shared<const ann::AnnMaterial>(ensemble, template_rve,
                                                            material_options);
        PointStandIn stand_in;
        stand_in.model = material;
        stand_in.state_from_rve = [material](const std::string& settled_rve_bytes) {
          return material->StateFrom(settled_rve_bytes)->Serialize();
        };
        return stand_in;
      };
  ComputeContext alone = context;
  alone.communicator = MPI_COMM_NULL;
  if (on_progress || context.progress_note) {
    alone.progress = [&material, &on_progress, outer = context.progress,
                      note = context.progress_note](double fraction) {
      AnnProgress progress;
      progress.fraction = fraction;
      if (material) {
        const ann::FallbackLog& log = material->log();
        const std::vector<ann::FallbackLog::Event> fallbacks = log.fallbacks();
        progress.fallbacks = static_cast<int>(fallbacks.size());
        progress.fallbacks_flagged = FlagsOf(fallbacks);
        progress.returns = log.returns();
        progress.network_seconds = log.network_seconds();
        progress.fallback_seconds = log.fallback_seconds();
      }
      if (note) note(ProgressNote(progress));
      if (outer) outer(fraction);
      if (on_progress) on_progress(progress);
    };
  }
  AnnRunReport report;
  try {
    static_cast<FeDeRunReport&>(report) = fe_de_.RunWithStandIn(request, make_stand_in, alone);
  } catch (...) {
    // A run stopped early keeps the paths its fallbacks paid for.
    if (fallback_paths && material) *fallback_paths = material->FallbackPaths();
    throw;
  }
  if (fallback_paths && material) *fallback_paths = material->FallbackPaths();
  report.curve.tier = Name();
  report.curve.tier_version = VersionOf(options);
  report.model_id = record.id;
  report.model_load_seconds = load_seconds;
  if (material) {
    const ann::FallbackLog& log = material->log();
    const std::vector<ann::FallbackLog::Event> fallbacks = log.fallbacks();
    for (const ann::FallbackLog::Event& event : fallbacks) {
      report.fallback_steps.push_back(event.point_step);
    }
    report.fallbacks_flagged = FlagsOf(fallbacks);
    report.fallbacks = static_cast<int>(report.fallback_steps.size());
    report.unanswered_flags = log.unanswered_flags();
    report.network_seconds = log.network_seconds();
    report.network_point_updates = log.network_point_updates();
    report.stress_returns = log.stress_returns();
    report.fallback_seconds = log.fallback_seconds();
    report.returns = log.returns();
  }
  SurrogateRun& run = report.curve.surrogate_run.emplace();
  run.fe_steps = report.fe_steps;
  run.fallbacks = report.fallbacks;
  run.fallback_point_steps = report.fallback_steps;
  run.fallbacks_flagged = report.fallbacks_flagged;
  run.returns = report.returns;
  run.unanswered_flags = report.unanswered_flags;
  run.fallback_paths_kept = fallback_paths ? static_cast<int>(fallback_paths->size()) : 0;
  run.network_point_updates = report.network_point_updates;
  run.network_seconds = report.network_seconds;
  run.fallback_seconds = report.fallback_seconds;
  return report;
}

TractionCurve FeAnnTier::ComputeCurve(const TractionRequest& request,
                                      const ComputeContext& context) const {
  int group_rank = 0;
  if (context.communicator != MPI_COMM_NULL) MPI_Comm_rank(context.communicator, &group_rank);
  if (group_rank != 0) return {};  // one rank computes; a group's others have nothing to do
  if (!context.keep_training_histories) return Run(request, context).curve;
  // The fallen-back points' paths go to the sink however the run ends: they were paid for.
  std::vector<ann::StrainHistory> fallback_paths;
  const auto hand_on = [&] {
    std::vector<std::string> bytes;
    for (const ann::StrainHistory& path : fallback_paths) {
      bytes.push_back(ann::SerializeHistory(path));
    }
    context.keep_training_histories(std::move(bytes));
  };
  try {
    TractionCurve curve = Run(request, context, {}, &fallback_paths).curve;
    hand_on();
    return curve;
  } catch (...) {
    hand_on();
    throw;
  }
}

std::optional<SurrogateModelRecord> ListedSurrogateModels::Find(const std::string& id) const {
  for (const SurrogateModelRecord& record : records_) {
    if (record.id == id) return record;
  }
  return std::nullopt;
}

std::optional<SurrogateModelRecord> ListedSurrogateModels::Best(
    const std::string& soil_parameters, const std::string& fe_de_preset) const {
  for (const SurrogateModelRecord& record : records_) {
    if (record.soil_parameters == soil_parameters && record.fe_de_preset == fe_de_preset) {
      return record;
    }
  }
  return std::nullopt;
}

}  // namespace gonogo::tiers
