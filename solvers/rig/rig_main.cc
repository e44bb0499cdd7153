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
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/rig/bevameter.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/wheel_rig.h"

namespace {

using namespace gonogo;

[[noreturn]] void Usage(const std::string& problem) {
  std::fprintf(stderr,
               "gonogo-rig: %s\n"
               "usage: gonogo-rig drawbar|constant-slip|towed --soil NAME --wheel-diameter M\n"
               "         --wheel-width M --wheel-load N [--element-size M] [--threads T]\n"
               "         [--slip-step S] [--samples] [--slip S] [--hold-s T]\n"
               "         [--hourglass-stiffness E] [--hourglass-viscosity Q]\n"
               "       gonogo-rig bevameter --soil NAME [--element-size M] [--threads T]\n",
               problem.c_str());
  std::exit(2);
}

double Number(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value)) {
    Usage(flag + " needs a number, got '" + text + "'");
  }
  return value;
}

void PrintSamples(const rig::RigRun& run) {
  std::printf("time_s,phase,slip,forward_speed_m_s,angular_speed_rad_s,drawbar_pull_n,torque_nm,"
              "vertical_force_n,sinkage_m\n");
  for (const rig::RigSample& s : run.samples) {
    std::printf("%.4f,%d,%.4f,%.4f,%.4f,%.2f,%.2f,%.2f,%.5f\n", s.time_s, s.phase, s.slip,
                s.forward_speed_m_s, s.angular_speed_rad_s, s.drawbar_pull_n, s.torque_nm,
                s.vertical_force_n, s.sinkage_m);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) Usage("missing command");
  const std::string command = argv[1];
  std::string soil_name;
  rig::RigWheel wheel;
  rig::RigOptions options;
  double slip_step = 0.05, slip = -1, hold_s = 1.0;
  bool samples = false;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) Usage(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--soil") soil_name = value();
    else if (flag == "--wheel-diameter") wheel.radius_m = 0.5 * Number(flag, value());
    else if (flag == "--wheel-width") wheel.width_m = Number(flag, value());
    else if (flag == "--wheel-load") wheel.load_n = Number(flag, value());
    else if (flag == "--element-size") options.element_size_m = Number(flag, value());
    else if (flag == "--hourglass-stiffness") options.hourglass_coefficient = Number(flag, value());
    else if (flag == "--hourglass-viscosity") options.hourglass_viscosity = Number(flag, value());
    else if (flag == "--threads") options.threads = static_cast<int>(Number(flag, value()));
    else if (flag == "--slip-step") slip_step = Number(flag, value());
    else if (flag == "--slip") slip = Number(flag, value());
    else if (flag == "--hold-s") hold_s = Number(flag, value());
    else if (flag == "--samples") samples = true;
    else if (flag == "--csv") {}  // CSV is the only output format
    else Usage("unknown option " + flag);
  }
  try {
    const rig::FeSoil* soil = rig::FeSoilLibrary::Builtin().Find(soil_name);
    if (soil == nullptr) {
      std::string known;
      for (const auto& n : rig::FeSoilLibrary::Builtin().Names()) known += " " + n;
      throw InputError("soil", "unknown fe-classic soil '" + soil_name + "'; known:" + known);
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
      run = rig::RunTowedTest(*soil, wheel, hold_s, {}, options);
    } else if (command == "constant-slip") {
      if (slip < 0) Usage("constant-slip needs --slip S");
      run = rig::RunConstantSlipTest(*soil, wheel, slip, hold_s, {}, options);
    } else {
      Usage("unknown command " + command);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "\n%d elements, %d nodes, h = %.4f m, dt = %.3g s, %d steps, %.1f s\n",
                 run.elements, run.nodes, run.element_size_m, run.time_step_s, run.steps, seconds);
    if (samples || command == "constant-slip" || command == "towed") {
      PrintSamples(run);
      return 0;
    }
    std::printf("slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency\n");
    for (const TractionPoint& p :
         rig::CurveFromRun(run, TractionRequest::SlipSweep(slip_step), wheel.radius_m)) {
      std::printf("%.4f,%.2f,%.2f,%.5f,%.4f\n", p.slip, p.drawbar_pull_n, p.torque_nm,
                  p.sinkage_m, p.tractive_efficiency);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\ngonogo-rig: %s\n", e.what());
    return 1;
  }
  return 0;
}
