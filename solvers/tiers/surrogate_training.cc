#include "solvers/tiers/surrogate_training.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "solvers/ann/ann_material.h"
#include "solvers/ann/path_recorder.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/material/kinematics.h"

namespace gonogo::tiers {

namespace {

ann::LabPathSpec Spec(ann::LabPath path, double pressure_pa, double max_strain, int steps,
                      std::uint64_t seed = 1) {
  ann::LabPathSpec spec;
  spec.path = path;
  spec.pressure_pa = pressure_pa;
  spec.max_strain = max_strain;
  spec.steps = steps;
  spec.seed = seed;
  spec.walk_step_strain = 1e-3;
  return spec;
}

std::string Kpa(double pressure_pa) {
  char text[32];
  std::snprintf(text, sizeof text, " %g kPa", pressure_pa / 1e3);
  return text;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The bytes of `rve`'s template settled isotropically at `path`'s initial mean stress, where a
// replay of the path starts (as the fe-de bin settles a point at the stress of its depth). Throws
// InputError("path", ...) for a path without steps or whose initial mean stress is not compressive.
std::string SettledAtPathStart(const dem::rve::RveMaterial& rve, const ann::StrainHistory& path) {
  Require(path.steps() > 0, "path", "has no steps to replay");
  const double initial_mean_pa = -path.initial_stress_pa.trace() / 3;  // tension positive
  Require(initial_mean_pa > 0, "path", "starts from a mean stress that is not compressive");
  dem::rve::Rve settled = rve.initial();
  settled.SettleIsotropic(initial_mean_pa);
  return settled.Save();
}

}  // namespace

SurrogateRecipe::SurrogateRecipe() {
  training.epochs = 300;
  training.batch_size = 64;
}

void SurrogateRecipe::Validate(const std::string& p) const {
  Require(steps >= 2 && steps <= 100000, p + "steps", "must lie in [2, 100000]");
  Require(walks >= 0 && walks <= 10000, p + "walks", "must lie in [0, 10000]");
  Require(held_out_walks >= 0 && held_out_walks <= 1000, p + "held_out_walks",
          "must lie in [0, 1000]");
  Require(pressures_pa.size() >= 2 && pressures_pa.size() <= 64, p + "pressures_pa",
          "must hold 2 to 64 pressures");
  for (double pressure : pressures_pa) {
    Require(std::isfinite(pressure) && pressure > 0 && pressure <= 1e9, p + "pressures_pa",
            "each must be a positive pressure, at most 1 GPa");
  }
  Require(std::is_sorted(pressures_pa.begin(), pressures_pa.end()), p + "pressures_pa",
          "must be in increasing order");
  Require(std::isfinite(max_walk_strain) && max_walk_strain > 0 && max_walk_strain <= 0.2,
          p + "max_walk_strain", "must lie in (0, 0.2]");
  architecture.Validate(p + "architecture.");
  Require(members >= 3 && members <= 64, p + "members", "must lie in [3, 64]");
  training.Validate(p + "training.");
  Require(threads >= 1 && threads <= 1024, p + "threads", "must lie in [1, 1024]");
  Require(rotated_copies >= 0 && rotated_copies <= 64, p + "rotated_copies",
          "must lie in [0, 64]");
  Require(std::isfinite(walk_share) && walk_share >= 0 && walk_share <= 0.99, p + "walk_share",
          "must lie in [0, 0.99]");
  Require(walk_share == 0 || rotated_copies == 0, p + "walk_share",
          "weighs the walks of the laboratory's frame only: not with rotated copies");
  Require(walk_share == 0 || training.history_weights.empty(), p + "walk_share",
          "sets the histories' weights itself: not with training.history_weights");
}

void SurrogateRecipe::ValidateAsOptions() const {
  // The option of each field one sets; a field no option sets keeps its own name.
  static const std::map<std::string, std::string> kOptionOfField = {
      {"steps", "--steps"},
      {"walks", "--walks"},
      {"held_out_walks", "--held-out-walks"},
      {"pressures_pa", "--pressures-kpa"},
      {"threads", "--threads"},
      {"rotated_copies", "--rotated-copies"},
      {"walk_share", "--walk-share"},
      {"architecture.hidden_widths", "--architecture"},
      {"architecture.carried_variables", "--carry"},
      {"architecture.pressure_reference_pa", "--pressure-scaled"},
      {"training.epochs", "--epochs"}};
  try {
    Validate("");
  } catch (const InputError& e) {
    const auto option = kOptionOfField.find(e.field());
    if (option == kOptionOfField.end()) throw;
    throw InputError(option->second, std::string(e.what()).substr(e.field().size() + 2));
  }
}

std::vector<double> WalkShareWeights(const std::vector<NamedLabPath>& training_paths,
                                     const std::vector<ann::StrainHistory>& histories,
                                     double walk_share) {
  std::vector<bool> is_walk;
  double walk_steps = 0, other_steps = 0;
  for (std::size_t k = 0; k < histories.size(); ++k) {
    is_walk.push_back(k < training_paths.size() &&
                      training_paths[k].spec.path == ann::LabPath::kRandomWalk);
    (is_walk.back() ? walk_steps : other_steps) += static_cast<double>(histories[k].steps());
  }
  const double walk_weight = walk_steps > 0 && other_steps > 0
                                 ? walk_share * other_steps / ((1 - walk_share) * walk_steps)
                                 : 1;
  std::vector<double> weights;
  for (bool walk : is_walk) weights.push_back(walk ? walk_weight : 1.0);
  return weights;
}

std::vector<NamedLabPath> TrainingPaths(const SurrogateRecipe& recipe) {
  using ann::LabPath;
  const int n = recipe.steps;
  std::vector<NamedLabPath> paths;
  for (double p : recipe.pressures_pa) {
    paths.push_back({"triaxial" + Kpa(p), Spec(LabPath::kTriaxial, p, 0.05, n)});
    paths.push_back({"simple-shear" + Kpa(p), Spec(LabPath::kSimpleShear, p, 0.1, n)});
  }
  const double second = recipe.pressures_pa[1], last = recipe.pressures_pa.back();
  for (double p : {second, last}) {
    paths.push_back({"unload-reload" + Kpa(p), Spec(LabPath::kUnloadReload, p, 0.04, n)});
    paths.push_back({"isotropic" + Kpa(p), Spec(LabPath::kIsotropic, p, 0.01, n)});
  }
  for (int k = 1; k <= recipe.walks; ++k) {
    const double p = recipe.pressures_pa[static_cast<std::size_t>(k) % recipe.pressures_pa.size()];
    paths.push_back({"random-walk" + Kpa(p) + " seed " + std::to_string(k),
                     Spec(LabPath::kRandomWalk, p, recipe.max_walk_strain, n,
                          static_cast<std::uint64_t>(k))});
  }
  return paths;
}

std::vector<NamedLabPath> HeldOutPaths(const SurrogateRecipe& recipe) {
  using ann::LabPath;
  const int n = recipe.steps;
  const std::vector<double>& p = recipe.pressures_pa;
  // Between training pressures (geometric means of neighbours), never on one.
  const auto between = [&](std::size_t k) { return std::sqrt(p[k] * p[k + 1]); };
  const std::size_t last = p.size() - 2;
  const double triaxial = between(last / 2), shear = between(last), reload = between(0);
  std::vector<NamedLabPath> paths = {
      {"triaxial" + Kpa(triaxial), Spec(LabPath::kTriaxial, triaxial, 0.05, n)},
      {"simple-shear" + Kpa(shear), Spec(LabPath::kSimpleShear, shear, 0.1, n)},
      {"unload-reload" + Kpa(reload), Spec(LabPath::kUnloadReload, reload, 0.04, n)}};
  // The first walk at the triaxial's pressure, the next ones cycling through the others between.
  for (int k = 0; k < recipe.held_out_walks; ++k) {
    const double pressure = between((last / 2 + static_cast<std::size_t>(k)) % (last + 1));
    const std::uint64_t seed = 1001 + static_cast<std::uint64_t>(k);
    paths.push_back({"random-walk" + Kpa(pressure) + " seed " + std::to_string(seed),
                     Spec(LabPath::kRandomWalk, pressure, recipe.max_walk_strain, n, seed)});
  }
  return paths;
}

std::vector<ann::StrainHistory> RunLabPaths(const material::ConstitutiveModel& model,
                                            const std::vector<NamedLabPath>& paths, int threads,
                                            const std::function<void(int done)>& progress,
                                            const ann::InternalVariables& internal) {
  std::vector<ann::StrainHistory> histories(paths.size());
  ann::DriverOptions options;
  options.relative_tolerance = 0.02;  // a packing's stress is a sum over contacts
  int done = 0;
#pragma omp parallel for schedule(dynamic) num_threads(threads)
  for (int k = 0; k < static_cast<int>(paths.size()); ++k) {
    histories[k] = ann::RunLabPath(model, paths[k].spec, options, internal);
#pragma omp critical
    {
      ++done;
      if (progress) progress(done);
    }
  }
  return histories;
}

ann::InternalVariables RveFabricVariables() {
  ann::InternalVariables internal;
  internal.names = {"coordination_number", "solid_fraction", "fabric_xx", "fabric_yy",
                    "fabric_zz",           "fabric_yz",      "fabric_xz", "fabric_xy"};
  internal.read = [](const material::MaterialState& state) {
    const dem::rve::RveSnapshot snapshot =
        static_cast<const dem::rve::RveState&>(state).rve().Snapshot();
    const material::Vector6 fabric = material::StressToVoigt(snapshot.fabric);
    return std::vector<double>{snapshot.coordination_number, snapshot.solid_fraction, fabric[0],
                               fabric[1], fabric[2], fabric[3], fabric[4], fabric[5]};
  };
  return internal;
}

ann::InternalVariables RveVariables(const std::vector<std::string>& names,
                                   const std::string& field) {
  return ann::Narrowed(RveFabricVariables(), names, field, "a variable of the RVE's state");
}

RecordedRigRun RecordRigPaths(const FeDeTier& fe_de, const TractionRequest& request,
                              const ComputeContext& context,
                              const ann::InternalVariables& internal) {
  std::shared_ptr<const ann::PathRecorder> recorder;
  const PointStandInFactory record = [&](std::shared_ptr<const dem::rve::RveMaterial> rve) {
    recorder = std::make_shared<const ann::PathRecorder>(rve, internal);
    PointStandIn stand_in;
    stand_in.model = recorder;  // its states are the RVE's bytes: no translation
    return stand_in;
  };
  ComputeContext alone = context;
  alone.communicator = MPI_COMM_NULL;
  RecordedRigRun recorded;
  recorded.run = fe_de.RunWithStandIn(request, record, alone);
  if (recorder) recorded.paths = recorder->Histories();
  return recorded;
}

ann::StrainHistory ReplayedOnRve(std::shared_ptr<const dem::rve::RveMaterial> rve,
                                 const ann::StrainHistory& path,
                                 const ann::InternalVariables& internal) {
  const std::string settled = SettledAtPathStart(*rve, path);
  const ann::PathRecorder recorder(rve, internal);
  std::unique_ptr<material::MaterialState> state = recorder.RestoreState(settled);
  std::string stopped_reason;
  for (const material::Matrix3& increment : path.increments) {
    std::vector<material::PointResponse> response =
        recorder.Update({{increment, state.get()}}, false);
    if (response.front().status != material::UpdateStatus::kOk) {
      stopped_reason = response.front().reason;
      break;
    }
    state = std::move(response.front().state);
  }
  std::vector<ann::StrainHistory> replayed = recorder.Histories();
  Require(replayed.size() == 1, "path", "the RVE took none of its increments: " + stopped_reason);
  replayed.front().stopped_reason = stopped_reason;
  return std::move(replayed.front());
}

GuardedReplay ReplayGuarded(const ann::SurrogateEnsemble& ensemble,
                            std::shared_ptr<const dem::rve::RveMaterial> rve,
                            const ann::StrainHistory& path, int return_after_steps) {
  const std::string settled = SettledAtPathStart(*rve, path);
  ann::AnnMaterialOptions options;  // as FeAnnTier::Run makes its points' material
  options.return_after_steps = return_after_steps;
  options.internal_variables = RveFabricVariables();
  // The material lives only in this call: it holds the caller's ensemble without owning it.
  const ann::AnnMaterial material(std::shared_ptr<const ann::SurrogateEnsemble>(
                                      &ensemble, [](const ann::SurrogateEnsemble*) {}),
                                  rve, options);
  std::unique_ptr<material::MaterialState> state = material.StateFrom(settled);
  GuardedReplay replay;
  for (const material::Matrix3& increment : path.increments) {
    std::vector<material::PointResponse> response =
        material.Update({{increment, state.get()}}, false);
    if (response.front().status != material::UpdateStatus::kOk) {
      replay.stopped_reason = response.front().reason;
      break;
    }
    replay.stresses_pa.push_back(material::StressToVoigt(response.front().stress_pa));
    state = std::move(response.front().state);
  }
  replay.error = ann::ReplayError(replay.stresses_pa, path);
  const std::vector<ann::FallbackLog::Event> fallbacks = material.log().fallbacks();
  replay.fallbacks = static_cast<int>(fallbacks.size());
  if (!fallbacks.empty()) replay.first_fallback_step = fallbacks.front().point_step;
  replay.returns = material.log().returns();
  return replay;
}

CurveDifference WorstDifference(const TractionCurve& a, const TractionCurve& b,
                                const TractionRequest& request) {
  const double load_n = request.wheel_load_n;
  const double radius_m = 0.5 * request.tyre.diameter_m;
  CurveDifference worst;
  for (std::size_t k = 0; k < std::min(a.points.size(), b.points.size()); ++k) {
    const TractionPoint& p = a.points[k];
    const TractionPoint& q = b.points[k];
    worst.drawbar_pull_over_w =
        std::max(worst.drawbar_pull_over_w, std::abs(p.drawbar_pull_n - q.drawbar_pull_n) / load_n);
    worst.torque_over_rw =
        std::max(worst.torque_over_rw, std::abs(p.torque_nm - q.torque_nm) / (radius_m * load_n));
    worst.sinkage_over_r =
        std::max(worst.sinkage_over_r, std::abs(p.sinkage_m - q.sinkage_m) / radius_m);
  }
  return worst;
}

std::string HistoriesHash(const std::vector<ann::StrainHistory>& histories) {
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a, 64 bit
  for (const ann::StrainHistory& history : histories) {
    for (unsigned char byte : ann::SerializeHistory(history)) {
      hash = (hash ^ byte) * 1099511628211ULL;
    }
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

double PackingFloor(const std::vector<PackingDifference>& packings) {
  if (packings.empty()) return 0;
  std::vector<double> differences;
  for (const PackingDifference& packing : packings) differences.push_back(packing.difference);
  std::sort(differences.begin(), differences.end());
  const std::size_t middle = differences.size() / 2;
  return differences.size() % 2 == 1 ? differences[middle]
                                     : 0.5 * (differences[middle - 1] + differences[middle]);
}

std::vector<std::size_t> EvenlySpreadIndices(std::size_t size, int count, int offset) {
  Require(count >= 0, "count", "must be >= 0");
  std::vector<std::size_t> chosen;
  if (size == 0 || count == 0) return chosen;
  const double stride = static_cast<double>(size) / count;
  for (int k = 0; k < count; ++k) {
    chosen.push_back(static_cast<std::size_t>(offset + k * stride) % size);
  }
  return chosen;
}

std::vector<ann::StrainHistory> EvenlySpread(const std::vector<ann::StrainHistory>& paths,
                                             int count, int offset) {
  std::vector<ann::StrainHistory> chosen;
  for (std::size_t index : EvenlySpreadIndices(paths.size(), count, offset)) {
    chosen.push_back(paths[index]);
  }
  return chosen;
}

int RigHeldOutOffset(int paths, int training_points) {
  return paths / (2 * std::max(1, training_points)) + 1;
}

TrainedSurrogate TrainSurrogateOnRve(
    const SoilParameters& soil, const FeDeOptions& fe_de, const SurrogateRecipe& recipe,
    const std::function<void(const std::string& stage, double fraction)>& stage) {
  recipe.Validate("recipe.");
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(soil, fe_de.numerics, "soil.parameters"));
  const std::vector<NamedLabPath> training_paths = TrainingPaths(recipe);
  const std::vector<NamedLabPath> held_out_paths = HeldOutPaths(recipe);
  const double all_paths = static_cast<double>(training_paths.size() + held_out_paths.size());

  // The histories record what the network carries, and nothing more.
  const ann::InternalVariables carried = RveVariables(
      recipe.architecture.carried_variables, "recipe.architecture.carried_variables");
  TrainedSurrogate trained;
  const auto start = std::chrono::steady_clock::now();
  trained.training = RunLabPaths(
      *rve, training_paths, recipe.threads,
      [&](int done) {
        if (stage) stage("paths", done / all_paths);
      },
      carried);
  trained.held_out = RunLabPaths(
      *rve, held_out_paths, recipe.threads,
      [&](int done) {
        if (stage) stage("paths", (training_paths.size() + done) / all_paths);
      },
      carried);
  trained.generation_seconds = Seconds(start);
  trained.training.insert(trained.training.end(), recipe.rig_training.begin(),
                          recipe.rig_training.end());
  std::vector<std::string> held_out_names;
  for (const NamedLabPath& path : held_out_paths) held_out_names.push_back(path.name);
  for (std::size_t k = 0; k < recipe.rig_held_out.size(); ++k) {
    trained.held_out.push_back(recipe.rig_held_out[k]);
    held_out_names.push_back("rig point " + std::to_string(k + 1));
  }

  for (const ann::StrainHistory& history : trained.training) {
    trained.samples += static_cast<std::int64_t>(history.steps());
  }
  trained.data_hash = HistoriesHash(trained.training);

  ann::TrainingOptions training = recipe.training;
  if (recipe.walk_share > 0) {
    training.history_weights =
        WalkShareWeights(training_paths, trained.training, recipe.walk_share);
  }
  if (stage) stage("training", 0);
  const auto train_start = std::chrono::steady_clock::now();
  trained.ensemble = ann::SurrogateEnsemble::Train(
      ann::WithRotatedCopies(trained.training, recipe.rotated_copies, recipe.training.seed),
      recipe.architecture, training, recipe.members);
  trained.training_seconds = Seconds(train_start);
  for (std::size_t k = 0; k < trained.held_out.size(); ++k) {
    const double error = ann::ReplayError(trained.ensemble, trained.held_out[k]);
    trained.held_out_errors.push_back({held_out_names[k], error, {}});
    trained.worst_held_out_error = std::max(trained.worst_held_out_error, error);
  }
  if (stage) stage("training", 1);
  return trained;
}

}  // namespace gonogo::tiers
