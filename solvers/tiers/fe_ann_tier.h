// The "fe-ann" traction tier (seed 000's FE-ANN): the fe-de tier's rig, bins and geostatic start
// (fe_de_tier.h) with every RVE replaced by a registered surrogate ensemble of the soil's RVE
// (solvers/ann/ann_material.h), which falls back to the RVE itself at a point whose input leaves
// what the ensemble was trained on.
//
// Models: a SurrogateModelSource (the service's registry, cache/model_store.h; a directory in
// tests) says which models exist for a soil and fe-de configuration. A request names one
// (TractionRequest::surrogate_model) or gets the source's best for its soil (ResolveChoices
// writes that choice into the request before it is keyed); a soil with no model is a
// PreconditionError naming the command that trains one.
//
// A point starts as its fe-de RVE would (the template settled at the stress of its depth) and,
// when flagged, replays its increments on that RVE (the fallback) and stays on it, or, with
// FeAnnOptions::return_after_steps, returns to the network once back inside. The curve's
// figures (AnnRunReport) say how many points fell back, at which step, and where the time went.
// The deployment sets the guard (FeAnnOptions); a request may set its own over it
// (TractionRequest::surrogate_guard), and the curve's version names the guard that computed it.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "solvers/ann/strain_history.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/tiers/fe_de_tier.h"

namespace gonogo::tiers {

// What the tier needs to know of a registered model.
struct SurrogateModelRecord {
  std::string id;
  std::string directory;  // SurrogateEnsemble::Save's
  // The canonical text (CanonicalText of solvers/common/soil_model.h) of the dem-hertz-mindlin
  // parameter set whose RVE made its training data, and the fe-de configuration whose RVE
  // numerics did: a model answers only for that soil and configuration.
  std::string soil_parameters;
  std::string fe_de_preset;
};

class SurrogateModelSource {
 public:
  virtual ~SurrogateModelSource() = default;
  // The model `id`, or nullopt.
  virtual std::optional<SurrogateModelRecord> Find(const std::string& id) const = 0;
  // The best model for the soil and configuration (the registry: its held-out errors least beyond
  // their RVE's own spread), or nullopt.
  virtual std::optional<SurrogateModelRecord> Best(const std::string& soil_parameters,
                                                   const std::string& fe_de_preset) const = 0;
};

struct FeAnnOptions {
  FeDeOptions fe_de;  // the rig, mesh, procedure and RVE numerics (its preset names them)
  bool fallback_enabled = true;
  // Flag thresholds (surrogate_ensemble.h); 0: the model's own.
  double distance_threshold = 0;
  double spread_threshold = 0;
  // A point whose mean compression is below this is flagged (surrogate_ensemble.h), Pa; 0: no
  // floor.
  double pressure_floor_pa = 0;
  // A fallen-back point returns to the network after this many increments in a row the ensemble
  // would not have flagged (ann_material.h); 0: it stays on its RVE.
  int return_after_steps = 0;
  void Validate(const std::string& field_prefix) const;
};

// One fe-ann curve and its run.
struct AnnRunReport : FeDeRunReport {
  std::string model_id;
  // Fallbacks made, and the step of its point's own history at which each was. A point falls
  // back once; an update its caller discarded counts too (FallbackLog), so this is at least the
  // number of points that fell back.
  int fallbacks = 0;
  std::vector<std::int64_t> fallback_steps;
  FallbackFlagCounts fallbacks_flagged;  // of them, those each of the guard's tests flagged
  std::int64_t unanswered_flags = 0;  // with the fallback off
  double network_seconds = 0;         // the ensemble's batched calls
  std::int64_t network_point_updates = 0;
  // Network answers whose stress was made admissible (SurrogateEnsemble::Admissible: capped at
  // the model's tensile limit or returned onto its cone), trial updates included.
  std::int64_t stress_returns = 0;
  double fallback_seconds = 0;        // replays and points on the RVE
  // Fallen-back points that went back to the network, trial updates included (as fallbacks).
  std::int64_t returns = 0;
  double model_load_seconds = 0;
};

// What an fe-ann run has done so far, at one of the rig's progress reports (a long run's only
// view of where its time goes while it runs: the fallbacks are what makes one long).
struct AnnProgress {
  double fraction = 0;  // of the run's FE steps
  int fallbacks = 0;    // as AnnRunReport's, so far
  FallbackFlagCounts fallbacks_flagged;  // of them, as AnnRunReport's
  std::int64_t returns = 0;
  double network_seconds = 0;
  double fallback_seconds = 0;
};
using AnnProgressReport = std::function<void(const AnnProgress&)>;

// "flagged: distance 12, spread 3[, pressure floor 1]": how many fallbacks each of the guard's
// tests flagged (one may be flagged by several), for progress notes and reports.
std::string FallbackFlagsPhrase(const FallbackFlagCounts& flagged);

class FeAnnTier : public TractionTier {
 public:
  FeAnnTier(FeAnnOptions options, std::shared_ptr<const SurrogateModelSource> models);

