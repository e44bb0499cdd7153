// gonogo-ann: the surrogate's study on a soil's own DE RVE, from the command line.
//
//   gonogo-ann --soil seed000_sand_rve100 [--preset ci] [--steps 50] [--walks 16]
//              [--pressures-kpa 2.5 5 ...] [--architecture 64x64 ...] [--members 3]
//              [--carry coordination_number] [--epochs 300] [--threads T] [--out DIR]
//
// Runs the laboratory paths of the fe-ann recipe (solvers/tiers/surrogate_training.h) on the
// soil's RVE, with the RVE numerics of the fe-de preset: a training set and a held-out set (other
// pressures, another seed), on OpenMP threads, one path per thread. Trains an ensemble per MLP --architecture (one network per
// GRU: gru32) and prints, per
// architecture, the training figures, each held-out path's replay error (the stress error
// relative to the path's mean |sigma|) and the evaluation cost; with --rig-load-n, each held-out
// rig path also as the fe-ann tier answers its point (tiers::ReplayGuarded: the RVE from where the
// ensemble flags). With --out, writes the histories
// (training.npy, held_out.npy with their .columns.txt) and each ensemble (DIR/<architecture>/).
#include <CLI/CLI.hpp>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/fe_ann_tier.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/soil_catalogue.h"
#include "solvers/tiers/surrogate_registry.h"
#include "solvers/tiers/surrogate_training.h"

namespace {

using namespace gonogo;
using namespace gonogo::ann;

struct CommandLine {
  std::string soil = "seed000_sand_rve100";
  std::string preset = "ci";
  // The recipe's own defaults (solvers/tiers/surrogate_training.h).
  int steps = tiers::SurrogateRecipe().steps;
  int walks = tiers::SurrogateRecipe().walks;
  int held_out_walks = tiers::SurrogateRecipe().held_out_walks;
  std::vector<double> pressures_kpa;  // empty: the recipe's
  bool unanchored = false;
  double pressure_reference_pa = 0;  // MlpArchitecture::pressure_reference_pa
  double rig_load_n = 0;  // 0: no rig paths
  double rig_diameter_m = 0.5;
  double rig_width_m = 0.2;
  int rig_points = 16;
  std::vector<double> validate_loads_n;
  // --validate-load-n's runs at each of these multiples of the model's spread threshold.
  std::vector<double> validate_spread_scales = {1.0};
  std::vector<double> validate_pressure_floors_kpa = {0.0};
  std::string register_data_dir;  // non-empty: register each MLP ensemble there
  std::string from_model_dir;     // non-empty: also fine-tune this ensemble on the study's data
  double rest_kpa = 0;            // > 0: only the rest test at this pressure
  int rest_steps = 200;
  double rest_axial_strain = 0;  // the rest test's oedometric compression before resting
  double increment_kpa = 0;  // > 0: only the increment-size study at this pressure
  std::string increment_path = "triaxial";
  std::vector<int> increment_steps = {40, 160, 640};
  double tune_learning_rate = 1e-3;
  std::vector<std::string> architectures = {"64x64"};
  int members = 3;
  int epochs = 300;
  double path_stress_weighting = 0;
  int rollout_steps = 0;  // TrainingOptions::rollout_steps
  double rollout_weight = 1;
  double stress_noise = 0;  // TrainingOptions::stress_noise
  double noise_correction = 1;
  double walk_share = 0;  // > 0: the random walks' share of the loss
  double walk_persistence = 0;  // the training walks' (ann::LabPathSpec::walk_persistence)
  std::uint64_t training_seed = 1;
  bool record_fabric = false;  // histories record the RVE's coordination and fabric (--out)
  int return_after_steps = 0;  // --validate-load-n: fallen-back points return to the network
  std::vector<unsigned> packing_seeds;  // held-out paths also run on these packings (RVE spread)
  std::vector<std::string> carried;  // internal variables the MLPs carry (implies record_fabric)
  int threads = 2;
  std::string out;
};

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The recipe's paths run on the RVE, with a progress line and each early stop named.
std::vector<StrainHistory> RunPaths(const material::ConstitutiveModel& rve,
                                    const std::vector<tiers::NamedLabPath>& paths, int threads,
                                    const char* label, const InternalVariables& internal) {
  const std::vector<StrainHistory> histories = tiers::RunLabPaths(
      rve, paths, threads,
      [&](int done) { std::fprintf(stderr, "\r%s paths: %d / %zu", label, done, paths.size()); },
      internal);
  std::fprintf(stderr, "\n");
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (!histories[k].stopped_reason.empty()) {
      std::fprintf(stderr, "  %s %s stopped after %zu steps: %s\n", label,
                   paths[k].name.c_str(), histories[k].steps(),
                   histories[k].stopped_reason.c_str());
    }
  }
  return histories;
}

// The soil's RVE at the preset's numerics, packed from `seed` (RveNumerics::seed); settled once
// per process and packing (SharedRveMaterial).
std::shared_ptr<const dem::rve::RveMaterial> PackedFrom(const SoilParameters& soil,
                                                        const tiers::FeDeOptions& preset,
                                                        unsigned seed) {
  dem::rve::RveNumerics numerics = preset.numerics;
  numerics.seed = seed;
  return dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(soil, numerics, "soil"));
}

