// gonogo-rig drawbar        --soil NAME --wheel-diameter M --wheel-width M --wheel-load N
//                           [--element-size M] [--threads T] [--slip-step S] [--samples]
//                           [--hourglass-stiffness E] [--hourglass-viscosity Q]
// gonogo-rig constant-slip  (as above) --slip S [--hold-s T]
// gonogo-rig towed          (as above) [--hold-s T]
// gonogo-rig bevameter      --soil NAME [--element-size M] [--threads T]
//
// The single-wheel rig of seed 001 section 6.3 on the fe-classic soil bin (solvers/rig/README.md).
//   drawbar        the full procedure; prints the traction curve as CSV (the columns of
//                  `gonogo curve --csv`), or with --samples every 5 ms record of the run
//   constant-slip  phases 1-3, then the slip held for --hold-s (default 1 s); prints the records
//   towed          phases 1-3, then free rolling (no torque) at the phase-3 forward speed for
//                  --hold-s; prints the records
//   bevameter      plate pressure-sinkage and shear-ring tests on the soil and the fitted
//                  Bekker-Janosi parameters
// Progress goes to stderr.
// Options belong to the commands above; an option a command does not take is an error (exit 2).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <initializer_list>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/rig/bevameter.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/wheel_rig.h"
#include "solvers/common/cli_checks.h"

