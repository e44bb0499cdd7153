// The registry of the fe-ann tier's surrogate models, in the service's data directory:
// <root>/<id>/ holds one ensemble (SurrogateEnsemble::Save: member_<k>.pt, envelope.bin) and its
// record, model.txt, with its provenance: the soil it was trained for, the fe-de configuration whose
// RVE numerics made its data, the architecture, the hash and size of the training data, the
// envelope's thresholds, the held-out errors, the training time, the model it was fine-tuned from,
// when and by which code. A directory is the registry because every rank of the pool reads it (as
// the fe-de checkpoints: a file system the ranks share), with no database connection per rank.
//
// Registration is atomic: the files are written to a hidden directory that is then renamed to
// <root>/<id>; an id is never reused. Hidden directories left by a crash are not models and are
// removed by CollectAbandoned.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/tiers/fe_ann_tier.h"
#include "solvers/tiers/surrogate_training.h"

namespace gonogo::tiers {

struct RegisteredSurrogate : SurrogateModelRecord {
  std::string soil_name;  // the catalogue name it was trained for ("" for explicit parameters)
  std::string architecture;
  int members = 0;
  std::string data_hash;
  std::int64_t samples = 0;
  // Of those, the fe-ann curves' fallback paths it was trained on (gonogo train
  // --fallback-paths-share) and the share of the loss they carried; 0 for a record made before.
  int fallback_paths = 0;
  double fallback_paths_share = 0;
  // The share of the recipe paths' loss its random walks carried (SurrogateRecipe::walk_share); 0:
  // their share of the steps, and for a record made before it was kept.
  double walk_share = 0;
  double distance_threshold = 0;
  double spread_threshold = 0;
  // SurrogateEnsemble::Admissible's cap (Pa); infinite for a record made before it existed.
  double tensile_limit_pa = std::numeric_limits<double>::infinity();
  double least_principal_ratio = 0;  // its cone; 0 (none) for a record made before it existed
  std::vector<HeldOutResult> held_out;
  double worst_held_out_error = 0;
  double training_seconds = 0;
  // How its members were trained (TrainingText); "" for a record made before it was kept.
  std::string training;
  std::string from_model;  // "" unless fine-tuned
  std::string code_version;
  std::int64_t created_unix_ms = 0;
};

// How a model's members were trained, for its record: "epochs=300 batch_size=64
// learning_rate=0.003 seed=1 path_stress_weighting=0 rollout_steps=0 weighted_histories=0", with
// rollout_weight after rollout_steps when the term is on, stress_noise and noise_correction
// after them when there is training noise. Member k was trained with seed + k;
// weighted_histories counts the training histories whose weight in the loss is not 1
// (TrainingOptions::history_weights). What the network is (anchoring, pressure scaling, carried
// variables) is its architecture's name.
std::string TrainingText(const ann::TrainingOptions& options);

// How far a model's held-out errors lie beyond its RVE's own spread: over the held-out paths, the
// largest of (error - the path's PackingFloor, the median of its differences on other packings of
// the RVE), at least 0; a path not run on other packings counts whole. A model whose every path is
// within its floor scores 0: the held-out set cannot tell it from its RVE. A record without
// held-out paths: its worst error.
double WorstErrorBeyondFloor(const RegisteredSurrogate& model);

class SurrogateRegistry : public SurrogateModelSource {
 public:
  explicit SurrogateRegistry(std::string root);

  std::optional<SurrogateModelRecord> Find(const std::string& id) const override;
  // The smallest WorstErrorBeyondFloor, then the smallest worst held-out error, then the newest.
  std::optional<SurrogateModelRecord> Best(const std::string& soil_parameters,
                                           const std::string& fe_de_preset) const override;
  std::optional<RegisteredSurrogate> Describe(const std::string& id) const;
  // Every model, newest first; `soil_name` non-empty: that soil's.
  std::vector<RegisteredSurrogate> List(const std::string& soil_name = "") const;

  // Writes `ensemble` and `record` (its directory set here) as model record.id. Throws
  // InputError("model.id", ...) for a malformed or taken id.
  RegisteredSurrogate Register(RegisteredSurrogate record,
                               const ann::SurrogateEnsemble& ensemble) const;
  // A fresh id for a model of `soil_name` and `architecture`: "<soil>-<architecture>-<n>", the
  // architecture in its short form where the whole would make the id longer than 56 characters
  // before "-<n>" ("mlp-128x128-anchored-ps3000pa-cn": no "-tanh", "pressure-scaled-" as "ps", the
  // carried variables by their initials), and cut after a whole word if even that is.
  std::string NewId(const std::string& soil_name, const std::string& architecture) const;
  // Removes what a crash mid-registration left; returns how many.
  int CollectAbandoned() const;

  const std::string& root() const { return root_; }

 private:
  std::string root_;
};

// Throws InputError(field, ...) unless `id` is 1-64 letters, digits, '-', '_' and '.', not
// starting with '.'.
void ValidateModelId(const std::string& id, const std::string& field);

}  // namespace gonogo::tiers