// The floor under a held-out error: the same held-out paths run on the soil's RVE packed from
// other seeds (RveNumerics::seed), their stresses measured against the study's packing's as a
// surrogate's replay is (HistoryDifference: sum |sigma_other - sigma| / sum |sigma| over the steps
// both reached). A surrogate of the soil cannot be told apart from its RVE closer than its packings
// are from one another. Returns each path's differences, for a registered model's record.
std::vector<std::vector<tiers::PackingDifference>> PrintPackingSpread(
    const CommandLine& line, const SoilParameters& soil, const tiers::FeDeOptions& preset,
    const std::vector<tiers::NamedLabPath>& held_out_paths,
    const std::vector<StrainHistory>& held_out) {
  std::vector<std::vector<tiers::PackingDifference>> differences(held_out.size());
  std::printf("packing_seed,");
  for (const tiers::NamedLabPath& path : held_out_paths) std::printf("%s %%,", path.name.c_str());
  std::printf("generation_s\n");
  for (unsigned seed : line.packing_seeds) {
    const auto start = std::chrono::steady_clock::now();
    const auto other_rve = PackedFrom(soil, preset, seed);
    const std::vector<StrainHistory> others =
        RunPaths(*other_rve, held_out_paths, line.threads, "other packing's held-out", {});
    std::printf("%u,", seed);
    for (std::size_t k = 0; k < held_out.size(); ++k) {
      differences[k].push_back({seed, HistoryDifference(others[k], held_out[k])});
      std::printf("%.2f,", 100 * differences[k].back().difference);
    }
    std::printf("%.1f\n", Since(start));
    std::fflush(stdout);
  }
  return differences;
}

MlpArchitecture ParseArchitecture(const std::string& text) {
  MlpArchitecture architecture;
  architecture.hidden_widths.clear();
  std::stringstream widths(text);
  std::string width;
  while (std::getline(widths, width, 'x')) {
    std::size_t used = 0;
    try {
      architecture.hidden_widths.push_back(std::stoi(width, &used));
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != width.size()) {
      throw InputError("--architecture", "'" + text + "' is not widths joined by x (64x64)");
    }
  }
  architecture.Validate("--architecture.");
  return architecture;
}

// The first `limit` training inputs: the batch an evaluation is timed on.
std::vector<SurrogateInput> TimingBatch(const std::vector<StrainHistory>& training,
                                        std::size_t limit,
                                        const std::vector<std::string>& carried = {}) {
  std::vector<SurrogateInput> batch;
  for (const StrainHistory& history : training) {
    for (const SurrogateInput& input : InputsOf(history, carried)) {
      if (batch.size() < limit) batch.push_back(input);
    }
  }
  return batch;
}

// Wall microseconds per point of `evaluate_batch` (a batch of `points`), over 5 calls.
double MicrosecondsPerPoint(std::size_t points, const std::function<void()>& evaluate_batch) {
  const int repeats = 5;
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < repeats; ++r) evaluate_batch();
  return 1e6 * Since(start) / (repeats * static_cast<double>(points));
}

// One GRU ("gru32": 32 hidden numbers per point), trained and measured as an ensemble member is.
int GruWidth(const std::string& text) {
  try {
    std::size_t used = 0;
    const int width = std::stoi(text.substr(3), &used);
    if (used == text.size() - 3 && width >= 1 && width <= 1024) return width;
  } catch (const std::exception&) {
  }
  throw InputError("--architecture", "'" + text + "' is not gru and a width in [1, 1024] (gru32)");
}

// The study's training options: epochs, seed and the loss's weights (empty: every history alike).
TrainingOptions StudyTraining(const CommandLine& line, const std::vector<double>& history_weights) {
  TrainingOptions options;
  options.epochs = line.epochs;
  options.seed = line.training_seed;
  options.path_stress_weighting = line.path_stress_weighting;
  options.rollout_steps = line.rollout_steps;
  options.rollout_weight = line.rollout_weight;
  options.stress_noise = line.stress_noise;
  options.noise_correction = line.noise_correction;
  options.history_weights = history_weights;
  return options;
}

void RunRecurrent(const CommandLine& line, const std::string& text,
                  const std::vector<StrainHistory>& training,
                  const std::vector<StrainHistory>& held_out,
                  const std::vector<double>& history_weights) {
  const int width = GruWidth(text);
  const TrainingOptions options = StudyTraining(line, history_weights);
  TrainingReport report;
  const RecurrentStressSurrogate gru =
      RecurrentStressSurrogate::Train(training, width, options, &report);
  std::printf("%s,1,%d,%lld,%.1f,%.3g,", gru.architecture().c_str(), line.epochs,
              static_cast<long long>(report.samples), report.seconds, report.final_loss);
  for (const StrainHistory& history : held_out) {
    std::printf("%.2f,", 100 * ReplayError(Replay(gru, history), history));
  }
  const std::vector<SurrogateInput> batch = TimingBatch(training, 1000);
  std::vector<std::vector<double>> hidden;
  std::printf("%.2f\n", MicrosecondsPerPoint(batch.size(), [&] { gru.Step(batch, &hidden); }));
  std::fflush(stdout);
  if (!line.out.empty()) gru.Save(line.out + "/" + gru.architecture() + ".pt");
}

TractionRequest RigRequest(const CommandLine& line, double load_n) {
  TractionRequest request;
  request.soil.soil_name = line.soil;
  request.tyre.diameter_m = line.rig_diameter_m;
  request.tyre.width_m = line.rig_width_m;
  request.tyre.section_height_m = 0.5 * line.rig_width_m;
  request.wheel_load_n = load_n;
  request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
  return request;
}

// fe-de curves by load, computed once each (the rig run's is the recorded run's).
struct FeDeReference {
  tiers::FeDeRunReport run;
  double seconds = 0;
};

