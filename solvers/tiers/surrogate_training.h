// Training a surrogate ensemble (solvers/ann) on a soil's own DE RVE, the recipe the fe-ann tier's
// models are made with: laboratory paths (solvers/ann/lab_paths.h) on the RVE of a dem-hertz-mindlin
// soil at the RVE numerics of an fe-de configuration, a training set and a held-out set, an
// ensemble trained on the first and measured on the second.
//
// Training set: drained triaxials and simple shears at each of `pressures_pa`, unload-reload and
// isotropic paths at the second and last of them, and `walks` seeded random walks at pressures
// cycling through them (within +-max_walk_strain). Held-out set: a triaxial, a simple shear and an
// unload-reload at pressures between the training ones, and a walk of another seed.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/common/soil_model.h"
#include "solvers/tiers/fe_de_tier.h"

namespace gonogo::tiers {

struct NamedLabPath {
  std::string name;  // "triaxial 15 kPa"
  ann::LabPathSpec spec;
};

struct SurrogateRecipe {
  int steps = 50;  // per path, after settling
  int walks = 16;
  // Held-out random walks (seeds 1001, 1002, ...), at pressures between the training ones: the
  // walk is the held-out path a network finds hardest, and one walk is one sample of it.
  int held_out_walks = 4;
  // Confining pressures of the training paths, Pa: they span the stresses of an fe-de bin under a
  // wheel (its surface layer starts at FeDeOptions::min_initial_pressure_pa, 2 kPa).
  std::vector<double> pressures_pa = {2.5e3, 5e3, 10e3, 20e3, 40e3, 80e3};
  double max_walk_strain = 0.01;
  // Rotated copies of every training history (ann::WithRotatedCopies): the paths in frames other
  // than the laboratory's, which an FE point under a wheel meets. 0: none. On the fe-ann tier's
  // test rig 3 copies took the fallbacks from 3 to 0 but the curve from 3.9 to 7.2 % of W off
  // fe-de's (solvers/ann/README.md), so the default is none.
  int rotated_copies = 0;
  ann::MlpArchitecture architecture;
  int members = 3;
  ann::TrainingOptions training;  // epochs 300, batches of 64 unless set
  int threads = 1;                // OpenMP threads running the paths
  // Paths recorded at the points of an fe-de rig run (RecordRigPaths; seed 000's step 2), added to
  // the training set and to the held-out set ("rig point k").
  std::vector<ann::StrainHistory> rig_training;
  std::vector<ann::StrainHistory> rig_held_out;
  // > 0: the random walks' share of the training loss, in [0, 0.99] (WalkShareWeights); 0: their
  // share of the steps. Not with rotated copies or with training.history_weights of its own.
  double walk_share = 0;
  SurrogateRecipe();
  void Validate(const std::string& field_prefix) const;
  // Validate, its InputError naming the command-line option that sets the field where one does
  // (the options gonogo-ann and gonogo-bench-fe-ann share: --steps, --walks, --pressures-kpa,
  // --walk-share, ...), so that a user reads the option they gave rather than the recipe's field.
  void ValidateAsOptions() const;
};

std::vector<NamedLabPath> TrainingPaths(const SurrogateRecipe& recipe);

// Loss weights (ann::TrainingOptions::history_weights) for `histories`, whose first ones are the
// histories of `training_paths` in order (a path that stopped early is shorter) and the rest any
// others (the rig's recorded paths): every walk's steps weigh w and every other step 1, with w such
// that the walks carry `walk_share` of the loss,
//   w walk_steps / (w walk_steps + other_steps) = walk_share.
// Without walks or without other steps every weight is 1.
std::vector<double> WalkShareWeights(const std::vector<NamedLabPath>& training_paths,
                                     const std::vector<ann::StrainHistory>& histories,
                                     double walk_share);
std::vector<NamedLabPath> HeldOutPaths(const SurrogateRecipe& recipe);

// Runs `paths` on `model` on `threads` OpenMP threads; `progress` (if set) is called with the
// number of paths done after each. `internal` (if set) is recorded at every step.
std::vector<ann::StrainHistory> RunLabPaths(const material::ConstitutiveModel& model,
                                            const std::vector<NamedLabPath>& paths, int threads,
                                            const std::function<void(int done)>& progress = {},
                                            const ann::InternalVariables& internal = {});

// What a history can record of a DE RVE's state beside its stress (dem::rve::RveSnapshot):
// coordination_number, solid_fraction and the contact fabric fabric_xx ... fabric_xy (Voigt
// order, tensor components; trace 1). The recipe's histories record only what its network
// carries (RveVariables below), so the data hashes of a network that carries nothing do not
// depend on this.
ann::InternalVariables RveFabricVariables();
// The reader of RveFabricVariables narrowed to `names` (in that order); throws
// InputError(field, ...) for a name it does not read.
ann::InternalVariables RveVariables(const std::vector<std::string>& names, const std::string& field);

// The same held-out path on another packing of the soil's RVE: its difference from the training
// packing's (ann::HistoryDifference), the floor under a surrogate's replay error on that path.
struct PackingDifference {
  unsigned packing_seed = 0;  // RveNumerics::seed
  double difference = 0;      // a fraction
};

struct HeldOutResult {
  std::string path;
  double replay_error = 0;  // ReplayError: mean |sigma error| / mean |sigma|
  std::vector<PackingDifference> packings;  // empty: not measured
};

// The floor under a held-out error: the median of the path's differences on other packings (what
// a typical other packing of the same soil is off by), 0 when none was measured. The median, not
// the furthest: the furthest grows with every packing run (the walk at 3.5 kPa of the tiny RVE:
// 12.8 % over packings 2-4, 27.2 % over 2-17, where the median is 15.1 %; solvers/ann/README.md,
// "The RVE's own spread").
double PackingFloor(const std::vector<PackingDifference>& packings);

struct TrainedSurrogate {
  ann::SurrogateEnsemble ensemble;
  std::vector<ann::StrainHistory> training;
  std::vector<ann::StrainHistory> held_out;
  std::vector<HeldOutResult> held_out_errors;
  double worst_held_out_error = 0;
  std::int64_t samples = 0;      // training steps
  double generation_seconds = 0;  // running the paths
  double training_seconds = 0;
  // FNV-1a of the training histories' blobs (strain_history.h), hex: what data made the model.
  std::string data_hash;
};

// The paths the points of an fe-de rig run take (seed 000's step 2): `fe_de`'s run of `request`,
// alone, every RVE recorded (solvers/ann/path_recorder.h). The run is the fe-de run: its curve is
// the tier's, bit for bit.
struct RecordedRigRun {
  FeDeRunReport run;
  std::vector<ann::StrainHistory> paths;  // one per point of the wheel's bin
};
RecordedRigRun RecordRigPaths(const FeDeTier& fe_de, const TractionRequest& request,
                              const ComputeContext& context = {},
                              const ann::InternalVariables& internal = {});

// A recorded point's path (a rig point's, RecordRigPaths) taken again by a fresh point of `rve`:
// its template settled isotropically at the path's initial mean stress, as the fe-de bin settles
// each point at the stress of its depth (FeDeOptions::min_initial_pressure_pa), then the path's
// displacement-gradient increments, one update each, recorded as RecordRigPaths records (with
// `internal`). On another packing of the same soil (RveNumerics::seed), its difference from the
// path (ann::HistoryDifference) is that path's floor, as a laboratory path's is. The replay stops
// at the first increment the RVE refuses (stopped_reason). Throws InputError("path", ...) for a
// path without steps or whose initial mean stress is not compressive.
ann::StrainHistory ReplayedOnRve(std::shared_ptr<const dem::rve::RveMaterial> rve,
                                 const ann::StrainHistory& path,
                                 const ann::InternalVariables& internal = {});

// A recorded point's path answered as the fe-ann tier answers its point (fe_ann_tier.h): by an
// ann::AnnMaterial of `ensemble` with `rve` as its fallback, the point started where
// ReplayedOnRve starts it (the template settled isotropically at the path's initial mean stress,
// StateFrom), then the path's increments, one update each. Where the ensemble flags an increment
// the point falls back: the RVE replays its increments from that start and answers from then on
// (until `return_after_steps` unflagged increments in a row bring it back, when > 0). The open-loop
// replay (ann::Replay) answers every step by the network, flagged or not; this is what a curve's
// point gets. Stops at the first increment the material refuses (stopped_reason).
struct GuardedReplay {
  std::vector<ann::Vector6> stresses_pa;  // after each step taken
  double error = 0;                       // ann::ReplayError against the path
  std::int64_t first_fallback_step = -1;  // increments taken before the first fallback; -1: none
  int fallbacks = 0;
  std::int64_t returns = 0;
  std::string stopped_reason;
};
GuardedReplay ReplayGuarded(const ann::SurrogateEnsemble& ensemble,
                            std::shared_ptr<const dem::rve::RveMaterial> rve,
                            const ann::StrainHistory& path, int return_after_steps = 0);

// The largest differences between two curves of the same request over their common slips: drawbar
// pull over the wheel load W, torque over r W, sinkage over r (r = d / 2): the measures of
// fe-ann against fe-de.
struct CurveDifference {
  double drawbar_pull_over_w = 0;
  double torque_over_rw = 0;
  double sinkage_over_r = 0;
};
CurveDifference WorstDifference(const TractionCurve& a, const TractionCurve& b,
                                const TractionRequest& request);

// FNV-1a (64 bit, hex) of the histories' blobs (strain_history.h): which data made a model.
std::string HistoriesHash(const std::vector<ann::StrainHistory>& histories);

// `count` of `paths`, evenly spread over them from index `offset` (every size / count-th).
std::vector<ann::StrainHistory> EvenlySpread(const std::vector<ann::StrainHistory>& paths,
                                             int count, int offset = 0);
// The indices EvenlySpread picks among `size` paths.
std::vector<std::size_t> EvenlySpreadIndices(std::size_t size, int count, int offset = 0);

// Where the held-out rig paths start among a rig run's `paths` recorded points when
// `training_points` of them train (EvenlySpread from 0): half a training stride on, and one more,
// so that each held-out path lies between two training ones.
int RigHeldOutOffset(int paths, int training_points);

// The recipe on `soil`'s RVE at the RVE numerics of `fe_de`. `stage` (if set) hears "paths",
// "training" and each done fraction.
TrainedSurrogate TrainSurrogateOnRve(
    const SoilParameters& soil, const FeDeOptions& fe_de, const SurrogateRecipe& recipe,
    const std::function<void(const std::string& stage, double fraction)>& stage = {});

}  // namespace gonogo::tiers
