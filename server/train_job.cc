// The training half of the job manager: TrainSurrogate jobs (kind "train"). A job trains one
// surrogate ensemble of a soil's DE RVE for the fe-ann tier, on the worker pool:
//   1. the recipe's strain paths (solvers/tiers/surrogate_training.h: the training set and the
//      held-out set) on the soil's RVE at the server's fe-de numerics, one pool task per path not
//      already in the dataset store; each history is stored the moment it arrives, so a cancelled,
//      drained or crashed job loses no finished path, and every later training on the same soil
//      and configuration reuses them (cache/dataset_store.h);
//   2. each ensemble member trained (or fine-tuned from a registered model's member) as a pool
//      task on the stored training histories;
//   3. the members assembled with their envelope (SurrogateEnsemble::Assemble), measured on the
//      held-out histories and registered with their provenance (surrogate_registry.h).
// The registered model is the job's summary (SurrogateModel as JSON) and product model.json.
#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "cache/dataset_store.h"
#include "server/convert.h"
#include "server/fallback_paths.h"
#include "server/job_manager.h"
#include "server/job_records.h"
#include "server/training_work.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/soil_catalogue.h"
#include "solvers/tiers/surrogate_registry.h"
#include "solvers/tiers/surrogate_training.h"

namespace gonogo::server {

namespace fs = std::filesystem;

namespace {

// Scheduling estimate of one training task: the long lane of the pool's queue.
constexpr double kTrainingTaskSeconds = 10;

int64_t NowUnixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

const tiers::CatalogueEntry& RveSoil(const std::string& soil_name) {
  Require(!soil_name.empty(), "soil_name", "is missing");
  Require(soil_name.size() <= 256, "soil_name", "must be at most 256 characters");
  const tiers::CatalogueEntry* entry =
      tiers::BuiltinSoilCatalogue().Find(soil_name, dem::rve::kRveSoilModel);
  if (entry == nullptr) {
    throw InputError("soil_name", "no " + std::string(dem::rve::kRveSoilModel) + " soil '" +
                                      soil_name + "' in the catalogue (`gonogo soils` lists them)");
  }
  return *entry;
}

// The request's recipe with the API's defaults ("0 means ..."), validated by field.
tiers::SurrogateRecipe RecipeOf(const v1::TrainSurrogateRequest& request, bool fine_tuning) {
  tiers::SurrogateRecipe recipe;
  if (request.steps() != 0) recipe.steps = static_cast<int>(std::min(request.steps(), 1000000u));
  Require(recipe.steps <= 100000, "steps", "must be at most 100000");
  if (request.walks() != 0) recipe.walks = static_cast<int>(std::min(request.walks(), 1000000u));
  Require(recipe.walks <= 10000, "walks", "must be at most 10000");
  if (request.pressures_kpa_size() > 0) {
    Require(request.pressures_kpa_size() >= 2 && request.pressures_kpa_size() <= 64,
            "pressures_kpa", "must hold 2 to 64 pressures");
    recipe.pressures_pa.clear();
    for (double kpa : request.pressures_kpa()) {
      Require(std::isfinite(kpa) && kpa > 0 && kpa <= 1e6, "pressures_kpa",
              "each must be a positive pressure up to 1 GPa, kPa");
      recipe.pressures_pa.push_back(kpa * 1e3);
    }
    Require(std::is_sorted(recipe.pressures_pa.begin(), recipe.pressures_pa.end()),
            "pressures_kpa", "must be in increasing order");
  }
  if (request.hidden_widths_size() > 0) {
    Require(!fine_tuning, "hidden_widths", "a fine-tuned model keeps its base model's layers");
    Require(request.hidden_widths_size() <= 16, "hidden_widths", "needs 1 to 16 hidden layers");
    recipe.architecture.hidden_widths.clear();
    for (uint32_t width : request.hidden_widths()) {
      Require(width >= 1 && width <= 4096, "hidden_widths", "each layer 1 to 4096 wide");
      recipe.architecture.hidden_widths.push_back(static_cast<int>(width));
    }
  }
  Require(!(fine_tuning && request.unanchored()), "unanchored",
          "a fine-tuned model keeps its base model's anchoring");
  recipe.architecture.anchored = !request.unanchored();
  Require(!(fine_tuning && request.pressure_reference_pa() != 0), "pressure_reference_pa",
          "a fine-tuned model keeps its base model's pressure scaling");
  recipe.architecture.pressure_reference_pa = request.pressure_reference_pa();
  Require(!(fine_tuning && request.hybrid()), "hybrid",
          "a fine-tuned model keeps its base model's form");
  Require(!(request.hybrid() && request.unanchored()), "hybrid",
          "needs the anchored network (not unanchored)");
  recipe.architecture.homogeneous_term = request.hybrid();
  Require(!(fine_tuning && request.previous_direction()), "previous_direction",
          "a fine-tuned model keeps its base model's form");
  recipe.architecture.previous_direction = request.previous_direction();
  recipe.walk_share = request.walk_share();
  recipe.architecture.Validate("");
  if (request.carried_variables_size() > 0) {
    Require(!fine_tuning, "carried_variables",
            "a fine-tuned model carries what its base model carries");
    recipe.architecture.carried_variables.assign(request.carried_variables().begin(),
                                                 request.carried_variables().end());
    recipe.architecture.Validate("");
    tiers::RveVariables(recipe.architecture.carried_variables, "carried_variables");
  }
  if (request.members() != 0) {
    Require(!fine_tuning, "members", "a fine-tuned model keeps its base model's members");
    Require(request.members() >= 3 && request.members() <= 64, "members", "must lie in [3, 64]");
    recipe.members = static_cast<int>(request.members());
  }
  recipe.training.epochs = fine_tuning ? 100 : 300;
  if (request.epochs() != 0) {
    Require(request.epochs() <= 100000, "epochs", "must be at most 100000");
    recipe.training.epochs = static_cast<int>(request.epochs());
  }
  recipe.training.learning_rate = fine_tuning ? 1e-3 : 3e-3;
  if (request.learning_rate() != 0) {
    Require(std::isfinite(request.learning_rate()) && request.learning_rate() > 0 &&
                request.learning_rate() < 1,
            "learning_rate", "must lie in (0, 1)");
    recipe.training.learning_rate = request.learning_rate();
  }
  recipe.training.seed = request.seed() == 0 ? 1 : request.seed();
  Require(request.name().size() <= 256, "name", "must be at most 256 characters");
  recipe.Validate("");
  return recipe;
}

// Seed 000's step 2 in a request: the rig run whose points' paths join the data.
struct RigRecipe {
  double load_n = 0;  // 0: none
  double diameter_m = 0.5;
  double width_m = 0.2;
  int training_points = 8;
  int held_out_points = 4;
};

RigRecipe RigRecipeOf(const v1::TrainSurrogateRequest& request) {
  RigRecipe rig;
  Require(std::isfinite(request.rig_load_n()) && request.rig_load_n() >= 0 &&
              request.rig_load_n() <= 1e6,
          "rig_load_n", "must be a wheel load in [0, 1e6] N (0: no rig paths)");
  if (request.rig_load_n() == 0) {
    Require(request.rig_diameter_m() == 0 && request.rig_width_m() == 0 &&
                request.rig_points() == 0,
            "rig_load_n", "is needed with a rig wheel or rig points (0: no rig paths)");
    return rig;
  }
  rig.load_n = request.rig_load_n();
  if (request.rig_diameter_m() != 0) rig.diameter_m = request.rig_diameter_m();
  if (request.rig_width_m() != 0) rig.width_m = request.rig_width_m();
  Require(std::isfinite(rig.diameter_m) && rig.diameter_m > 0 && rig.diameter_m <= 5,
          "rig_diameter_m", "must lie in (0, 5] m");
  Require(std::isfinite(rig.width_m) && rig.width_m > 0 && rig.width_m <= rig.diameter_m,
          "rig_width_m", "must lie in (0, rig_diameter_m] m");
  if (request.rig_points() != 0) {
    Require(request.rig_points() <= 1024, "rig_points", "must be at most 1024");
    rig.training_points = static_cast<int>(request.rig_points());
  }
  rig.held_out_points = std::max(1, rig.training_points / 2);
  return rig;
}

// The internal variables a registered architecture carries ("...-carrying-a+b": a, b).
std::vector<std::string> CarriedOfArchitecture(const std::string& architecture) {
  const std::string marker = "-carrying-";
  std::vector<std::string> carried;
  const size_t at = architecture.find(marker);
  if (at == std::string::npos) return carried;
  std::stringstream names(architecture.substr(at + marker.size()));
  for (std::string name; std::getline(names, name, '+');) carried.push_back(name);
  return carried;
}

// ";recorded=a+b" when a history records the RVE's internal variables a and b, else nothing (the
// keys of histories that record none are those from before any did).
std::string RecordedSuffix(const std::vector<std::string>& recorded) {
  std::string names;
  for (const std::string& name : recorded) names += (names.empty() ? "" : "+") + name;
  return names.empty() ? "" : ";recorded=" + names;
}

// What a stored history is: the soil, the configuration, the RVE's code, the path, the RVE's
// packing when it is not the configuration's own (`packing_seed` 0), and what it records of the
// RVE's state.
std::string HistoryKey(const std::string& soil_parameters, const std::string& preset,
                       const std::string& rve_version, const ann::LabPathSpec& spec,
                       const std::vector<std::string>& recorded, unsigned packing_seed = 0) {
  char path[256];
  std::snprintf(path, sizeof path, "path=%s;p=%.17g;max=%.17g;steps=%d;settle=%d;walk=%.17g;seed=%llu",
                ann::LabPathName(spec.path).c_str(), spec.pressure_pa, spec.max_strain, spec.steps,
                spec.settle_steps, spec.walk_step_strain,
                static_cast<unsigned long long>(spec.seed));
  return "gonogo-rve-path-v1;soil=" + soil_parameters + ";preset=" + preset +
         ";rve=" + rve_version + ";" + path +
         (packing_seed > 0 ? ";packing=" + std::to_string(packing_seed) : std::string()) +
         RecordedSuffix(recorded);
}

// How many other packings each held-out path also runs on (the floor under its error).
int FloorPackingsOf(const v1::TrainSurrogateRequest& request) {
  Require(request.floor_packings() <= 16, "floor_packings", "must be at most 16 (0: none)");
  return static_cast<int>(request.floor_packings());
}

// Runs `tasks` on the pool, at most kInFlightPerWorker per worker at a time, and hands each
// answer to `on_answer` on the calling thread as it arrives. Stops early, cancelling what is
// queued or running and waiting for it, when `stop` says so, the pool cancels a task (its
// shutdown) or a task fails. Returns the first failure; else cancelled when stopped; else ok.
TaskResult RunTrainingTasks(CurveResolver& resolver, std::vector<TaskSpec> tasks,
                            const std::function<bool()>& stop,
                            const std::function<void(size_t index, const TaskResult&)>& on_answer) {
  struct Shared {
    std::mutex mutex;
    std::condition_variable arrived;
    std::deque<TaskResult> results;
  };
  auto shared = std::make_shared<Shared>();
  WorkerPool& pool = resolver.pool();
  const size_t in_flight_limit =
      kInFlightPerWorker * static_cast<size_t>(std::max(1, pool.Workers()));
  std::map<uint64_t, size_t> outstanding;  // task id -> index
  size_t next = 0;
  TaskResult failure;      // the first task that failed
  bool stopped = false;    // by `stop`, or by the pool cancelling a task (its shutdown)
  const auto stopping = [&] { return stopped || failure.error_kind != ErrorKind::kNone; };
  while (true) {
    while (!stopping() && next < tasks.size() && outstanding.size() < in_flight_limit) {
      TaskSpec& task = tasks[next];
      task.task_id = resolver.NewTaskId();
      outstanding[task.task_id] = next++;
      pool.Submit(std::move(task), [shared](TaskResult result) {
        std::lock_guard<std::mutex> lock(shared->mutex);
        shared->results.push_back(std::move(result));
        shared->arrived.notify_all();
      });
    }
    if (outstanding.empty()) break;
    std::deque<TaskResult> ready;
    {
      std::unique_lock<std::mutex> lock(shared->mutex);
      shared->arrived.wait_for(lock, std::chrono::milliseconds(100),
                               [&] { return !shared->results.empty(); });
      ready.swap(shared->results);
    }
    for (TaskResult& result : ready) {
      const auto found = outstanding.find(result.task_id);
      if (found == outstanding.end()) continue;
      const size_t index = found->second;
      outstanding.erase(found);
      if (result.ok) {
        if (!stopping()) on_answer(index, result);
      } else if (result.cancelled) {
        stopped = true;
      } else if (failure.error_kind == ErrorKind::kNone) {
        failure = std::move(result);
        if (failure.error_kind == ErrorKind::kNone) failure.error_kind = ErrorKind::kInternal;
      }
    }
    if (!stopping() && stop()) stopped = true;
    if (stopping()) {
      for (const auto& [id, index] : outstanding) pool.Cancel(id);
    }
  }
  if (failure.error_kind != ErrorKind::kNone) return failure;
  TaskResult outcome;
  outcome.ok = !stopped;
  outcome.cancelled = stopped;
  return outcome;
}

TaskSpec TrainingTask(v1::TrainingWork work, uint32_t debug_delay_ms) {
  TaskSpec task;
  task.debug_delay_ms = debug_delay_ms;
  task.tier = "fe-ann";
  task.needs.ranks = 1;
  task.needs.threads = 1;
  task.needs.expected_seconds = kTrainingTaskSeconds;
  task.training = std::make_shared<const v1::TrainingWork>(std::move(work));
  return task;
}

struct PlannedPath {
  tiers::NamedLabPath path;  // a laboratory path's specification; a rig path's name only
  std::string role;
  std::string key;
  bool from_rig = false;  // made by the job's rig run, not by a path task of its own
  // A held-out path on another packing of the RVE (floor_packings): that packing's seed and the
  // place in the plan of the path it is the floor of; 0 and none for every other path.
  unsigned packing_seed = 0;
  size_t floor_of = 0;
  // A held-out rig path on another packing: its task replays the rig's path (tiers::ReplayedOnRve),
  // so it runs once the rig run has made that path.
  bool replays_rig_path = false;
};

// The k-th kept path of a rig run (training or held out), by what the run and the choice were.
std::string RigPathKey(const std::string& soil_parameters, const std::string& preset,
                       const std::string& rve_version, const RigRecipe& rig,
                       const std::string& role, int k, const std::vector<std::string>& recorded) {
  char text[256];
  std::snprintf(text, sizeof text, "load=%.17g;d=%.17g;b=%.17g;kept=%d+%d;%s=%d", rig.load_n,
                rig.diameter_m, rig.width_m, rig.training_points, rig.held_out_points,
                role.c_str(), k);
  return "gonogo-rig-path-v1;soil=" + soil_parameters + ";preset=" + preset +
         ";rve=" + rve_version + ";" + text + RecordedSuffix(recorded);
}

// The dataset a training's paths go to: the soil's at the configuration, followed by "+NAME" for
// each internal variable the paths record.
std::string DatasetOf(const tiers::CatalogueEntry& soil, const std::string& preset,
                      const std::vector<std::string>& recorded) {
  std::string dataset = cache::DatasetId(soil.soil, preset, CanonicalText(soil.parameters));
  for (const std::string& name : recorded) dataset += "+" + name;
  return dataset;
}

// What a training request's fallback_paths_share may be.
void ValidateFallbackShare(const v1::TrainSurrogateRequest& request) {
  Require(std::isfinite(request.fallback_paths_share()) && request.fallback_paths_share() >= 0 &&
              request.fallback_paths_share() <= 0.99,
          "fallback_paths_share", "must be in [0, 0.99] (0: the fallback paths are left out)");
}

// "rig 1000 N point 3": kept path k (from 0) of a rig run.
std::string RigPathName(const RigRecipe& rig, int k) {
  char text[64];
  std::snprintf(text, sizeof text, "rig %g N point %d", rig.load_n, k + 1);
  return text;
}

}  // namespace

v1::Job JobManager::SubmitTraining(const std::string& id, const std::string& owner,
                                   const v1::TrainSurrogateRequest& request) {
  if (config_.models_dir.empty()) {
    throw PreconditionError("tier", "this server keeps no fe-ann models (no data directory)");
  }
  const tiers::CatalogueEntry& soil = RveSoil(request.soil_name());
  Require(request.from_model().size() <= 64, "from_model", "must be at most 64 characters");
  const bool fine_tuning = !request.from_model().empty();
  const tiers::SurrogateRecipe recipe = RecipeOf(request, fine_tuning);
  RigRecipeOf(request);
  ValidateFallbackShare(request);
  FloorPackingsOf(request);
  std::vector<std::string> recorded = recipe.architecture.carried_variables;
  if (fine_tuning) {
    const auto base =
        tiers::SurrogateRegistry(config_.models_dir).Describe(request.from_model());
    Require(base.has_value(), "from_model",
            "no model '" + request.from_model() + "' (`gonogo models` lists them)");
    Require(base->fe_de_preset == config_.fe_de_preset, "from_model",
            "model '" + base->id + "' was trained on RVEs of the " + base->fe_de_preset +
                " configuration; this server runs " + config_.fe_de_preset);
    Require(base->architecture.find("-hybrid") == std::string::npos, "from_model",
            "model '" + base->id + "' has the homogeneous term (hybrid), which is not fine-tuned");
    recorded = CarriedOfArchitecture(base->architecture);
  }
  if (request.fallback_paths_share() > 0) {
    const std::string dataset = DatasetOf(soil, config_.fe_de_preset, recorded);
    if (!cache::DatasetStore(db_).HasKind(dataset, kFallbackPathKind)) {
      throw PreconditionError("fallback_paths_share",
                              "dataset " + dataset + " holds no fallback paths: they are kept "
                              "from fe-ann curves whose points fell back (gonogo curve --tier "
                              "fe-ann --model ID)");
    }
  }
  cache::JobRecord rec;
  rec.id = id;
  rec.owner = owner;
  rec.kind = cache::kTrainJob;
  rec.name = request.name().empty() ? "surrogate training: " + soil.soil : request.name();
  rec.tier = "fe-ann";
  rec.request = request.SerializeAsString();
  return Enqueue(std::move(rec));
}

void JobManager::RunTrainJob(const cache::JobRecord& rec, const std::shared_ptr<Live>& live) {
  const std::string id = rec.id;
  v1::JobStatus status = StatusOf(rec);
  auto report = [&](double fraction, const std::string& message, bool persist) {
    status.set_fraction_done(fraction);
    ReportProgress(id, status, message, persist);
  };
  const auto stop = [&] {
    std::lock_guard<std::mutex> lock(mutex_);
    return stopping_ || live->cancel_requested.load();
  };
  // A stopped job: cancelled, or back to QUEUED for the next start when the server drains.
  const auto end_stopped = [&] {
    if (live->cancel_requested) return Finish(id, cache::JobState::kCancelled, "cancelled", "", {});
    Requeue(id);
  };
  const auto end_failed = [&](const TaskResult& failure, const std::string& what) {
    Finish(id, cache::JobState::kFailed,
           std::string(ErrorKindName(failure.error_kind)) + ": " + what + ": " + failure.error, "",
           {});
  };
  try {
    jobs_.SetState(id, cache::JobState::kRunning, "planning the strain paths");
    v1::TrainSurrogateRequest request;
    Require(request.ParseFromString(rec.request), "request", "stored request is unreadable");
    const bool fine_tuning = !request.from_model().empty();
    const tiers::SurrogateRecipe recipe = RecipeOf(request, fine_tuning);
    const tiers::CatalogueEntry& soil = RveSoil(request.soil_name());
    const std::string soil_text = CanonicalText(soil.parameters);
    const std::string& preset = config_.fe_de_preset;
    const std::string rve_version = tiers_.Get("fe-de").Version();
    const tiers::SurrogateRegistry registry(config_.models_dir);
    std::optional<tiers::RegisteredSurrogate> base;
    if (fine_tuning) {
      base = registry.Describe(request.from_model());
      Require(base.has_value(), "from_model", "model '" + request.from_model() + "' is gone");
    }
    // What the paths record of the RVE's state: what the network carries. Histories that record
    // it are a dataset of their own, so that a dataset exports as one table.
    const std::vector<std::string> recorded = fine_tuning
                                                  ? CarriedOfArchitecture(base->architecture)
                                                  : recipe.architecture.carried_variables;
    const std::string dataset = DatasetOf(soil, preset, recorded);

    // 1. The strain paths: the stored ones from the dataset, the others on the pool.
    std::vector<PlannedPath> planned;
    for (const auto& [paths, role] :
         {std::make_pair(tiers::TrainingPaths(recipe), cache::kTrainingRole),
          std::make_pair(tiers::HeldOutPaths(recipe), cache::kHeldOutRole)}) {
      for (const tiers::NamedLabPath& path : paths) {
        planned.push_back(
            {path, role, HistoryKey(soil_text, preset, rve_version, path.spec, recorded), false});
      }
    }
    // The floor under the held-out errors: each held-out laboratory path on other packings of the
    // soil's RVE (seeds after the configuration's own), stored as held-out histories of their own.
    const int floor_packings = FloorPackingsOf(request);
    const unsigned own_packing = tiers::FeDeOptions::Preset(preset).numerics.seed;
    for (size_t k = 0, lab_paths = planned.size(); k < lab_paths && floor_packings > 0; ++k) {
      if (planned[k].role != cache::kHeldOutRole) continue;
      for (int n = 1; n <= floor_packings; ++n) {
        PlannedPath other = planned[k];
        other.packing_seed = own_packing + static_cast<unsigned>(n);
        other.floor_of = k;
        other.path.name += " on packing " + std::to_string(other.packing_seed);
        other.key = HistoryKey(soil_text, preset, rve_version, other.path.spec, recorded,
                               other.packing_seed);
        planned.push_back(std::move(other));
      }
    }
    // Seed 000's step 2: the kept paths of an fe-de rig run's points, after the lab paths.
    const RigRecipe rig = RigRecipeOf(request);
    std::vector<size_t> rig_paths;  // their places in `planned`
    if (rig.load_n > 0) {
      for (const auto& [role, count] : {std::make_pair(std::string(cache::kTrainingRole),
                                                       rig.training_points),
                                        std::make_pair(std::string(cache::kHeldOutRole),
                                                       rig.held_out_points)}) {
        for (int k = 0; k < count; ++k) {
          PlannedPath path;
          path.path.name = role == cache::kTrainingRole ? RigPathName(rig, k)
                                                        : "rig point " + std::to_string(k + 1);
          path.role = role;
          path.key = RigPathKey(soil_text, preset, rve_version, rig, role, k, recorded);
          path.from_rig = true;
          rig_paths.push_back(planned.size());
          planned.push_back(std::move(path));
        }
      }
      // Their floors: each held-out rig path replayed on the other packings, as the lab paths.
      for (size_t k = 0, planned_paths = planned.size(); k < planned_paths; ++k) {
        if (!planned[k].from_rig || planned[k].role != cache::kHeldOutRole) continue;
        for (int n = 1; n <= floor_packings; ++n) {
          PlannedPath other;
          other.role = cache::kHeldOutRole;
          other.packing_seed = own_packing + static_cast<unsigned>(n);
          other.floor_of = k;
          other.replays_rig_path = true;
          other.path.name =
              planned[k].path.name + " on packing " + std::to_string(other.packing_seed);
          other.key = planned[k].key + ";packing=" + std::to_string(other.packing_seed);
          planned.push_back(std::move(other));
        }
      }
    }
    const size_t floor_paths = static_cast<size_t>(std::count_if(
        planned.begin(), planned.end(), [](const PlannedPath& p) { return p.packing_seed > 0; }));
    cache::DatasetStore store(db_);
    std::vector<TaskSpec> path_tasks;
    std::vector<size_t> task_path;  // the planned path of each task (planned.size(): the rig run)
    int stored = 0;
    bool rig_missing = false;
    for (size_t k = 0; k < planned.size(); ++k) {
      if (store.Has(planned[k].key)) {
        ++stored;
        continue;
      }
      if (planned[k].from_rig) {
        rig_missing = true;
        continue;
      }
      if (planned[k].replays_rig_path) continue;  // after the rig run (below)
      v1::TrainingWork work;
      *work.mutable_rve_path() = ToProto(planned[k].path.spec);
      work.mutable_rve_path()->set_soil_parameters(soil_text);
      work.mutable_rve_path()->set_fe_de_preset(preset);
      for (const std::string& name : recorded) work.mutable_rve_path()->add_recorded_variables(name);
      work.mutable_rve_path()->set_packing_seed(planned[k].packing_seed);
      path_tasks.push_back(TrainingTask(std::move(work), config_.task_delay_ms));
      task_path.push_back(k);
    }
    if (rig_missing) {  // one run makes every kept path of it
      v1::TrainingWork work;
      v1::RigPathsWork* run = work.mutable_rig_paths();
      run->set_soil_parameters(soil_text);
      run->set_fe_de_preset(preset);
      run->set_wheel_load_n(rig.load_n);
      run->set_diameter_m(rig.diameter_m);
      run->set_width_m(rig.width_m);
      run->set_training_points(rig.training_points);
      run->set_held_out_points(rig.held_out_points);
      for (const std::string& name : recorded) run->add_recorded_variables(name);
      // First in the queue: it is the longest task of the job.
      path_tasks.insert(path_tasks.begin(), TrainingTask(std::move(work), config_.task_delay_ms));
      task_path.insert(task_path.begin(), planned.size());
    }
    const int members = fine_tuning ? base->members : recipe.members;
    const int total_tasks = static_cast<int>(planned.size()) + members;
    int done = stored;
    status.set_tasks_total(static_cast<uint32_t>(total_tasks));
    status.set_tasks_done(static_cast<uint32_t>(done));
    status.set_cache_hits(static_cast<uint32_t>(stored));
    const auto paths_message = [&] {
      return std::string(rig.load_n > 0 ? "RVE strain paths and rig paths: "
                                        : "RVE strain paths: ") +
             std::to_string(done) + " of " + std::to_string(planned.size()) + " (" +
             (floor_paths > 0 ? std::to_string(floor_paths) + " on other packings; " : "") +
             std::to_string(stored) + " from dataset " + dataset + ")";
    };
    // The paths are most of a training's time: 80 % of the bar.
    report(0.8 * done / planned.size(), paths_message(), true);
    // Stores one history as it arrives (the first copy of a key stays).
    const auto keep = [&](const PlannedPath& path, const std::string& bytes, const std::string& kind,
                          int64_t seed, const TaskResult& result) {
      const ann::StrainHistory history = ann::ParseHistory(bytes);
      cache::StoredHistory row;
      row.history_key = path.key;
      row.dataset = dataset;
      row.soil_name = soil.soil;
      row.soil_parameters = soil_text;
      row.fe_de_preset = preset;
      row.rve_version = rve_version;
      row.path_kind = kind;
      row.path_name = path.path.name;
      row.role = path.role;
      row.seed = seed;
      row.steps = static_cast<int64_t>(history.steps());
      row.history = bytes;
      row.code_version = GONOGO_VERSION;
      row.computed_by = result.computed_by;
      row.compute_seconds = result.compute_seconds;
      row.created_unix_ms = NowUnixMs();
      if (store.Put(row)) ++done;
    };
    const auto generation_start = std::chrono::steady_clock::now();
    // Stores the answer of the task that made planned path k (planned.size(): the rig run).
    const auto keep_answer = [&](size_t k, const TaskResult& result) {
      if (k == planned.size()) {
        v1::RigPathsOutput output;
        Require(output.ParseFromString(result.training_output), "training.rig_paths",
                "the rig run's answer is unreadable");
        Require(output.training_size() == rig.training_points &&
                    output.held_out_size() == rig.held_out_points,
                "training.rig_paths", "the rig run kept another number of paths");
        // The kept paths in the order of `rig_paths`: training, then held out.
        std::vector<const std::string*> kept;
        for (const std::string& bytes : output.training()) kept.push_back(&bytes);
        for (const std::string& bytes : output.held_out()) kept.push_back(&bytes);
        TaskResult each = result;  // the run's seconds shared among its paths
        each.compute_seconds = result.compute_seconds / static_cast<double>(kept.size());
        for (size_t r = 0; r < rig_paths.size(); ++r) {
          keep(planned[rig_paths[r]], *kept[r], "rig-point", 0, each);
        }
        spdlog::info("job {}: rig run at {} N ({} elements, {} FE steps) in {:.1f} s on {}", id,
                     rig.load_n, output.elements(), output.fe_steps(), result.compute_seconds,
                     result.computed_by);
      } else if (planned[k].replays_rig_path) {
        keep(planned[k], result.training_output, "rig-point", 0, result);
      } else {
        const PlannedPath& path = planned[k];
        keep(path, result.training_output, ann::LabPathName(path.path.spec.path),
             static_cast<int64_t>(path.path.spec.seed), result);
      }
      status.set_tasks_done(static_cast<uint32_t>(done));
      report(0.8 * done / planned.size(), paths_message(), true);
    };
    const TaskResult paths_outcome = RunTrainingTasks(
        resolver_, std::move(path_tasks), stop,
        [&](size_t index, const TaskResult& result) { keep_answer(task_path[index], result); });
    if (paths_outcome.cancelled) return end_stopped();
    if (!paths_outcome.ok) return end_failed(paths_outcome, "an RVE strain path or the rig run");
    // The held-out rig paths' floors, now that the rig's paths are in the dataset.
    std::vector<TaskSpec> replay_tasks;
    std::vector<size_t> replay_path;  // the planned path of each replay task
    std::map<size_t, std::string> rig_path_bytes;  // each replayed rig path, read once
    for (size_t k = 0; k < planned.size(); ++k) {
      if (!planned[k].replays_rig_path || store.Has(planned[k].key)) continue;
      const size_t of = planned[k].floor_of;
      if (!rig_path_bytes.count(of)) {
        const std::optional<cache::StoredHistory> rig_path = store.Find(planned[of].key);
        Require(rig_path.has_value(), "dataset",
                "history of '" + planned[of].path.name + "' is missing");
        rig_path_bytes[of] = rig_path->history;
      }
      v1::TrainingWork work;
      v1::ReplayPathWork* replay = work.mutable_replay_path();
      replay->set_soil_parameters(soil_text);
      replay->set_fe_de_preset(preset);
      replay->set_packing_seed(planned[k].packing_seed);
      replay->set_history(rig_path_bytes[of]);
      for (const std::string& name : recorded) replay->add_recorded_variables(name);
      replay_tasks.push_back(TrainingTask(std::move(work), config_.task_delay_ms));
      replay_path.push_back(k);
    }
    const TaskResult replays_outcome = RunTrainingTasks(
        resolver_, std::move(replay_tasks), stop,
        [&](size_t index, const TaskResult& result) { keep_answer(replay_path[index], result); });
    if (replays_outcome.cancelled) return end_stopped();
    if (!replays_outcome.ok) {
      return end_failed(replays_outcome, "a held-out rig path on another packing");
    }
    const double generation_seconds = Seconds(generation_start);

    std::vector<ann::StrainHistory> training, held_out;
    std::vector<std::string> held_out_names;
    // Of each held-out path, the same path on other packings (its floor).
    std::vector<std::vector<std::pair<unsigned, ann::StrainHistory>>> held_out_floors;
    std::map<size_t, size_t> held_out_of_planned;
    v1::TrainMemberWork member_work;
    for (size_t k = 0; k < planned.size(); ++k) {
      const PlannedPath& path = planned[k];
      const std::optional<cache::StoredHistory> row = store.Find(path.key);
      Require(row.has_value(), "dataset", "history of '" + path.path.name + "' is missing");
      if (path.packing_seed > 0) {  // after the path it is the floor of
        held_out_floors[held_out_of_planned.at(path.floor_of)].emplace_back(
            path.packing_seed, ann::ParseHistory(row->history));
      } else if (path.role == cache::kTrainingRole) {
        training.push_back(ann::ParseHistory(row->history));
        member_work.add_histories(row->history);
      } else {
        held_out_of_planned[k] = held_out.size();
        held_out.push_back(ann::ParseHistory(row->history));
        held_out_names.push_back(path.path.name);
        held_out_floors.emplace_back();
      }
    }

    // The recipe's walks weighed to carry the asked share of the recipe paths' loss: `training`
    // holds the recipe's training paths in TrainingPaths order, then the rig's, as
    // WalkShareWeights takes them (the order gonogo-ann weighs them in, so both train alike).
    std::vector<double> recipe_weights(training.size(), 1.0);
    if (recipe.walk_share > 0) {
      recipe_weights =
          tiers::WalkShareWeights(tiers::TrainingPaths(recipe), training, recipe.walk_share);
    }
    // The fallback paths kept from fe-ann curves, weighed to carry the asked share of the whole
    // loss beside the recipe paths' weighed steps.
    const double fallback_share = request.fallback_paths_share();
    int fallback_paths = 0;
    if (recipe.walk_share > 0 || fallback_share > 0) {
      member_work.mutable_history_weights()->Add(recipe_weights.begin(), recipe_weights.end());
    }
    if (fallback_share > 0) {
      // The dataset's fallback paths (server/fallback_paths.h), in the order they were kept.
      const std::vector<cache::StoredHistory> rows =
          store.Histories(dataset, cache::kTrainingRole, kFallbackPathKind);
      Require(!rows.empty(), "fallback_paths_share", "dataset " + dataset + " holds no fallback paths");
      double recipe_steps = 0, fallback_steps = 0;  // weighed recipe steps
      for (size_t k = 0; k < training.size(); ++k) {
        recipe_steps += recipe_weights[k] * static_cast<double>(training[k].steps());
      }
      for (const cache::StoredHistory& row : rows) fallback_steps += static_cast<double>(row.steps);
      const double weight = fallback_share * recipe_steps / ((1 - fallback_share) * fallback_steps);
      for (const cache::StoredHistory& row : rows) {
        training.push_back(ann::ParseHistory(row.history));
        member_work.add_histories(row.history);
        member_work.add_history_weights(weight);
      }
      fallback_paths = static_cast<int>(rows.size());
    }

    // 2. The members, one task each.
    member_work.set_epochs(recipe.training.epochs);
    member_work.set_batch_size(recipe.training.batch_size);
    member_work.set_learning_rate(recipe.training.learning_rate);
    member_work.set_anchored(recipe.architecture.anchored);
    member_work.set_pressure_reference_pa(recipe.architecture.pressure_reference_pa);
    member_work.set_homogeneous_term(recipe.architecture.homogeneous_term);
    member_work.set_previous_direction(recipe.architecture.previous_direction);
    for (int width : recipe.architecture.hidden_widths) member_work.add_hidden_widths(width);
    for (const std::string& name : recipe.architecture.carried_variables) {
      member_work.add_carried_variables(name);
    }
    std::vector<TaskSpec> member_tasks;
    for (int k = 0; k < members; ++k) {
      v1::TrainingWork work;
      *work.mutable_train_member() = member_work;
      work.mutable_train_member()->set_seed(recipe.training.seed + static_cast<uint64_t>(k));
      if (fine_tuning) {
        work.mutable_train_member()->set_base_member_path(
            (fs::path(base->directory) / ("member_" + std::to_string(k) + ".pt")).string());
      }
      member_tasks.push_back(TrainingTask(std::move(work), config_.task_delay_ms));
    }
    // The weights as the member tasks ran them, for the record (member_work's copy is freed).
    const std::vector<double> member_weights(member_work.history_weights().begin(),
                                             member_work.history_weights().end());
    member_work.Clear();
    std::vector<std::string> member_bytes(static_cast<size_t>(members));
    int members_done = 0;
    const auto members_message = [&] {
      return "training the ensemble: " + std::to_string(members_done) + " of " +
             std::to_string(members) + " members (" + std::to_string(training.size()) +
             " training paths" +
             (fallback_paths > 0 ? ", " + std::to_string(fallback_paths) + " of them fallback paths"
                                 : std::string()) +
             ")";
    };
    report(0.8, members_message(), true);
    const auto training_start = std::chrono::steady_clock::now();
    const TaskResult members_outcome = RunTrainingTasks(
        resolver_, std::move(member_tasks), stop, [&](size_t index, const TaskResult& result) {
          member_bytes[index] = result.training_output;
          ++members_done;
          status.set_tasks_done(static_cast<uint32_t>(++done));
          report(0.8 + 0.18 * members_done / members, members_message(), true);
        });
    if (members_outcome.cancelled) return end_stopped();
    if (!members_outcome.ok) return end_failed(members_outcome, "an ensemble member");
    const double training_seconds = Seconds(training_start);

    // 3. Assembled, measured on the held-out paths, registered.
    report(0.98, "measuring the held-out paths and registering the model", true);
    std::vector<ann::StressSurrogate> surrogates;
    for (const std::string& bytes : member_bytes) {
      surrogates.push_back(ann::StressSurrogate::FromBytes(bytes));
    }
    const ann::SurrogateEnsemble ensemble =
        ann::SurrogateEnsemble::Assemble(std::move(surrogates), training);
    tiers::RegisteredSurrogate record;
    record.soil_name = soil.soil;
    record.soil_parameters = soil_text;
    record.fe_de_preset = preset;
    record.architecture = ensemble.member(0).architecture();
    record.id = registry.NewId(soil.soil, record.architecture);
    record.members = static_cast<int>(ensemble.size());
    record.data_hash = tiers::HistoriesHash(training);
    for (const ann::StrainHistory& history : training) {
      record.samples += static_cast<int64_t>(history.steps());
    }
    record.fallback_paths = fallback_paths;
    record.fallback_paths_share = fallback_share;  // 0 when none asked (then fallback_paths 0)
    record.walk_share = recipe.walk_share;
    record.distance_threshold = ensemble.distance_threshold();
    record.spread_threshold = ensemble.spread_threshold();
    record.tensile_limit_pa = ensemble.envelope().tensile_limit_pa;
    record.least_principal_ratio = ensemble.envelope().least_principal_ratio;
    for (size_t k = 0; k < held_out.size(); ++k) {
      tiers::HeldOutResult result{held_out_names[k], ann::ReplayError(ensemble, held_out[k]), {}};
      for (const auto& [seed, other] : held_out_floors[k]) {
        result.packings.push_back({seed, ann::HistoryDifference(other, held_out[k])});
      }
      record.worst_held_out_error = std::max(record.worst_held_out_error, result.replay_error);
      record.held_out.push_back(std::move(result));
    }
    const auto worst = std::max_element(
        record.held_out.begin(), record.held_out.end(),
        [](const auto& a, const auto& b) { return a.replay_error < b.replay_error; });
    record.training_seconds = training_seconds;
    ann::TrainingOptions member_training = recipe.training;  // as the member tasks ran it
    member_training.history_weights = member_weights;
    record.training = tiers::TrainingText(member_training);
    record.from_model = request.from_model();
    record.code_version = GONOGO_VERSION;
    record.created_unix_ms = NowUnixMs();
    const tiers::RegisteredSurrogate registered = registry.Register(record, ensemble);

    std::string json;
    google::protobuf::util::JsonPrintOptions json_options;
    json_options.add_whitespace = true;
    json_options.preserve_proto_field_names = true;
    google::protobuf::util::MessageToJsonString(ToProto(registered), &json, json_options);
    const fs::path out_dir = fs::path(JobDir(id)) / "out";
    fs::create_directories(out_dir);
    std::ofstream(out_dir / "model.json") << json << "\n";
    jobs_.SetProgress(id, {1.0, done, total_tasks, stored, 0, "done"});
    spdlog::info("job {}: model {} registered ({} paths in {:.1f} s, {} from the dataset; {} "
                 "members in {:.1f} s; worst held-out error {:.2f} %)",
                 id, registered.id, planned.size(), generation_seconds, stored, members,
                 training_seconds, 100 * registered.worst_held_out_error);
    char worst_text[128];
    std::snprintf(worst_text, sizeof worst_text, "%.2f %%", 100 * registered.worst_held_out_error);
    std::string message = "done: model " + registered.id + ", worst held-out error " + worst_text;
    if (worst != record.held_out.end() && !worst->packings.empty()) {
      // The floor under it: how far the RVE's other packings answer that path.
      const auto [least, most] = std::minmax_element(
          worst->packings.begin(), worst->packings.end(),
          [](const auto& a, const auto& b) { return a.difference < b.difference; });
      if (worst->packings.size() == 1) {
        std::snprintf(worst_text, sizeof worst_text, "another packing of the RVE %.2f %%",
                      100 * least->difference);
      } else {
        std::snprintf(worst_text, sizeof worst_text,
                      "other packings of the RVE %.2f to %.2f %%, median %.2f %%",
                      100 * least->difference, 100 * most->difference,
                      100 * tiers::PackingFloor(worst->packings));
      }
      message += " (" + worst->path + "; " + worst_text + ")";
      // What the registry ranks by (the soil's default model: the least).
      std::snprintf(worst_text, sizeof worst_text, "%.2f %%",
                    100 * tiers::WorstErrorBeyondFloor(registered));
      message += ", beyond the floors " + std::string(worst_text);
    }
    Finish(id, cache::JobState::kDone, message, json, {"model.json"});
  } catch (const std::exception& e) {
    Finish(id, cache::JobState::kFailed, e.what(), "", {});
  }
}

}  // namespace gonogo::server