// The ensemble as the fe-ann tier's model, run at each validation load against fe-de.
void Validate(const CommandLine& line, const std::string& model_directory,
              const std::string& architecture, double model_spread_threshold,
              const SoilParameters& soil, std::map<double, FeDeReference>& references) {
  tiers::SurrogateModelRecord record;
  record.id = architecture;
  record.directory = model_directory;
  record.soil_parameters = CanonicalText(soil);
  record.fe_de_preset = line.preset;
  const auto models = std::make_shared<tiers::ListedSurrogateModels>(
      std::vector<tiers::SurrogateModelRecord>{record});
  const tiers::FeDeOptions fe_de_options = tiers::FeDeOptions::Preset(line.preset);
  const tiers::FeDeTier fe_de(fe_de_options);
  for (double spread_scale : line.validate_spread_scales) {
    for (double pressure_floor_kpa : line.validate_pressure_floors_kpa) {
      tiers::FeAnnOptions options;
      options.fe_de = fe_de_options;
      options.return_after_steps = line.return_after_steps;
      // 1: the model's own (0 in the options); the envelope's distance threshold stays the model's.
      options.spread_threshold = spread_scale == 1.0 ? 0.0 : spread_scale * model_spread_threshold;
      options.pressure_floor_pa = 1e3 * pressure_floor_kpa;
      const tiers::FeAnnTier fe_ann(options, models);
      for (double load_n : line.validate_loads_n) {
        const TractionRequest request = RigRequest(line, load_n);
        if (references.count(load_n) == 0) {
          const auto start = std::chrono::steady_clock::now();
          references[load_n].run = fe_de.Run(request, {});
          references[load_n].seconds = Since(start);
        }
        const FeDeReference& reference = references[load_n];
        const auto start = std::chrono::steady_clock::now();
        const tiers::AnnRunReport ann = fe_ann.Run(request, {});
        const double seconds = Since(start);
        const auto& a = ann.curve.points;
        const auto& d = reference.run.curve.points;
        const tiers::CurveDifference worst =
            tiers::WorstDifference(ann.curve, reference.run.curve, request);
        std::printf("validate,%s,%g,%g,%.0f,%.1f,%.2f,%.1f,%.2f,%.2f,%d,%lld,%lld,%.2f,%.2f,%.2f\n",
                    architecture.c_str(), spread_scale, pressure_floor_kpa, load_n,
                    reference.seconds, seconds, reference.seconds / seconds, ann.network_seconds,
                    ann.fallback_seconds, ann.fallbacks, static_cast<long long>(ann.returns),
                    static_cast<long long>(ann.stress_returns), 100 * worst.drawbar_pull_over_w,
                    100 * worst.torque_over_rw, 100 * worst.sinkage_over_r);
        for (std::size_t k = 0; k < std::min(a.size(), d.size()); ++k) {
          std::printf("#   s %.2f: D %.1f (fe-de %.1f) N, T %.2f (%.2f) N m, z %.2f (%.2f) mm\n",
                      a[k].slip, a[k].drawbar_pull_n, d[k].drawbar_pull_n, a[k].torque_nm,
                      d[k].torque_nm, 1e3 * a[k].sinkage_m, 1e3 * d[k].sinkage_m);
        }
        std::fflush(stdout);
      }
    }
  }
}

// What every ensemble of a study is trained and measured on.
struct Study {
  SoilParameters soil;
  std::vector<StrainHistory> training, held_out;
  std::vector<std::string> held_out_names;
  // Of each held-out path, its differences on other packings (--packing-seeds; a rig path
  // replayed from its initial stress, tiers::ReplayedOnRve).
  std::vector<std::vector<tiers::PackingDifference>> held_out_packings;
  std::map<double, FeDeReference> references;  // fe-de curves by load
  std::string data_hash;                       // of `training` (HistoriesHash)
  // The soil's RVE, and where the held-out rig paths begin in `held_out` (its size: none).
  std::shared_ptr<const dem::rve::RveMaterial> rve;
  std::size_t first_rig_held_out = 0;
};