namespace {

using namespace gonogo;

// The numbers the rig reads must be finite (CLI11 alone takes "nan" and "inf").
const CLI::Validator kFinite = gonogo::cli_checks::FiniteNumber();

struct CommandLine {
  std::string soil_name;
  rig::RigWheel wheel;
  rig::RigOptions options;
  double slip_step = 0.05;
  double slip = 0;
  double hold_s = 1.0;
  bool samples = false;
};

// --soil and the bin's mesh and numerics: every command takes them.
void AddSoilOptions(CLI::App* command, CommandLine* line) {
  command->add_option("--soil", line->soil_name,
                      "fe-classic soil (solvers/rig/data/fe_soils.csv); required");
  command
      ->add_option("--element-size", line->options.element_size_m,
                   "bin resolution near the wheel path, m; 0: R / elements_per_radius")
      ->check(kFinite)
      ->capture_default_str();
  command->add_option("--threads", line->options.threads, "threads of the FE solver")
      ->capture_default_str();
  command
      ->add_option("--hourglass-stiffness", line->options.hourglass_coefficient,
                   "hourglass stiffness coefficient eps_hg (fe::ExplicitOptions)")
      ->check(kFinite)
      ->capture_default_str();
  command
      ->add_option("--hourglass-viscosity", line->options.hourglass_viscosity,
                   "hourglass viscosity Q_hg (fe::ExplicitOptions)")
      ->check(kFinite)
      ->capture_default_str();
  command->add_flag("--csv", "accepted and ignored: CSV is the only output format");
}

// The wheel and the curve's options: drawbar, constant-slip and towed take them.
void AddWheelOptions(CLI::App* command, CommandLine* line) {
  AddSoilOptions(command, line);
  command
      ->add_option_function<double>(
          "--wheel-diameter", [line](const double& d) { line->wheel.radius_m = 0.5 * d; },
          "wheel diameter, m; required")
      ->check(kFinite);
  command->add_option("--wheel-width", line->wheel.width_m, "wheel width, m; required")
      ->check(kFinite);
  command->add_option("--wheel-load", line->wheel.load_n, "vertical wheel load W, N; required")
      ->check(kFinite);
  command->add_option("--slip-step", line->slip_step, "slip spacing of the printed curve")
      ->check(kFinite)
      ->capture_default_str();
  command->add_flag("--samples", line->samples,
                    "print every 5 ms record of the run instead of the curve");
}

// Throws CLI::RequiredError for the first of `names` not given to `command`. CLI11 checks its
// required options before it rejects unknown ones; checking here, after parsing, lets a mistyped
// required option (--wheel-lod) be reported by its own name rather than as a missing one.
void RequireGiven(const CLI::App& command, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    if (command.count(name) == 0) throw CLI::RequiredError(name);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "The single-wheel rig of seed 001 section 6.3 on the fe-classic soil bin "
      "(solvers/rig/README.md). Progress goes to stderr.",
      "gonogo-rig");
  // At most one command; "none" is checked after parsing, so that an unknown option or command is
  // reported by name rather than as a missing command.
  app.require_subcommand(0, 1);
  CommandLine line;
  CLI::App* drawbar = app.add_subcommand(
      "drawbar",
      "the full procedure; prints the traction curve as CSV (the columns of `gonogo curve --csv`), "
      "or with --samples every 5 ms record of the run");
  AddWheelOptions(drawbar, &line);
  CLI::App* constant_slip = app.add_subcommand(
      "constant-slip", "phases 1-3, then the slip held for --hold-s; prints the records");
  AddWheelOptions(constant_slip, &line);
  constant_slip->add_option("--slip", line.slip, "the slip held after phase 3; required")
      ->check(kFinite & CLI::NonNegativeNumber);
  constant_slip->add_option("--hold-s", line.hold_s, "how long the slip is held, s")
      ->check(kFinite)
      ->capture_default_str();
  CLI::App* towed = app.add_subcommand(
      "towed",
      "phases 1-3, then free rolling (no torque) at the phase-3 forward speed for --hold-s; "
      "prints the records");
  AddWheelOptions(towed, &line);
  towed->add_option("--hold-s", line.hold_s, "how long the wheel rolls freely, s")
      ->check(kFinite)
      ->capture_default_str();
  CLI::App* bevameter = app.add_subcommand(
      "bevameter",
      "plate pressure-sinkage and shear-ring tests on the soil and the fitted Bekker-Janosi "
      "parameters");
  AddSoilOptions(bevameter, &line);
  try {
    app.parse(argc, argv);
    for (const CLI::App* command : app.get_subcommands()) {
      RequireGiven(*command, {"--soil"});
      if (command != bevameter) {
        RequireGiven(*command, {"--wheel-diameter", "--wheel-width", "--wheel-load"});
      }
      if (command == constant_slip) RequireGiven(*command, {"--slip"});
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (app.get_subcommands().empty()) {
    std::fprintf(stderr, "gonogo-rig: a command is required\n%s", app.help().c_str());
    return 2;
  }
  const std::string command = app.get_subcommands().front()->get_name();
  const rig::RigWheel& wheel = line.wheel;
  rig::RigOptions& options = line.options;
  try {
    const rig::FeSoil* soil = rig::FeSoilLibrary::Builtin().Find(line.soil_name);
    if (soil == nullptr) {
      std::string known;
      for (const auto& n : rig::FeSoilLibrary::Builtin().Names()) known += " " + n;
      throw InputError("soil", "unknown fe-classic soil '" + line.soil_name + "'; known:" + known);
    }
    const auto start = std::chrono::steady_clock::now();
    int last_percent = -1;
    options.progress = [&](double fraction) {
      const int percent = static_cast<int>(100 * fraction);
      if (percent / 5 != last_percent / 5) {
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "\r%3d %% (%.0f s)", percent, s);
        last_percent = percent;
      }
    };
    if (command == "bevameter") {
      const rig::BevameterResult result = rig::RunVirtualBevameter(*soil, {}, options);
      std::fprintf(stderr, "\n");
      rig::PrintBevameter(result, stdout);
      return 0;
    }
    rig::RigRun run;
    if (command == "drawbar") {
      run = rig::RunDrawbarPullTest(*soil, wheel, {}, options);
    } else if (command == "towed") {
      run = rig::RunTowedTest(*soil, wheel, line.hold_s, {}, options);
    } else {
      run = rig::RunConstantSlipTest(*soil, wheel, line.slip, line.hold_s, {}, options);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "\n%d elements, %d nodes, h = %.4f m, dt = %.3g s, %d steps, %.1f s\n",
                 run.elements, run.nodes, run.element_size_m, run.time_step_s, run.steps, seconds);
    if (line.samples || command == "constant-slip" || command == "towed") {
      std::fputs(rig::RigSamplesCsv(run.samples).c_str(), stdout);
      return 0;
    }
    std::printf("slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency\n");
    for (const TractionPoint& p :
         rig::CurveFromRun(run, TractionRequest::SlipSweep(line.slip_step), wheel.radius_m)) {
      std::printf("%.4f,%.2f,%.2f,%.5f,%.4f\n", p.slip, p.drawbar_pull_n, p.torque_nm,
                  p.sinkage_m, p.tractive_efficiency);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\ngonogo-rig: %s\n", e.what());
    return 1;
  }
  return 0;
}
