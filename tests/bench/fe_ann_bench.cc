// gonogo-bench-fe-ann: the fe-ann tier's figures (issue "FE-ANN tier", benchmark).
//
//   gonogo-bench-fe-ann [--soil seed000_sand_rve100] [--preset tiny] [--steps 40] [--walks 12]
//                       [--epochs 200] [--architecture 64x64] [--pressure-scaled PA]
//                       [--walk-share F] [--training-seed 1] [--pressures-kpa P ...]
//                       [--wheel-load-n 1000] [--threads 2]
//                       [--fe-de-budget-s S | --fe-de-curve FILE] [--carry coordination_number]
//                       [--return-after-steps N] [--no-fe-de] [--fe-ann-budget-s S]
//                       [--progress-every-s 60] [--fe-ann-stop-at F]
//                       [--refine-rounds N [--refine-epochs 100] [--refine-share F]
//                       [--refine-stop-at F]] [--samples-csv FILE]
//
// Trains a model by the fe-ann recipe (solvers/tiers/surrogate_training.h) on the soil's RVE at
// the preset's numerics, then prints
//   - training: paths' and training's seconds, samples, the histories' bytes;
//   - the network: microseconds per point and evaluations per second of one member, batched
//     (1 to 8,192 points), by the fused Eigen kernel and by the TorchScript module, and of the
//     ensemble (3 members, the envelope's checks included);
//   - a traction curve of the preset's rig (0.5 x 0.2 m wheel) by fe-de and by fe-ann: wall
//     seconds, the fe-ann phases (network, fallbacks, model load, the rest: FE and contact), the
//     speedup and the largest differences; with --fe-de-budget-s, a configuration whose fe-de
//     curve takes hours (default): fe-de run for S seconds and its whole time projected from its
//     pace (solvers/tiers/fe_de_pace.h, a lower bound), and fe-ann run to the end (or, with
//     --fe-ann-budget-s, stopped after S seconds, or with --fe-ann-stop-at F once it has done the
//     fraction F of its FE steps: the same place for every model); while fe-ann runs, a line every
//     --progress-every-s seconds: how far, the fallbacks and returns so far, and their seconds
//     against the network's; --no-fe-de leaves fe-de out; --fe-de-curve FILE compares with an
//     fe-de curve of the same rig computed before (gonogo-fe-de --curve-csv, checkpointed over
//     as many runs as it takes; solvers/tiers/fe_de_curve_file.h) instead of running fe-de;
//   - with --refine-rounds N, N rounds of the fallbacks' own training data: the fe-ann run records
//     its fallen-back points' paths on their RVEs (FeAnnTier::Run's fallback_paths), the model
//     is fine-tuned on its training paths and every fallback path gathered so far
//     (SurrogateEnsemble::FineTune, --refine-epochs at 1e-3; with --refine-share F the fallback
//     paths' steps carry the share F of the loss, else each step weighs alike), and the curve is
//     run again on the fine-tuned model (to the same budget, or with --refine-stop-at F to that
//     fraction of the FE steps, 0: to the end): its fallbacks, time and curve each round;
//   - with --samples-csv FILE, the rig's 5 ms records of each whole fe-ann curve written there
//     (the last one kept), to set beside gonogo-fe-de --samples-csv's;
//   - peak resident memory after each part.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/ann/strain_history.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/rig/wheel_rig.h"
#include "solvers/tiers/fe_ann_tier.h"
#include "solvers/tiers/fe_de_curve_file.h"
#include "solvers/tiers/fe_de_pace.h"
#include "solvers/tiers/soil_catalogue.h"
#include "solvers/tiers/surrogate_training.h"

namespace {

using namespace gonogo;

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // kB on Linux
}

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void WriteRecords(const std::string& path, const std::vector<rig::RigSample>& samples) {
  std::ofstream out(path);
  out << rig::RigSamplesCsv(samples);
  if (!out) throw std::runtime_error("could not write --samples-csv " + path);
}

std::string FlagsOf(const tiers::AnnProgress& progress) {
  return tiers::FallbackFlagsPhrase(progress.fallbacks_flagged);
}

// Microseconds per point of `evaluate` on a batch of `points`, repeated to about 0.3 s.
double MicrosecondsPerPoint(std::size_t points, const std::function<void()>& evaluate) {
  evaluate();  // warm
  int repeats = 0;
  const auto start = std::chrono::steady_clock::now();
  while (Since(start) < 0.3 || repeats < 3) {
    evaluate();
    ++repeats;
  }
  return 1e6 * Since(start) / (repeats * static_cast<double>(points));
}

}  // namespace