// One trained ensemble's row (training figures, held-out errors, evaluation cost), then, as asked,
// its files (--out), its registration (--register) and its fe-ann runs against fe-de
// (--validate-load-n).
void ReportEnsemble(const CommandLine& line, Study& study, const SurrogateEnsemble& ensemble,
                    const std::string& name, const TrainingOptions& options,
                    const std::vector<TrainingReport>& reports, double train_s,
                    const std::string& from_model) {
  double final_loss = 0;
  double final_rollout_loss = 0;
  for (const TrainingReport& report : reports) {
    final_loss += report.final_loss / reports.size();
    final_rollout_loss += report.final_rollout_loss / reports.size();
  }
  if (line.rollout_steps > 0) {
    std::fprintf(stderr, "%s: the rollout term over %d steps, last epoch, members' mean: %.3g\n",
                 name.c_str(), line.rollout_steps, final_rollout_loss);
  }
  std::printf("%s,%zu,%d,%lld,%.1f,%.3g,", name.c_str(), ensemble.size(), options.epochs,
              static_cast<long long>(reports.front().samples), train_s, final_loss);
  std::vector<double> held_out_errors;  // replayed once: the row and the record both show them
  for (const StrainHistory& history : study.held_out) {
    held_out_errors.push_back(ReplayError(ensemble, history));
    std::printf("%.2f,", 100 * held_out_errors.back());
  }
  const std::vector<SurrogateInput> batch = TimingBatch(study.training, 1000, ensemble.carried_variables());
  std::printf("%.2f\n",
              MicrosecondsPerPoint(batch.size(), [&] { ensemble.Answer(batch, false); }));
  // The held-out rig paths as the tier answers their points: the RVE where the ensemble flags, at
  // each spread threshold validated (--validate-spread-scales; the model's own distance threshold).
  // The thresholds are the ensemble's own, so they are set on one copy of it, read back once.
  std::optional<SurrogateEnsemble> rescaled;
  if (study.first_rig_held_out < study.held_out.size() &&
      (line.validate_spread_scales != std::vector<double>{1.0} ||
       line.validate_pressure_floors_kpa != std::vector<double>{0.0})) {
    const std::string copy_directory =
        (std::filesystem::temp_directory_path() /
         ("gonogo_ann_guard_" + std::to_string(::getpid()) + "_" + name))
            .string();
    ensemble.Save(copy_directory);
    rescaled = SurrogateEnsemble::Load(copy_directory);
    std::filesystem::remove_all(copy_directory);
  }
  for (double spread_scale : line.validate_spread_scales) {
    for (double pressure_floor_kpa : line.validate_pressure_floors_kpa) {
      if (rescaled) {
        rescaled->SetThresholds(ensemble.distance_threshold(),
                                spread_scale * ensemble.spread_threshold());
        rescaled->SetPressureFloor(1e3 * pressure_floor_kpa);
      }
      for (std::size_t k = study.first_rig_held_out; k < study.held_out.size(); ++k) {
        const tiers::GuardedReplay guarded = tiers::ReplayGuarded(
            rescaled ? *rescaled : ensemble, study.rve, study.held_out[k], line.return_after_steps);
        std::printf(
            "# %s: %s, as the fe-ann tier answers its point (spread threshold x %g, pressure "
            "floor %g kPa) %.2f %% (",
            name.c_str(), study.held_out_names[k].c_str(), spread_scale, pressure_floor_kpa,
            100 * guarded.error);
        if (guarded.fallbacks == 0) {
          std::printf("no fallback");
        } else {
          std::printf("fell back after %lld of %zu increments, %d fallbacks, %lld returns",
                      static_cast<long long>(guarded.first_fallback_step),
                      study.held_out[k].steps(), guarded.fallbacks,
                      static_cast<long long>(guarded.returns));
        }
        std::printf("%s%s); open-loop %.2f %%\n",
                    guarded.stopped_reason.empty() ? "" : ", stopped: ",
                    guarded.stopped_reason.c_str(), 100 * held_out_errors[k]);
      }
    }
  }
  const double ratio = ensemble.envelope().least_principal_ratio;
  std::printf("# %s: principal stresses capped at %g Pa (the training data's most tensile) and "
              "kept within the cone min/max principal compression >= %.3f (friction angle "
              "%.1f deg)\n",
              name.c_str(), ensemble.envelope().tensile_limit_pa, ratio,
              std::asin((1 - ratio) / (1 + ratio)) * 180 / M_PI);
  std::fflush(stdout);
  if (!line.out.empty()) ensemble.Save(line.out + "/" + name);
  if (!line.register_data_dir.empty()) {
    const tiers::SurrogateRegistry registry(
        (std::filesystem::path(line.register_data_dir) / "models").string());
    tiers::RegisteredSurrogate record;
    record.id = registry.NewId(line.soil, name);
    record.soil_name = line.soil;
    record.soil_parameters = CanonicalText(study.soil);
    record.fe_de_preset = line.preset;
    record.architecture = ensemble.member(0).architecture();
    record.members = static_cast<int>(ensemble.size());
    record.data_hash = study.data_hash;
    record.samples = reports.front().samples;
    record.distance_threshold = ensemble.distance_threshold();
    record.spread_threshold = ensemble.spread_threshold();
    record.tensile_limit_pa = ensemble.envelope().tensile_limit_pa;
    record.least_principal_ratio = ensemble.envelope().least_principal_ratio;
    for (std::size_t k = 0; k < study.held_out.size(); ++k) {
      record.held_out.push_back(
          {study.held_out_names[k], held_out_errors[k], study.held_out_packings[k]});
      record.worst_held_out_error = std::max(record.worst_held_out_error, held_out_errors[k]);
    }
    record.training_seconds = train_s;
    record.training = tiers::TrainingText(options);
    record.walk_share = line.walk_share;
    record.from_model = from_model;
    record.code_version = GONOGO_VERSION;
    record.created_unix_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count();
    const tiers::RegisteredSurrogate registered = registry.Register(record, ensemble);
    std::printf("# registered model %s in %s\n", registered.id.c_str(),
                registered.directory.c_str());
    std::fflush(stdout);
  }
  if (!line.validate_loads_n.empty()) {
    const std::string directory =
        line.out.empty() ? (std::filesystem::temp_directory_path() /
                            ("gonogo_ann_" + std::to_string(::getpid()) + "_" +
                             name))
                               .string()
                         : line.out + "/" + name;
    if (line.out.empty()) ensemble.Save(directory);
    std::printf(
        "validate,architecture,spread_scale,pressure_floor_kpa,load_n,fe_de_s,fe_ann_s,speedup,"
        "network_s,"
        "fallback_s,fallbacks,returns,stress_returns,worst_D_pct_W,worst_T_pct_rW,worst_z_pct_r\n");
    Validate(line, directory, name, ensemble.spread_threshold(), study.soil, study.references);
    if (line.out.empty()) std::filesystem::remove_all(directory);
  }
}

