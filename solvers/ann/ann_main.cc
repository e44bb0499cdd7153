// gonogo-ann: the surrogate's study on a soil's own DE RVE, from the command line.
//
//   gonogo-ann --soil seed000_sand_rve100 [--preset ci] [--steps 50] [--walks 16]
//              [--pressures-kpa 2.5 5 ...] [--architecture 64x64 ...] [--members 3]
//              [--carry coordination_number] [--epochs 300] [--threads T] [--out DIR]
//
// Runs the laboratory paths of the fe-ann recipe (solvers/tiers/surrogate_training.h) on the
// soil's RVE, with the RVE numerics of the fe-de preset: a training set and a held-out set (other
// pressures, another seed), on OpenMP threads, one path per thread. Trains an ensemble per MLP
// --architecture (one network per GRU: gru32) and prints, per architecture, the training figures,
// each held-out path's replay error (the stress error relative to the path's mean |sigma|) and
// the evaluation cost; with --rig-load-n, each held-out rig path also as the fe-ann tier answers
// its point (tiers::ReplayGuarded: the RVE from where the ensemble flags). With --out, writes the
// histories (training.npy, held_out.npy with their .columns.txt) and each ensemble
// (DIR/<architecture>/). The options: study_command_line.h. --rest-kpa and --increment-kpa run
// only a study of the RVE alone instead (rve_point_studies.h).
#include <omp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/rve_point_studies.h"
#include "solvers/ann/study_command_line.h"
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
    const StudyCommandLine& line, const SoilParameters& soil, const tiers::FeDeOptions& preset,
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
TrainingOptions StudyTraining(const StudyCommandLine& line,
                              const std::vector<double>& history_weights) {
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

void RunRecurrent(const StudyCommandLine& line, const std::string& text,
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

TractionRequest RigRequest(const StudyCommandLine& line, double load_n) {
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
void Validate(const StudyCommandLine& line, const std::string& model_directory,
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
  // The recipe's training paths, the first of `training` (the rig's recorded paths follow).
  std::vector<tiers::NamedLabPath> training_paths;
};

// One trained ensemble's row (training figures, held-out errors, evaluation cost), then, as asked,
// its files (--out), its registration (--register) and its fe-ann runs against fe-de
// (--validate-load-n).
void ReportEnsemble(const StudyCommandLine& line, Study& study, const SurrogateEnsemble& ensemble,
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

// The paths of an fe-de rig run at --rig-load-n (seed 000's step 2) added to the study:
// --rig-points of them, evenly spread over the bin, to its training and half as many others to its
// held-out paths, each with its floor (the path replayed from its initial stress on each of
// --packing-seeds); the run's curve becomes the study's fe-de reference at that load. With
// --rig-held-out-as N the held-out paths are those of N training points, and the training points
// are spread over the rest.
void AddRigPaths(const StudyCommandLine& line, const tiers::FeDeOptions& preset,
                 const InternalVariables& internal, Study& study) {
  const auto start = std::chrono::steady_clock::now();
  const tiers::RecordedRigRun recorded = tiers::RecordRigPaths(
      tiers::FeDeTier(preset), RigRequest(line, line.rig_load_n), {}, internal);
  study.references[line.rig_load_n] = {recorded.run, Since(start)};
  const std::size_t paths = recorded.paths.size();
  const int held_out_as = line.rig_held_out_as > 0 ? line.rig_held_out_as : line.rig_points;
  const std::vector<std::size_t> held_out =
      tiers::EvenlySpreadIndices(paths, std::max(1, held_out_as / 2),
                                 tiers::RigHeldOutOffset(static_cast<int>(paths), held_out_as));
  std::vector<std::size_t> trainable(paths);
  std::iota(trainable.begin(), trainable.end(), std::size_t{0});
  if (line.rig_held_out_as > 0) {
    trainable.erase(std::remove_if(trainable.begin(), trainable.end(),
                                   [&](std::size_t index) {
                                     return std::find(held_out.begin(), held_out.end(), index) !=
                                            held_out.end();
                                   }),
                    trainable.end());
  }
  std::vector<StrainHistory> rig_training, rig_checks;
  std::string indices = "training";
  for (std::size_t k : tiers::EvenlySpreadIndices(trainable.size(), line.rig_points, 0)) {
    rig_training.push_back(recorded.paths[trainable[k]]);
    indices += " " + std::to_string(trainable[k]);
  }
  indices += ", held out";
  for (std::size_t index : held_out) {
    rig_checks.push_back(recorded.paths[index]);
    indices += " " + std::to_string(index);
  }
  study.training.insert(study.training.end(), rig_training.begin(), rig_training.end());
  for (std::size_t k = 0; k < rig_checks.size(); ++k) {
    study.held_out.push_back(rig_checks[k]);
    study.held_out_names.push_back("rig point " + std::to_string(k + 1));
    std::vector<tiers::PackingDifference> floors;
    for (unsigned seed : line.packing_seeds) {
      const StrainHistory other =
          tiers::ReplayedOnRve(PackedFrom(study.soil, preset, seed), rig_checks[k]);
      floors.push_back({seed, HistoryDifference(other, rig_checks[k])});
    }
    if (!floors.empty()) {
      std::printf("# %s on the other packings: median %.2f %% (",
                  study.held_out_names.back().c_str(), 100 * tiers::PackingFloor(floors));
      for (const tiers::PackingDifference& floor : floors) {
        std::printf("%s%u %.2f %%", &floor == &floors.front() ? "" : ", ", floor.packing_seed,
                    100 * floor.difference);
      }
      std::printf(")\n");
    }
    study.held_out_packings.push_back(std::move(floors));
  }
  std::printf(
      "# rig run at %.0f N (fe-de, %s): %d elements, %d FE steps, %.1f s; %zu points' "
      "paths recorded, %zu in training, %zu held out (the points' indices: %s)\n",
      line.rig_load_n, line.preset.c_str(), recorded.run.elements, recorded.run.fe_steps,
      Since(start), recorded.paths.size(), rig_training.size(), rig_checks.size(), indices.c_str());
}

// The study's data: the recipe's laboratory paths on the soil's RVE (training and held out), with
// --packing-seeds each held-out path's floor, and with --rig-load-n the rig's paths
// (AddRigPaths); written to --out.
Study GatherStudy(const StudyCommandLine& line, const SoilParameters& soil,
                  const tiers::FeDeOptions& preset,
                  const std::shared_ptr<const dem::rve::RveMaterial>& rve) {
  const auto start = std::chrono::steady_clock::now();
  tiers::SurrogateRecipe recipe;
  recipe.steps = line.steps;
  recipe.walks = line.walks;
  recipe.held_out_walks = line.held_out_walks;
  if (!line.pressures_kpa.empty()) {
    recipe.pressures_pa.clear();
    for (double kpa : line.pressures_kpa) recipe.pressures_pa.push_back(kpa * 1e3);
  }
  recipe.ValidateAsOptions();
  Study study;
  study.soil = soil;
  study.rve = rve;
  study.training_paths = tiers::TrainingPaths(recipe);
  // Only the training walks persist; the held-out walks stay the yardstick every model is read by.
  for (tiers::NamedLabPath& path : study.training_paths) {
    if (path.spec.path == ann::LabPath::kRandomWalk) {
      path.spec.walk_persistence = line.walk_persistence;
    }
  }
  const std::vector<tiers::NamedLabPath> held_out_paths = tiers::HeldOutPaths(recipe);
  const InternalVariables internal = line.record_fabric || !line.carried.empty()
                                         ? tiers::RveFabricVariables()
                                         : InternalVariables{};
  study.training = RunPaths(*rve, study.training_paths, line.threads, "training", internal);
  study.held_out = RunPaths(*rve, held_out_paths, line.threads, "held-out", internal);
  const double generation_s = Since(start);
  for (const tiers::NamedLabPath& path : held_out_paths) study.held_out_names.push_back(path.name);
  study.held_out_packings.resize(study.held_out.size());
  if (!line.packing_seeds.empty()) {
    study.held_out_packings =
        PrintPackingSpread(line, soil, preset, held_out_paths, study.held_out);
  }
  study.first_rig_held_out = study.held_out.size();
  if (line.rig_load_n > 0) AddRigPaths(line, preset, internal, study);
  study.data_hash = tiers::HistoriesHash(study.training);
  std::size_t steps = 0;
  for (const StrainHistory& history : study.training) steps += history.steps();
  std::printf(
      "# soil %s (RVEs of %g grains), preset %s: %zu training paths (%zu steps), %zu "
      "held-out, generated in %.1f s on %d threads\n",
      line.soil.c_str(), soil.Get("grains_per_rve"), line.preset.c_str(), study.training.size(),
      steps, study.held_out.size(), generation_s, line.threads);
  if (!line.out.empty()) {
    std::filesystem::create_directories(line.out);
    WriteHistoriesNpy(line.out + "/training.npy", study.training);
    WriteHistoriesNpy(line.out + "/held_out.npy", study.held_out);
  }
  return study;
}

int Run(const StudyCommandLine& line) {
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
  if (line.rig_weight != 1 && line.rig_load_n <= 0) {
    throw InputError("--rig-weight", "weighs the rig's recorded paths: give --rig-load-n too");
  }
  if (line.rig_held_out_as > 0 && line.rig_load_n <= 0) {
    throw InputError("--rig-held-out-as",
                     "chooses among the rig's recorded paths: give --rig-load-n too");
  }
  tiers::RveVariables(line.carried, "--carry");  // refused before any path runs
  std::optional<SurrogateEnsemble> from;         // loaded before any path runs
  if (!line.from_model_dir.empty()) from = SurrogateEnsemble::Load(line.from_model_dir);
  const IncrementStudyOptions increment_study{
      line.increment_kpa, ParseLabPath(line.increment_path, "--increment-path"),
      line.increment_steps};  // refused before the RVE is packed
  const tiers::FeDeOptions preset = tiers::FeDeOptions::Preset(line.preset);
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(entry->parameters, preset.numerics, "soil"));
  const std::string label = line.soil + ", preset " + line.preset;
  if (line.rest_kpa > 0) {
    RunRestTest(*rve, {line.rest_kpa, line.rest_axial_strain, line.rest_steps}, label);
    return 0;
  }
  if (line.increment_kpa > 0) {
    RunIncrementStudy(*rve, increment_study, label);
    return 0;
  }
  Study study = GatherStudy(line, entry->parameters, preset, rve);
  std::vector<double> history_weights;
  if (line.walk_share > 0) {
    // Walks and the rest weighed so that the walks' steps carry walk_share of the loss (the rig's
    // recorded paths, after the recipe's, count as the rest).
    history_weights =
        tiers::WalkShareWeights(study.training_paths, study.training, line.walk_share);
    double walk_steps = 0, other_steps = 0, walk_weight = 1;
    for (std::size_t k = 0; k < study.training.size(); ++k) {
      const bool walk = k < study.training_paths.size() &&
                        study.training_paths[k].spec.path == ann::LabPath::kRandomWalk;
      (walk ? walk_steps : other_steps) += static_cast<double>(study.training[k].steps());
      if (walk) walk_weight = history_weights[k];
    }
    std::printf("# the walks' %.0f steps weigh %.3g each, the other %.0f steps 1\n", walk_steps,
                walk_weight, other_steps);
  }
  if (line.rig_weight != 1) {
    // The rig's recorded paths follow the recipe's in `training` (AddRigPaths).
    history_weights.resize(study.training.size(), 1.0);
    double rig_steps = 0;
    for (std::size_t k = study.training_paths.size(); k < study.training.size(); ++k) {
      history_weights[k] *= line.rig_weight;
      rig_steps += static_cast<double>(study.training[k].steps());
    }
    std::printf("# the rig's %.0f training steps weigh %.3g each\n", rig_steps, line.rig_weight);
  }
  std::printf("architecture,members,epochs,samples,train_s,mean_final_loss,");
  for (const std::string& name : study.held_out_names) std::printf("%s %%,", name.c_str());
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
      RunRecurrent(line, text, study.training, study.held_out, history_weights);
      continue;
    }
    MlpArchitecture architecture = ParseArchitecture(text);
    architecture.anchored = !line.unanchored;
    architecture.homogeneous_term = line.hybrid;
    architecture.previous_direction = line.previous_direction;
    architecture.pressure_reference_pa = line.pressure_reference_pa;
    architecture.carried_variables = line.carried;
    TrainingOptions options = StudyTraining(line, history_weights);
    options.batch_size = 64;
    const auto train_start = std::chrono::steady_clock::now();
    std::vector<TrainingReport> reports;
    const SurrogateEnsemble ensemble =
        SurrogateEnsemble::Train(study.training, architecture, options, line.members, &reports);
    const double train_s = Since(train_start);
    ReportEnsemble(line, study, ensemble, architecture.Describe(), options, reports, train_s, "");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  StudyCommandLine line;
  CLI::App app("gonogo-ann: the stress surrogate's study on a soil's own DE RVE");
  AddStudyOptions(app, line);
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