int main(int argc, char** argv) {
  std::string soil_name = "seed000_sand_rve100", preset = "tiny", architecture_text = "64x64";
  int steps = 40, walks = 12, epochs = 200, threads = 2, rotated_copies = 0;
  double load_n = 1000, fe_de_budget_s = 0, distance_threshold = 0, spread_threshold = 0;
  double pressure_floor_kpa = 0;
  double fe_ann_budget_s = 0, progress_every_s = 60, fe_ann_stop_at = 0;
  bool no_fe_de = false;
  std::string fe_de_curve_path;
  std::string samples_csv;
  std::vector<std::string> carried;
  int return_after_steps = 0, refine_rounds = 0, refine_epochs = 100;
  double refine_share = 0, refine_stop_at = -1;
  double pressure_reference_pa = 0, walk_share = 0;
  unsigned training_seed = 1;
  std::vector<double> pressures_kpa;
  CLI::App app("gonogo-bench-fe-ann: the fe-ann tier's network, curve, training and memory",
               "gonogo-bench-fe-ann");
  app.add_option("--soil", soil_name, "dem-hertz-mindlin soil of the catalogue")->capture_default_str();
  app.add_option("--preset", preset, "fe-de configuration")->capture_default_str();
  app.add_option("--steps", steps, "steps per training path")->capture_default_str();
  app.add_option("--walks", walks, "random walks in the training set")->capture_default_str();
  app.add_option("--epochs", epochs, "training epochs")->capture_default_str();
  app.add_option("--rotated-copies", rotated_copies,
                 "rotated copies of each training path added to the training set")
      ->capture_default_str();
  app.add_option("--architecture", architecture_text, "MLP hidden widths joined by x")
      ->capture_default_str();
  app.add_option("--pressure-scaled", pressure_reference_pa,
                 "MLPs that see the stress relative to max(p, 0) + this reference pressure (Pa) "
                 "and answer d_sigma over it (stress_surrogate.h); 0: unscaled")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--walk-share", walk_share,
                 "the random walks' share of the training loss; 0: their share of the steps")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  app.add_option("--pressures-kpa", pressures_kpa,
                 "confining pressures of the training paths, kPa, increasing (default: 2.5 5 10 "
                 "20 40 80)");
  app.add_option("--training-seed", training_seed,
                 "the first member's seed of weights and batch order (member k: seed + k)")
      ->capture_default_str();
  app.add_option("--return-after-steps", return_after_steps,
                 "a fallen-back point returns to the network after this many unflagged FE steps "
                 "(0: never)")
      ->capture_default_str();
  app.add_option("--carry", carried,
                 "internal variables of the RVE the MLPs carry (coordination_number, "
                 "solid_fraction; stress_surrogate.h)");
  app.add_option("--wheel-load-n", load_n, "the rig wheel's load, N")->capture_default_str();
  app.add_option("--fe-de-budget-s", fe_de_budget_s,
                 "> 0: run fe-de this long and project its whole time from its pace")
      ->capture_default_str();
  app.add_flag("--no-fe-de", no_fe_de, "no fe-de curve: fe-ann alone (its speedup not measured)");
  app.add_option("--fe-de-curve", fe_de_curve_path,
                 "compare with this fe-de curve of the same rig (gonogo-fe-de --curve-csv, run "
                 "with --slip-step 0.25) instead of running fe-de");
  app.add_option(
      "--samples-csv", samples_csv,
      "write each whole fe-ann curve's rig records (5 ms means; gonogo-fe-de "
      "--samples-csv's columns) here, the last curve's kept: the fine-tuned model's when "
      "refining");
  app.add_option("--fe-ann-budget-s", fe_ann_budget_s,
                 "> 0: stop the fe-ann curve after this long and print how far it came")
      ->capture_default_str();
  app.add_option("--fe-ann-stop-at", fe_ann_stop_at,
                 "> 0: stop the fe-ann curve once this fraction of its FE steps is done")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--progress-every-s", progress_every_s,
                 "seconds between the fe-ann run's progress lines")
      ->capture_default_str();
  app.add_option("--distance-threshold", distance_threshold,
                 "the fe-ann run's envelope distance threshold; 0: the model's own")
      ->capture_default_str();
  app.add_option("--spread-threshold", spread_threshold,
                 "the fe-ann run's ensemble spread threshold; 0: the model's own")
      ->capture_default_str();
  app.add_option("--pressure-floor-kpa", pressure_floor_kpa,
                 "the fe-ann run's pressure floor, kPa: a point whose mean compression is below "
                 "it falls back to its RVE; 0: none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--threads", threads, "OpenMP threads running the training paths")
      ->capture_default_str();
  app.add_option("--refine-rounds", refine_rounds,
                 "rounds of fine-tuning the model on its fe-ann runs' fallback paths, each run "
                 "again")
      ->check(CLI::Range(0, 10))
      ->capture_default_str();
  app.add_option("--refine-epochs", refine_epochs, "epochs of each round's fine-tuning")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--refine-stop-at", refine_stop_at,
                 "the refined runs stop once this fraction of their FE steps is done (0: at the "
                 "end; default: as --fe-ann-stop-at)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--refine-share", refine_share,
                 "the fallback paths' share of the fine-tuning's loss (0: each step alike)")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (int(no_fe_de) + int(fe_de_budget_s > 0) + int(!fe_de_curve_path.empty()) > 1) {
    std::fprintf(stderr, "gonogo-bench-fe-ann: --no-fe-de, --fe-de-budget-s and --fe-de-curve "
                         "exclude each other\n");
    return 2;
  }
  try {
    const tiers::CatalogueEntry* entry =
        tiers::BuiltinSoilCatalogue().Find(soil_name, dem::rve::kRveSoilModel);
    if (entry == nullptr) throw InputError("--soil", "no dem-hertz-mindlin soil '" + soil_name + "'");
    tiers::SurrogateRecipe recipe;
    recipe.steps = steps;
    recipe.walks = walks;
    recipe.training.epochs = epochs;
    recipe.rotated_copies = rotated_copies;
    recipe.threads = threads;
    recipe.architecture.hidden_widths.clear();
    std::stringstream widths(architecture_text);
    for (std::string width; std::getline(widths, width, 'x');) {
      recipe.architecture.hidden_widths.push_back(std::stoi(width));
    }
    recipe.architecture.carried_variables = carried;
    recipe.architecture.pressure_reference_pa = pressure_reference_pa;
    recipe.walk_share = walk_share;
    recipe.training.seed = training_seed;
    if (!pressures_kpa.empty()) {
      recipe.pressures_pa.clear();
      for (double kpa : pressures_kpa) recipe.pressures_pa.push_back(1e3 * kpa);
    }
    recipe.ValidateAsOptions();  // before the fe-de curve file is read and the model trained
    const tiers::FeDeOptions fe_de = tiers::FeDeOptions::Preset(preset);
    TractionRequest request;
    request.soil.soil_name = soil_name;
    request.tyre.diameter_m = 0.5;
    request.tyre.width_m = 0.2;
    request.tyre.section_height_m = 0.1;
    request.wheel_load_n = load_n;
    request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
    // An fe-de curve computed before: read and checked first, so that a wrong file fails before
    // the training.
    tiers::FeDeCurveFile fe_de_curve_file;
    if (!fe_de_curve_path.empty()) {
      fe_de_curve_file = tiers::ReadFeDeCurveFile(fe_de_curve_path, "--fe-de-curve");
      tiers::RequireFeDeConfiguration(
          fe_de_curve_file,
          tiers::FeDeRigConfiguration(tiers::FeDeTier(fe_de).Version(), soil_name, preset, "none",
                                      request),
          request.slips, "--fe-de-curve");
    }
    std::printf("# gonogo-bench-fe-ann: soil %s, preset %s, %s, %d epochs\n", soil_name.c_str(),
                preset.c_str(), recipe.architecture.Describe().c_str(), epochs);

    const tiers::TrainedSurrogate trained =
        tiers::TrainSurrogateOnRve(entry->parameters, fe_de, recipe);
    std::size_t history_bytes = 0;
    for (const ann::StrainHistory& history : trained.training) {
      history_bytes += ann::SerializeHistory(history).size();
    }
    std::printf("training: paths %.1f s on %d threads, training %.1f s (3 members, one thread), "
                "%lld samples, histories %.1f kB; worst held-out %.1f %%; peak RSS %.0f MB\n",
                trained.generation_seconds, threads, trained.training_seconds,
                static_cast<long long>(trained.samples), history_bytes / 1024.0,
                100 * trained.worst_held_out_error, PeakRssMb());
    std::printf("held-out:");
    for (const tiers::HeldOutResult& result : trained.held_out_errors) {
      std::printf(" %s %.1f %%;", result.path.c_str(), 100 * result.replay_error);
    }
    std::printf("\n");

    const ann::InputEnvelope& envelope = trained.ensemble.envelope();
    std::printf("model: distance threshold %.2f, spread threshold %.3g, tensile limit %g Pa, cone "
                "least principal ratio %.3f; %d rotated copies of each training path\n",
                trained.ensemble.distance_threshold(), trained.ensemble.spread_threshold(),
                envelope.tensile_limit_pa, envelope.least_principal_ratio, rotated_copies);

    // The network, batched.
    std::vector<ann::SurrogateInput> pool;
    for (const ann::StrainHistory& history : trained.training) {
      for (const ann::SurrogateInput& input : ann::InputsOf(history, carried)) pool.push_back(input);
    }
    std::printf("batch,fused_us_per_point,module_us_per_point,fused_evals_per_s,"
                "ensemble_us_per_point,ensemble_tangent_us_per_point\n");
    const ann::StressSurrogate& member = trained.ensemble.member(0);
    for (std::size_t batch_size : {1, 16, 128, 1024, 8192}) {
      std::vector<ann::SurrogateInput> batch;
      for (std::size_t k = 0; k < batch_size; ++k) batch.push_back(pool[k % pool.size()]);
      const double fused = MicrosecondsPerPoint(batch_size, [&] { member.StressIncrements(batch); });
      const double module =
          MicrosecondsPerPoint(batch_size, [&] { member.StressIncrementsByModule(batch); });
      const double ensemble =
          MicrosecondsPerPoint(batch_size, [&] { trained.ensemble.Answer(batch, false); });
      const double with_tangent =
          MicrosecondsPerPoint(batch_size, [&] { trained.ensemble.Answer(batch, true); });
      std::printf("%zu,%.2f,%.2f,%.3g,%.2f,%.2f\n", batch_size, fused, module, 1e6 / fused,
                  ensemble, with_tangent);
    }
    std::fflush(stdout);

    // One curve each way, on the same rig and mesh.
    const std::string directory = (std::filesystem::temp_directory_path() /
                                   ("gonogo_bench_fe_ann_" + std::to_string(::getpid())))
                                      .string();

    auto start = std::chrono::steady_clock::now();
    tiers::FeDeRunReport de;
    double de_s = 0;
    if (no_fe_de) {
      std::printf("fe-de curve: not run (--no-fe-de)\n");
    } else if (!fe_de_curve_path.empty()) {
      de.curve.points = fe_de_curve_file.points;
      std::printf("fe-de curve: from %s (%s elements, %s FE steps; its wall time over its resumed "
                  "runs is not in the file)\n",
                  fe_de_curve_path.c_str(), fe_de_curve_file.configuration["elements"].c_str(),
                  fe_de_curve_file.configuration["fe_steps"].c_str());
    } else if (fe_de_budget_s > 0) {
      const tiers::FeDePace pace =
          tiers::MeasureFeDePace(tiers::FeDeTier(fe_de), request, fe_de_budget_s);
      de_s = pace.projected_s();
      std::printf("fe-de curve: not run to the end: %.0f of %.0f FE steps in %.1f s after a %.1f "
                  "s setup, %.3f s per FE step; the whole curve at this pace %.0f s (%.2f h); "
                  "peak RSS %.0f MB\n",
                  pace.steps_done, pace.total_steps, pace.stepping_s, pace.setup_s,
                  pace.seconds_per_step(), de_s, de_s / 3600, PeakRssMb());
    } else {
      de = tiers::FeDeTier(fe_de).Run(request, {});
      de_s = Since(start);
      std::printf("fe-de curve: %.1f s wall, %d elements, %d FE steps; peak RSS %.0f MB\n", de_s,
                  de.elements, de.fe_steps, PeakRssMb());
    }
    std::fflush(stdout);

    // The fe-ann curve on `ensemble`, printed under `label`; its fallen-back points' paths.
    const auto run_fe_ann = [&](const ann::SurrogateEnsemble& ensemble, const std::string& label,
                                double stop_at) {
      std::filesystem::remove_all(directory);
      ensemble.Save(directory);
      tiers::SurrogateModelRecord record;
      record.id = "bench";
      record.directory = directory;
      record.soil_parameters = CanonicalText(entry->parameters);
      record.fe_de_preset = preset;
      tiers::FeAnnOptions options;
      options.fe_de = fe_de;
      options.distance_threshold = distance_threshold;
      options.spread_threshold = spread_threshold;
      options.pressure_floor_pa = 1e3 * pressure_floor_kpa;
      options.return_after_steps = return_after_steps;
      const tiers::FeAnnTier fe_ann(options,
                                    std::make_shared<tiers::ListedSurrogateModels>(
                                        std::vector<tiers::SurrogateModelRecord>{record}));
      const auto run_start = std::chrono::steady_clock::now();
      double last_line_s = 0;
      tiers::AnnProgress last_progress;
      ComputeContext ann_context;
      ann_context.cancelled = [&] {
        return (fe_ann_budget_s > 0 && Since(run_start) > fe_ann_budget_s) ||
               (stop_at > 0 && last_progress.fraction >= stop_at);
      };
      const tiers::AnnProgressReport print_progress = [&](const tiers::AnnProgress& p) {
        last_progress = p;
        if (Since(run_start) - last_line_s < progress_every_s) return;
        last_line_s = Since(run_start);
        std::printf(
            "  %s %.0f s: %.1f %% of the FE steps; %d fallbacks (%s; %lld returned), "
            "fallbacks %.1f s, network %.1f s\n",
            label.c_str(), last_line_s, 100 * p.fraction, p.fallbacks, FlagsOf(p).c_str(),
            static_cast<long long>(p.returns), p.fallback_seconds, p.network_seconds);
        std::fflush(stdout);
      };
      std::vector<ann::StrainHistory> fallback_paths;
      tiers::AnnRunReport ann;
      try {
        ann = fe_ann.Run(request, ann_context, print_progress,
                         refine_rounds > 0 ? &fallback_paths : nullptr);
      } catch (const CancelledError& stop) {
        // The rig's records up to the stop, where it says them (rig::StoppedRunError).
        const auto* stopped = dynamic_cast<const rig::StoppedRunError*>(&stop);
        if (stopped && !samples_csv.empty()) {
          WriteRecords(samples_csv, stopped->samples());
          std::printf("%s curve: its rig records up to the stop (%zu) in %s\n", label.c_str(),
                      stopped->samples().size(), samples_csv.c_str());
        }
        const tiers::AnnProgress& p = last_progress;
        std::printf(
            "%s curve: stopped after %.0f s at %.1f %% of the FE "
            "steps: %d fallbacks (%s; %lld returned), fallbacks %.1f s, network %.1f s, "
            "the rest (FE, contact) %.1f s; %zu fallback paths; peak RSS %.0f MB\n",
            label.c_str(), Since(run_start), 100 * p.fraction, p.fallbacks, FlagsOf(p).c_str(),
            static_cast<long long>(p.returns), p.fallback_seconds, p.network_seconds,
            Since(run_start) - p.fallback_seconds - p.network_seconds, fallback_paths.size(),
            PeakRssMb());
        std::fflush(stdout);
        return fallback_paths;
      }
      const double ann_s = Since(run_start);
      if (!samples_csv.empty()) {
        WriteRecords(samples_csv, ann.samples);
        std::printf("%s curve: its rig records in %s\n", label.c_str(), samples_csv.c_str());
      }
      const double rest_s =
          ann_s - ann.network_seconds - ann.fallback_seconds - ann.model_load_seconds;
      char speedup[64] = "fe-de not run";
      if (!fe_de_curve_path.empty()) {
        std::snprintf(speedup, sizeof speedup, "fe-de's time not measured here");
      } else if (!no_fe_de) {
        std::snprintf(speedup, sizeof speedup, "%.1fx%s", de_s / ann_s,
                      fe_de_budget_s > 0 ? " of the projection" : "");
      }
      std::printf(
          "%s curve: %.2f s wall (%s): network %.2f s (%lld point updates, %.1f us "
          "each; %lld answers returned to admissible stresses), fallbacks %d in %.2f s "
          "(%s; %lld returned; %zu fallback paths), model load %.3f s, FE and contact "
          "%.2f s; peak RSS %.0f MB\n",
          label.c_str(), ann_s, speedup, ann.network_seconds,
          static_cast<long long>(ann.network_point_updates),
          1e6 * ann.network_seconds / std::max<std::int64_t>(1, ann.network_point_updates),
          static_cast<long long>(ann.stress_returns), ann.fallbacks, ann.fallback_seconds,
          tiers::FallbackFlagsPhrase(ann.fallbacks_flagged).c_str(),
          static_cast<long long>(ann.returns), fallback_paths.size(), ann.model_load_seconds,
          rest_s, PeakRssMb());
      if (fe_de_budget_s > 0 || no_fe_de) {
        std::printf("%s curve (no fe-de curve to compare with):\nslip,drawbar_pull_n,torque_nm,"
                    "sinkage_m\n",
                    label.c_str());
        for (const TractionPoint& p : ann.curve.points) {
          std::printf("%.2f,%.1f,%.2f,%.5f\n", p.slip, p.drawbar_pull_n, p.torque_nm, p.sinkage_m);
        }
      } else {
        const tiers::CurveDifference worst = tiers::WorstDifference(ann.curve, de.curve, request);
        std::printf("%s against fe-de, worst over the slips: drawbar pull %.1f %% of W, torque "
                    "%.1f %% of rW, sinkage %.1f %% of r\n",
                    label.c_str(), 100 * worst.drawbar_pull_over_w, 100 * worst.torque_over_rw,
                    100 * worst.sinkage_over_r);
      }
      std::fflush(stdout);
      return fallback_paths;
    };

    std::vector<ann::StrainHistory> gathered =
        run_fe_ann(trained.ensemble, "fe-ann", fe_ann_stop_at);
    std::unique_ptr<ann::SurrogateEnsemble> refined;
    for (int round = 1; round <= refine_rounds; ++round) {
      // The model before this round, fine-tuned on its training paths and every fallback path so
      // far (the paths the envelope missed, answered by the RVEs).
      std::vector<ann::StrainHistory> data = trained.training;
      data.insert(data.end(), gathered.begin(), gathered.end());
      ann::TrainingOptions tuning = recipe.training;
      tuning.epochs = refine_epochs;
      tuning.learning_rate = 1e-3;
      tuning.batch_size = 64;
      if (refine_share > 0 && !gathered.empty()) {
        // Each fallback path's steps weighed so that together they carry refine_share of the loss.
        double training_steps = 0, fallback_steps = 0;
        for (const ann::StrainHistory& path : trained.training) training_steps += path.steps();
        for (const ann::StrainHistory& path : gathered) fallback_steps += path.steps();
        tuning.history_weights.assign(trained.training.size(), 1.0);
        tuning.history_weights.resize(
            data.size(), refine_share * training_steps / ((1 - refine_share) * fallback_steps));
      }
      const auto tune_start = std::chrono::steady_clock::now();
      std::vector<ann::TrainingReport> reports;
      auto tuned = std::make_unique<ann::SurrogateEnsemble>(ann::SurrogateEnsemble::FineTune(
          refined ? *refined : trained.ensemble, data, tuning, &reports));
      double worst_held_out = 0;
      std::string held_out_errors;
      for (std::size_t k = 0; k < trained.held_out.size(); ++k) {
        const double error = ann::ReplayError(*tuned, trained.held_out[k]);
        worst_held_out = std::max(worst_held_out, error);
        char text[160];
        std::snprintf(text, sizeof text, " %s %.1f %%;", trained.held_out_errors[k].path.c_str(),
                      100 * error);
        held_out_errors += text;
      }
      std::printf("refine round %d: fine-tuned on %zu training paths and %zu fallback paths "
                  "(%lld samples), %d epochs in %.1f s; worst held-out %.1f %%; distance "
                  "threshold %.2f\n",
                  round, trained.training.size(), gathered.size(),
                  static_cast<long long>(reports.front().samples), refine_epochs,
                  Since(tune_start), 100 * worst_held_out, tuned->distance_threshold());
      std::printf("refine round %d held-out:%s\n", round, held_out_errors.c_str());
      std::fflush(stdout);
      refined = std::move(tuned);
      const std::vector<ann::StrainHistory> more =
          run_fe_ann(*refined, "fe-ann round " + std::to_string(round),
                     refine_stop_at >= 0 ? refine_stop_at : fe_ann_stop_at);
      gathered.insert(gathered.end(), more.begin(), more.end());
    }
    std::filesystem::remove_all(directory);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gonogo-bench-fe-ann: %s\n", e.what());
    return 1;
  }
}