// The mean stress p (compression positive) and the deviatoric stress q (von Mises) of a
// tension-positive Cauchy stress, Pa.
struct MeanAndDeviatoric {
  double p = 0, q = 0;
};
MeanAndDeviatoric StressInvariants(const Matrix3& sigma) {
  const double p = -sigma.trace() / 3;
  const Matrix3 deviator = sigma + p * Matrix3::Identity();
  return {p, std::sqrt(1.5 * deviator.squaredNorm())};
}

// The RVE at rest: settled isotropically at `line.rest_kpa`, optionally compressed along z by
// `line.rest_axial_strain` with the lateral strains held (oedometric, in 20 increments: a
// deviatoric load like a point's under a wheel), then `line.rest_steps` zero increments, each
// committed. Prints the mean stress p and the deviatoric q (von Mises) every tenth zero step:
// what an FE point held still would see (a surrogate anchored at rest sees nothing).
int RunRestTest(const CommandLine& line, const dem::rve::RveMaterial& rve) {
  dem::rve::Rve settled = rve.initial();
  settled.SettleIsotropic(line.rest_kpa * 1e3);
  std::unique_ptr<material::MaterialState> state = rve.RestoreState(settled.Save());
  std::printf("# rest test, %s, preset %s: settled at %g kPa, compressed by %g along z (lateral "
              "strains held), then %d zero increments\n",
              line.soil.c_str(), line.preset.c_str(), line.rest_kpa, line.rest_axial_strain,
              line.rest_steps);
  const auto step_once = [&](const Matrix3& increment, const std::string& what) {
    material::PointIncrement point;
    point.committed = state.get();
    point.displacement_gradient_increment = increment;
    std::vector<material::PointResponse> answer = rve.Update({point}, false);
    if (answer.at(0).status != material::UpdateStatus::kOk) {
      throw NumericalError(what + ": " + answer.at(0).reason);
    }
    state = std::move(answer.at(0).state);
    return answer.at(0).stress_pa;
  };
  constexpr int kLoadingSteps = 20;
  Matrix3 compression = Matrix3::Zero();
  compression(2, 2) = -line.rest_axial_strain / kLoadingSteps;
  if (line.rest_axial_strain > 0) {
    for (int step = 0; step < kLoadingSteps; ++step) {
      step_once(compression, "loading step " + std::to_string(step));
    }
  }
  std::printf("step,p_pa,q_pa,p_change_pct,q_change_pct\n");
  double first_p = 0, first_q = 0;
  for (int step = 0; step <= line.rest_steps; ++step) {
    const auto [p, q] =
        StressInvariants(step_once(Matrix3::Zero(), "rest step " + std::to_string(step)));
    if (step == 0) first_p = p, first_q = q;
    if (step % 10 == 0 || step == line.rest_steps) {
      std::printf("%d,%.1f,%.1f,%.3f,%.3f\n", step, p, q, 100 * (p - first_p) / first_p,
                  first_q > 0 ? 100 * (q - first_q) / first_q : 0.0);
    }
  }
  return 0;
}

// The RVE's answer against the size of its increments: one laboratory path (the recipe's strain:
// 5 % axial for a triaxial, 10 % shear for a simple shear) at `line.increment_kpa`, taken in each
// of `line.increment_steps` steps. A quasi-static packing answers the same whatever the step; the
// RVE spreads each increment over at least min_steps_per_increment DE steps and relaxes it for
// relax_steps, so a path of many small increments (an FE point's) gets more DE steps per unit of
// strain than one of few large ones (a laboratory path's). Prints the mean stress p and the
// deviatoric q (von Mises) at fractions of the path, per step count.
int RunIncrementStudy(const CommandLine& line, const dem::rve::RveMaterial& rve) {
  LabPathSpec spec;
  spec.path = ParseLabPath(line.increment_path, "--increment-path");
  spec.pressure_pa = line.increment_kpa * 1e3;
  spec.max_strain = spec.path == LabPath::kSimpleShear ? 0.1 : 0.05;
  std::printf("# increment study, %s, preset %s: %s at %g kPa to %g strain\n", line.soil.c_str(),
              line.preset.c_str(), line.increment_path.c_str(), line.increment_kpa,
              spec.max_strain);
  std::printf("steps,fraction,strain,p_pa,q_pa,seconds\n");
  DriverOptions options;
  options.relative_tolerance = 0.02;  // as the training paths (tiers::RunLabPaths)
  for (int steps : line.increment_steps) {
    spec.steps = steps;
    spec.Validate("--increment-steps.");
    const auto start = std::chrono::steady_clock::now();
    const StrainHistory history = RunLabPath(rve, spec, options);
    const double seconds = Since(start);
    if (!history.stopped_reason.empty()) {
      std::printf("# %d steps stopped: %s\n", steps, history.stopped_reason.c_str());
    }
    const int settle = spec.settle_steps;  // recorded first
    for (double fraction : {0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0}) {
      const int step = settle + static_cast<int>(std::lround(fraction * steps)) - 1;
      if (step < 0 || step >= static_cast<int>(history.stresses_pa.size())) continue;
      const auto [p, q] = StressInvariants(
          material::VoigtToStress(history.stresses_pa[static_cast<std::size_t>(step)]));
      std::printf("%d,%.2f,%.4f,%.1f,%.1f,%.2f\n", steps, fraction, fraction * spec.max_strain, p,
                  q, seconds);
    }
  }
  return 0;
}