  std::string Name() const override { return "fe-ann"; }
  std::string Version() const override;
  std::string VersionFor(const TractionRequest& request) const override;
  bool UsesConeIndex() const override { return false; }
  bool UsesSoilName() const override { return true; }
  TierDescription Describe() const override;
  TierNeeds Needs(const TractionRequest& request) const override;
  void ValidateSoil(const SoilState& soil, const std::string& field) const override;
  void ResolveChoices(TractionRequest& request, const std::string& field_prefix) const override;

  const FeAnnOptions& options() const { return options_; }
  // The tier's options with the request's surrogate guard over them, the thresholds to the 4
  // significant digits the version names; InputError naming field_prefix + "surrogate_guard." +
  // the field for a guard these options cannot keep.
  FeAnnOptions OptionsFor(const TractionRequest& request, const std::string& field_prefix) const;
  // Compute, with the run's figures; the request's model as ResolveChoices leaves it.
  // `on_progress`, when set, is called at each of the rig's progress reports (after
  // context.progress), on the thread that runs the rig. `fallback_paths`, when given, receives
  // each fallen-back point's path on its RVE (ann::AnnMaterial::FallbackPaths: from the settled
  // RVE the point started from, its carried variables recorded), also when the run stops early
  // (cancelled or failed): the paths the model was missing, answered by the RVE itself, which a
  // model fine-tuned on them (gonogo train --from) no longer misses.
  AnnRunReport Run(TractionRequest request, const ComputeContext& context,
                   const AnnProgressReport& on_progress = {},
                   std::vector<ann::StrainHistory>* fallback_paths = nullptr) const;

 protected:
  // Run's curve; with context.keep_training_histories, the run's fallback paths are handed there
  // (serialised), however the run ends.
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override;

 private:
  SurrogateModelRecord Choose(const TractionRequest& request, const std::string& prefix) const;
  std::shared_ptr<const ann::SurrogateEnsemble> Load(const SurrogateModelRecord& record,
                                                     const FeAnnOptions& options) const;

  FeAnnOptions options_;
  FeDeTier fe_de_;
  std::shared_ptr<const SurrogateModelSource> models_;
  mutable std::mutex loaded_mutex_;
  // By id and flag thresholds.
  mutable std::map<std::string, std::shared_ptr<const ann::SurrogateEnsemble>> loaded_;
};

// A SurrogateModelSource over a fixed list (tests, the gonogo-ann command).
class ListedSurrogateModels : public SurrogateModelSource {
 public:
  explicit ListedSurrogateModels(std::vector<SurrogateModelRecord> records)
      : records_(std::move(records)) {}
  std::optional<SurrogateModelRecord> Find(const std::string& id) const override;
  // The first listed for the soil and configuration.
  std::optional<SurrogateModelRecord> Best(const std::string& soil_parameters,
                                           const std::string& fe_de_preset) const override;

 private:
  std::vector<SurrogateModelRecord> records_;
};

}  // namespace gonogo::tiers
