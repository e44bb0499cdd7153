// gonogo-ann: the surrogate's study on a soil's own DE RVE, from the command line.
//
//   gonogo-ann --soil seed000_sand_rve100 [--preset ci] [--steps 50] [--walks 16]
//              [--architecture 64x64 ...] [--members 3] [--epochs 300] [--threads T] [--out DIR]
//
// Runs laboratory paths (lab_paths.h) on the soil's RVE, with the RVE numerics of the fe-de
// preset: a training set (drained triaxials, simple shears, unload-reload and isotropic paths at
// 5-40 kPa, and seeded random walks) and a held-out set (other pressures, other seeds), on
// OpenMP threads, one path per thread. Trains an ensemble per MLP --architecture (one network per
// GRU: gru32) and prints, per
// architecture, the training figures, each held-out path's replay error (the stress error
// relative to the path's mean |sigma|) and the evaluation cost. With --out, writes the histories
// (training.npy, held_out.npy with their .columns.txt) and each ensemble (DIR/<architecture>/).
#include <CLI/CLI.hpp>
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/soil_catalogue.h"

namespace {

using namespace gonogo;
using namespace gonogo::ann;

struct CommandLine {
  std::string soil = "seed000_sand_rve100";
  std::string preset = "ci";
  int steps = 50;
  int walks = 16;
  std::vector<std::string> architectures = {"64x64"};
  int members = 3;
  int epochs = 300;
  int threads = 2;
  std::string out;
};

struct NamedPath {
  std::string name;
  LabPathSpec spec;
};

LabPathSpec Spec(LabPath path, double pressure_pa, double max_strain, int steps,
                 std::uint64_t seed = 1) {
  LabPathSpec spec;
  spec.path = path;
  spec.pressure_pa = pressure_pa;
  spec.max_strain = max_strain;
  spec.steps = steps;
  spec.seed = seed;
  spec.walk_step_strain = 1e-3;
  return spec;
}

std::vector<NamedPath> TrainingSet(int steps, int walks) {
  std::vector<NamedPath> paths;
  for (double p : {5e3, 10e3, 20e3, 40e3}) {
    paths.push_back({"triaxial", Spec(LabPath::kTriaxial, p, 0.05, steps)});
    paths.push_back({"simple-shear", Spec(LabPath::kSimpleShear, p, 0.1, steps)});
  }
  for (double p : {10e3, 30e3}) {
    paths.push_back({"unload-reload", Spec(LabPath::kUnloadReload, p, 0.04, steps)});
  }
  for (double p : {5e3, 40e3}) {
    paths.push_back({"isotropic", Spec(LabPath::kIsotropic, p, 0.01, steps)});
  }
  for (int k = 1; k <= walks; ++k) {
    paths.push_back({"random-walk", Spec(LabPath::kRandomWalk, 5e3 * (1 + k % 8), 0.01, steps,
                                         static_cast<std::uint64_t>(k))});
  }
  return paths;
}

std::vector<NamedPath> HeldOutSet(int steps) {
  return {{"triaxial 15 kPa", Spec(LabPath::kTriaxial, 15e3, 0.05, steps)},
          {"simple-shear 30 kPa", Spec(LabPath::kSimpleShear, 30e3, 0.1, steps)},
          {"unload-reload 20 kPa", Spec(LabPath::kUnloadReload, 20e3, 0.04, steps)},
          {"random-walk 15 kPa seed 1001", Spec(LabPath::kRandomWalk, 15e3, 0.01, steps, 1001)}};
}

std::vector<StrainHistory> RunPaths(const material::ConstitutiveModel& rve,
                                    const std::vector<NamedPath>& paths, int threads,
                                    const char* label) {
  std::vector<StrainHistory> histories(paths.size());
  DriverOptions options;
  options.relative_tolerance = 0.02;  // a packing's stress is a sum over contacts
  int done = 0;
#pragma omp parallel for schedule(dynamic) num_threads(threads)
  for (int k = 0; k < static_cast<int>(paths.size()); ++k) {
    histories[k] = RunLabPath(rve, paths[k].spec, options);
#pragma omp critical
    {
      ++done;
      std::fprintf(stderr, "\r%s paths: %d / %zu", label, done, paths.size());
    }
  }
  std::fprintf(stderr, "\n");
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (!histories[k].stopped_reason.empty()) {
      std::fprintf(stderr, "  %s %s (%.0f Pa) stopped after %zu steps: %s\n", label,
                   paths[k].name.c_str(), paths[k].spec.pressure_pa, histories[k].steps(),
                   histories[k].stopped_reason.c_str());
    }
  }
  return histories;
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
                                        std::size_t limit) {
  std::vector<SurrogateInput> batch;
  for (const StrainHistory& history : training) {
    for (const SurrogateInput& input : InputsOf(history)) {
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
  return 1e6 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
         (repeats * static_cast<double>(points));
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

void RunRecurrent(const CommandLine& line, const std::string& text,
                  const std::vector<StrainHistory>& training,
                  const std::vector<StrainHistory>& held_out) {
  const int width = GruWidth(text);
  TrainingOptions options;
  options.epochs = line.epochs;
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

int Run(const CommandLine& line) {
  const tiers::CatalogueEntry* entry =
      tiers::BuiltinSoilCatalogue().Find(line.soil, dem::rve::kRveSoilModel);
  if (entry == nullptr) throw InputError("--soil", "no dem-hertz-mindlin soil '" + line.soil + "'");
  for (const std::string& text : line.architectures) {  // refused before any path runs
    if (text.rfind("gru", 0) == 0) {
      GruWidth(text);
    } else {
      ParseArchitecture(text);
    }
  }
  const tiers::FeDeOptions preset = tiers::FeDeOptions::Preset(line.preset);
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(entry->parameters, preset.numerics, "soil"));
  const auto start = std::chrono::steady_clock::now();
  const std::vector<NamedPath> training_paths = TrainingSet(line.steps, line.walks);
  const std::vector<NamedPath> held_out_paths = HeldOutSet(line.steps);
  const std::vector<StrainHistory> training =
      RunPaths(*rve, training_paths, line.threads, "training");
  const std::vector<StrainHistory> held_out =
      RunPaths(*rve, held_out_paths, line.threads, "held-out");
  const double generation_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::size_t steps = 0;
  for (const StrainHistory& history : training) steps += history.steps();
  std::printf("# soil %s (RVEs of %g grains), preset %s: %zu training paths (%zu steps), %zu "
              "held-out, generated in %.1f s on %d threads\n",
              line.soil.c_str(), entry->parameters.Get("grains_per_rve"), line.preset.c_str(),
              training.size(), steps, held_out.size(), generation_s, line.threads);
  if (!line.out.empty()) {
    std::filesystem::create_directories(line.out);
    WriteHistoriesNpy(line.out + "/training.npy", training);
    WriteHistoriesNpy(line.out + "/held_out.npy", held_out);
  }
  std::printf("architecture,members,epochs,samples,train_s,mean_final_loss,");
  for (const NamedPath& path : held_out_paths) std::printf("%s %%,", path.name.c_str());
  std::printf("us_per_point_batch_1000\n");
  for (const std::string& text : line.architectures) {
    if (text.rfind("gru", 0) == 0) {
      RunRecurrent(line, text, training, held_out);
      continue;
    }
    const MlpArchitecture architecture = ParseArchitecture(text);
    TrainingOptions options;
    options.epochs = line.epochs;
    options.batch_size = 64;
    const auto train_start = std::chrono::steady_clock::now();
    std::vector<TrainingReport> reports;
    const SurrogateEnsemble ensemble =
        SurrogateEnsemble::Train(training, architecture, options, line.members, &reports);
    const double train_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - train_start).count();
    double final_loss = 0;
    for (const TrainingReport& report : reports) final_loss += report.final_loss / reports.size();
    std::printf("%s,%d,%d,%lld,%.1f,%.3g,", architecture.Describe().c_str(), line.members,
                line.epochs, static_cast<long long>(reports.front().samples), train_s, final_loss);
    for (const StrainHistory& history : held_out) {
      std::printf("%.2f,", 100 * ReplayError(ensemble, history));
    }
    const std::vector<SurrogateInput> batch = TimingBatch(training, 1000);
    std::printf("%.2f\n",
                MicrosecondsPerPoint(batch.size(), [&] { ensemble.Answer(batch, false); }));
    std::fflush(stdout);
    if (!line.out.empty()) ensemble.Save(line.out + "/" + architecture.Describe());
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
  app.add_option("--walks", line.walks, "random walks in the training set")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("--architecture", line.architectures,
                 "MLP hidden widths joined by x (64x64; the seed's 600x600x600x600x600x600x600), "
                 "or a GRU and its width (gru32; one network, not an ensemble)")
      ->capture_default_str();
  app.add_option("--members", line.members, "ensemble members")
      ->check(CLI::Range(3, 64))
      ->capture_default_str();
  app.add_option("--epochs", line.epochs, "training epochs")
      ->check(CLI::Range(1, 100000))
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