int Run(const CommandLine& line) {
  const tiers::CatalogueEntry* entry =
      tiers::BuiltinSoilCatalogue().Find(line.soil, dem::rve::kRveSoilModel);
  if (entry == nullptr) throw InputError("--soil", "no dem-hertz-mindlin soil '" + line.soil + "'");
  for (const std::string& text : line.architectures) {  // refused before any path runs
    if (text.rfind("gru", 0) == 0) {
      GruWidth(text);
      if (!line.carried.empty()) {
        throw InputError("--carry", "a GRU carries its hidden state, not internal variables");
      }
    } else {
      ParseArchitecture(text);
    }
  }
  MlpArchitecture carrying;
  carrying.carried_variables = line.carried;
  try {
    carrying.Validate("");
  } catch (const InputError& e) {  // named by the flag that gave it
    throw InputError("--carry", std::string(e.what()).substr(e.field().size() + 2));
  }
  tiers::RveVariables(line.carried, "--carry");  // refused before any path runs
  std::optional<SurrogateEnsemble> from;  // loaded before any path runs
  if (!line.from_model_dir.empty()) from = SurrogateEnsemble::Load(line.from_model_dir);
  const tiers::FeDeOptions preset = tiers::FeDeOptions::Preset(line.preset);
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(entry->parameters, preset.numerics, "soil"));
  if (line.rest_kpa > 0) return RunRestTest(line, *rve);
  if (line.increment_kpa > 0) return RunIncrementStudy(line, *rve);
  const auto start = std::chrono::steady_clock::now();
  tiers::SurrogateRecipe recipe;
  recipe.steps = line.steps;
  recipe.walks = line.walks;
  recipe.held_out_walks = line.held_out_walks;
  if (!line.pressures_kpa.empty()) {
    recipe.pressures_pa.clear();
    for (double kpa : line.pressures_kpa) recipe.pressures_pa.push_back(kpa * 1e3);
  }
  recipe.Validate("");
  std::vector<tiers::NamedLabPath> training_paths = tiers::TrainingPaths(recipe);
  // Only the training walks persist; the held-out walks stay the yardstick every model is read by.
  for (tiers::NamedLabPath& path : training_paths) {
    if (path.spec.path == ann::LabPath::kRandomWalk) {
      path.spec.walk_persistence = line.walk_persistence;
    }
  }
  const std::vector<tiers::NamedLabPath> held_out_paths = tiers::HeldOutPaths(recipe);
  const InternalVariables internal = line.record_fabric || !line.carried.empty()
                                         ? tiers::RveFabricVariables()
                                         : InternalVariables{};
  const std::vector<StrainHistory> training =
      RunPaths(*rve, training_paths, line.threads, "training", internal);
  const std::vector<StrainHistory> held_out =
      RunPaths(*rve, held_out_paths, line.threads, "held-out", internal);
  const double generation_s = Since(start);
  std::vector<std::vector<tiers::PackingDifference>> held_out_packings(held_out.size());
  if (!line.packing_seeds.empty()) {
    held_out_packings =
        PrintPackingSpread(line, entry->parameters, preset, held_out_paths, held_out);
  }
  std::vector<StrainHistory> training_all = training;
  std::vector<StrainHistory> held_out_all = held_out;
  std::vector<std::string> held_out_names;
  for (const tiers::NamedLabPath& path : held_out_paths) held_out_names.push_back(path.name);
  std::map<double, FeDeReference> references;
  if (line.rig_load_n > 0) {
    const auto rig_start = std::chrono::steady_clock::now();
    const tiers::RecordedRigRun recorded = tiers::RecordRigPaths(
        tiers::FeDeTier(preset), RigRequest(line, line.rig_load_n), {}, internal);
    references[line.rig_load_n] = {recorded.run, Since(rig_start)};
    const std::vector<StrainHistory> rig_training =
        tiers::EvenlySpread(recorded.paths, line.rig_points, 0);
    const int rig_held_out = std::max(1, line.rig_points / 2);
    const std::vector<StrainHistory> rig_checks = tiers::EvenlySpread(
        recorded.paths, rig_held_out,
        static_cast<int>(recorded.paths.size() / (2 * std::max(1, line.rig_points))) + 1);
    training_all.insert(training_all.end(), rig_training.begin(), rig_training.end());
    for (std::size_t k = 0; k < rig_checks.size(); ++k) {
      held_out_all.push_back(rig_checks[k]);
      held_out_names.push_back("rig point " + std::to_string(k + 1));
      // Its floor: the path replayed from its initial stress on each other packing.
      std::vector<tiers::PackingDifference> floors;
      for (unsigned seed : line.packing_seeds) {
        const StrainHistory other =
            tiers::ReplayedOnRve(PackedFrom(entry->parameters, preset, seed), rig_checks[k]);
        floors.push_back({seed, HistoryDifference(other, rig_checks[k])});
      }
      if (!floors.empty()) {
        std::printf("# %s on the other packings: median %.2f %% (", held_out_names.back().c_str(),
                    100 * tiers::PackingFloor(floors));
        for (const tiers::PackingDifference& floor : floors) {
          std::printf("%s%u %.2f %%", &floor == &floors.front() ? "" : ", ", floor.packing_seed,
                      100 * floor.difference);
        }
        std::printf(")\n");
      }
      held_out_packings.push_back(std::move(floors));
    }
    std::printf("# rig run at %.0f N (fe-de, %s): %d elements, %d FE steps, %.1f s; %zu points' "
                "paths recorded, %zu in training, %zu held out\n",
                line.rig_load_n, line.preset.c_str(), recorded.run.elements,
                recorded.run.fe_steps, Since(rig_start), recorded.paths.size(),
                rig_training.size(), rig_checks.size());
  }
  std::size_t steps = 0;
  for (const StrainHistory& history : training_all) steps += history.steps();
  std::printf("# soil %s (RVEs of %g grains), preset %s: %zu training paths (%zu steps), %zu "
              "held-out, generated in %.1f s on %d threads\n",
              line.soil.c_str(), entry->parameters.Get("grains_per_rve"), line.preset.c_str(),
              training_all.size(), steps, held_out_all.size(), generation_s, line.threads);
  if (!line.out.empty()) {
    std::filesystem::create_directories(line.out);
    WriteHistoriesNpy(line.out + "/training.npy", training_all);
    WriteHistoriesNpy(line.out + "/held_out.npy", held_out_all);
  }
  Study study{entry->parameters,
              training_all,
              held_out_all,
              held_out_names,
              held_out_packings,
              references,
              tiers::HistoriesHash(training_all),
              rve,
              held_out.size()};
  std::vector<double> history_weights;
  if (line.walk_share > 0) {
    // Walks and the rest weighed so that the walks' steps carry walk_share of the loss (the rig's
    // recorded paths, after the recipe's, count as the rest).
    history_weights = tiers::WalkShareWeights(training_paths, training_all, line.walk_share);
    double walk_steps = 0, other_steps = 0, walk_weight = 1;
    for (std::size_t k = 0; k < training_all.size(); ++k) {
      const bool walk =
          k < training_paths.size() && training_paths[k].spec.path == ann::LabPath::kRandomWalk;
      (walk ? walk_steps : other_steps) += static_cast<double>(training_all[k].steps());
      if (walk) walk_weight = history_weights[k];
    }
    std::printf("# the walks' %.0f steps weigh %.3g each, the other %.0f steps 1\n", walk_steps,
                walk_weight, other_steps);
  }
  std::printf("architecture,members,epochs,samples,train_s,mean_final_loss,");
  for (const std::string& name : held_out_names) std::printf("%s %%,", name.c_str());
  std::printf("us_per_point_batch_1000\n");
  if (from) {
    // Transfer learning: the given ensemble fine-tuned on this study's data; the rows below train
    // from scratch on the same data, for comparison.
    const SurrogateEnsemble& base = *from;
    const std::string base_name =
        std::filesystem::path(line.from_model_dir).lexically_normal().filename().string();
    TrainingOptions options = StudyTraining(line, history_weights);
    options.batch_size = 64;
    options.learning_rate = line.tune_learning_rate;
    const auto train_start = std::chrono::steady_clock::now();
    std::vector<TrainingReport> reports;
    const SurrogateEnsemble tuned =
        SurrogateEnsemble::FineTune(base, study.training, options, &reports);
    ReportEnsemble(line, study, tuned, base.member(0).architecture() + "-from-" + base_name,
                   options, reports, Since(train_start), base_name);
  }
  for (const std::string& text : line.architectures) {
    if (text.rfind("gru", 0) == 0) {
      RunRecurrent(line, text, training_all, held_out_all, history_weights);
      continue;
    }
    MlpArchitecture architecture = ParseArchitecture(text);
    architecture.anchored = !line.unanchored;
    architecture.pressure_reference_pa = line.pressure_reference_pa;
    architecture.carried_variables = line.carried;
    TrainingOptions options = StudyTraining(line, history_weights);
    options.batch_size = 64;
    const auto train_start = std::chrono::steady_clock::now();
    std::vector<TrainingReport> reports;
    const SurrogateEnsemble ensemble =
        SurrogateEnsemble::Train(training_all, architecture, options, line.members, &reports);
    const double train_s = Since(train_start);
    ReportEnsemble(line, study, ensemble, architecture.Describe(), options, reports, train_s, "");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine line;
  CLI::App app("gonogo-ann: the stress surrogate's study on a soil's own DE RVE");
  app.add_option("--soil", line.soil, "dem-hertz-mindlin soil of the catalogue")
      ->capture_default_str();
  app.add_option("--preset", line.preset, "fe-de preset whose RVE numerics the paths use")
      ->capture_default_str();
  app.add_option("--steps", line.steps, "steps per path after settling")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--held-out-walks", line.held_out_walks,
                 "random walks in the held-out set (seeds 1001, 1002, ...)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--walks", line.walks, "random walks in the training set")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("--pressures-kpa", line.pressures_kpa,
                 "confining pressures of the training paths, kPa, increasing (default: "
                 "2.5 5 10 20 40 80)");
  app.add_option("--architecture", line.architectures,
                 "MLP hidden widths joined by x (64x64; the seed's 600x600x600x600x600x600x600), "
                 "or a GRU and its width (gru32; one network, not an ensemble)")
      ->capture_default_str();
  app.add_flag("--unanchored", line.unanchored,
               "MLPs without the at-rest anchor (d_sigma(0) = 0; stress_surrogate.h)");
  app.add_option("--pressure-scaled", line.pressure_reference_pa,
                 "MLPs that see the stress relative to s = max(p, 0) + this reference pressure "
                 "(Pa) and answer d_sigma / s (stress_surrogate.h); 0: unscaled")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--rig-load-n", line.rig_load_n,
                 "record the paths of an fe-de rig run of the preset at this wheel load (N) and "
                 "train and check on them too (seed 000's step 2); 0: none")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--rig-diameter-m", line.rig_diameter_m, "the rig wheel's diameter, m")
      ->check(CLI::Range(0.05, 5.0))
      ->capture_default_str();
  app.add_option("--rig-width-m", line.rig_width_m, "the rig wheel's width, m")
      ->check(CLI::Range(0.01, 2.0))
      ->capture_default_str();
  app.add_option("--rig-points", line.rig_points,
                 "recorded points in the training set (half as many others held out)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_flag("--record-fabric", line.record_fabric,
               "the histories --out writes also record, per step, the RVE's coordination number, "
               "solid fraction and contact fabric (fabric_xx ... fabric_xy; trace 1): for "
               "studies of what a network might carry (solvers/ann/studies/fabric.py)");
  app.add_option("--carry", line.carried,
                 "internal variables of the RVE the MLPs carry as further inputs and outputs "
                 "(coordination_number, solid_fraction; stress_surrogate.h); the histories record "
                 "them")
      ->type_name("NAME");
  app.add_option("--return-after-steps", line.return_after_steps,
                 "--validate-load-n's fe-ann runs: a fallen-back point returns to the network "
                 "after this many FE steps in a row its ensemble would not have flagged (0: never)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--packing-seeds", line.packing_seeds,
                 "also run the held-out paths on the soil's RVE packed from these seeds (the "
                 "study's packing is the preset's, seed 1; a held-out rig path replayed from its "
                 "initial stress) and print their stresses' difference "
                 "from the study's packing's, measured as a replay's error: the RVE's own spread, "
                 "the floor under a held-out error; with --register, in the model's record")
      ->check(CLI::PositiveNumber);
  app.add_option("--validate-load-n", line.validate_loads_n,
                 "run each MLP ensemble as the fe-ann tier on the rig at these loads (N) against "
                 "fe-de");
  app.add_option("--validate-spread-scales", line.validate_spread_scales,
                 "--validate-load-n's runs once at each of these multiples of the model's spread "
                 "threshold (below 1: more points fall back to the RVE)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--validate-pressure-floors-kpa", line.validate_pressure_floors_kpa,
                 "--validate-load-n's runs (and the held-out rig paths' guarded replays) once at "
                 "each of these pressure floors, kPa: a point whose mean compression is below "
                 "the floor falls back to the RVE (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--register", line.register_data_dir,
                 "register each MLP ensemble with its provenance in this gonogo-server data "
                 "directory (DATA_DIR/models), where the fe-ann tier finds it")
      ->type_name("DATA_DIR");
  app.add_option("--from", line.from_model_dir,
                 "transfer learning: also fine-tune this ensemble (a directory: DATA_DIR/models/ID "
                 "or --out's) on the study's data, beside the architectures trained from scratch")
      ->type_name("MODEL_DIR");
  app.add_option("--tune-learning-rate", line.tune_learning_rate,
                 "Adam's learning rate when fine-tuning")
      ->check(CLI::Range(1e-8, 0.5))
      ->capture_default_str();
  app.add_option("--rest-kpa", line.rest_kpa,
                 "only the rest test: the RVE settled at this pressure (kPa), then --rest-steps "
                 "zero increments; prints its stress as it drifts")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--rest-axial-strain", line.rest_axial_strain,
                 "the rest test's compression along z (lateral strains held) before the zero "
                 "increments: a deviatoric load")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  app.add_option("--rest-steps", line.rest_steps, "zero increments of the rest test")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--increment-kpa", line.increment_kpa,
                 "only the increment-size study: --increment-path at this pressure (kPa) taken "
                 "in each of --increment-steps steps; prints p and q along each")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--increment-path", line.increment_path,
                 "the increment study's laboratory path (triaxial, simple-shear, ...)")
      ->capture_default_str();
  app.add_option("--increment-steps", line.increment_steps, "the increment study's step counts")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--members", line.members, "ensemble members")
      ->check(CLI::Range(3, 64))
      ->capture_default_str();
  app.add_option("--epochs", line.epochs, "training epochs")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--path-stress-weighting", line.path_stress_weighting,
                 "each training step's squared error weighed by its path's mean |sigma| to the "
                 "power -2x: 0 every step alike, 1 relative to the path's stress (MLPs)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--rollout-steps", line.rollout_steps,
                 "a rollout term in the loss: windows of this many steps replayed on the "
                 "network's own stresses, their error relative to the path's stress (MLPs; 0: "
                 "none)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--rollout-weight", line.rollout_weight, "the rollout term's weight in the loss")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--stress-noise", line.stress_noise,
                 "training noise on the stress before each step, its standard deviation a "
                 "fraction of the path's mean |sigma| (MLPs; 0: none)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--noise-correction", line.noise_correction,
                 "the share of the noise each step's target takes back: 1 ends the step on the "
                 "recorded stress, 0 as far off as it began")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--walk-share", line.walk_share,
                 "the random walks' share of the training loss (their steps weighed to give it); "
                 "0: their share of the steps")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  app.add_option("--walk-persistence", line.walk_persistence,
                 "the training walks' correlation of one step's direction with the last's (0: "
                 "drawn afresh; 0.9: loading on for about 10 steps); held-out walks stay at 0")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  app.add_option("--training-seed", line.training_seed,
                 "the first member's seed of weights and batch order (member k: seed + k)")
      ->capture_default_str();
  app.add_option("--threads", line.threads, "OpenMP threads generating the paths")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--out", line.out, "directory for the histories (.npy) and the ensembles");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return Run(line);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gonogo-ann: %s\n", e.what());
    return 1;
  }
}
