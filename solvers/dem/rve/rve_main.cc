// gonogo-rve PATH [--grains N] [--seed S] [--confining-pa P] [--axial-strain E] [--threads T]
//                 [--consolidation-friction MU] [--rows K] [--load FILE] [--save FILE] [--csv]
//
// Laboratory stress paths on one periodic DE RVE with the seed 000 parameters: the RVE is
// generated and isotropically consolidated to the confining pressure (or loaded from --load), then
//   isotropic     all three normal strains compressed equally, to axial strain E (default 0.01)
//   triaxial      drained: axial strain compressed to E (default 0.2), lateral stresses held at P
//   simple-shear  shear strain gamma_xz to E (default 0.3), no lateral strain, sigma_zz held at P
// at the quasi-static rate cap (inertial number 1e-3). Prints CSV on stdout, compression positive
// (soil mechanics): strains, p, q, the six stress components, the mobilised friction angle, the
// solid fraction and the coordination number. Progress goes to stderr.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve.h"

namespace {

using gonogo::dem::rve::Matrix3;
using gonogo::dem::rve::MixedControl;
using gonogo::dem::rve::Rve;
using gonogo::dem::rve::RveParams;
using gonogo::dem::rve::RveSnapshot;

constexpr double kPi = 3.14159265358979323846;

struct Options {
  std::string path;
  RveParams rve;
  double axial_strain = -1.0;  // < 0: the path's default
  int rows = 100;
  std::string load_file;
  std::string save_file;
};

[[noreturn]] void Usage(const std::string& problem) {
  std::fprintf(stderr,
               "gonogo-rve: %s\n"
               "usage: gonogo-rve isotropic|triaxial|simple-shear [--grains N] [--seed S]\n"
               "         [--confining-pa P] [--axial-strain E] [--threads T]\n"
               "         [--consolidation-friction MU] [--rows K] [--load FILE] [--save FILE]"
               " [--csv]\n",
               problem.c_str());
  std::exit(2);
}

double ParseNumber(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value)) {
    Usage(flag + " needs a number, got '" + text + "'");
  }
  return value;
}

Options Parse(int argc, char** argv) {
  if (argc < 2) Usage("missing PATH");
  Options options;
  options.path = argv[1];
  if (options.path != "isotropic" && options.path != "triaxial" && options.path != "simple-shear") {
    Usage("PATH must be isotropic, triaxial or simple-shear, got '" + options.path + "'");
  }
  for (int a = 2; a < argc; ++a) {
    const std::string flag = argv[a];
    if (flag == "--csv") continue;  // CSV is the only output format
    if (a + 1 >= argc) Usage(flag + " needs a value");
    const char* value = argv[++a];
    if (flag == "--grains") {
      options.rve.grain_count = static_cast<int>(ParseNumber(flag, value));
    } else if (flag == "--seed") {
      options.rve.seed = static_cast<unsigned>(ParseNumber(flag, value));
    } else if (flag == "--confining-pa") {
      options.rve.consolidation_pressure_pa = ParseNumber(flag, value);
    } else if (flag == "--axial-strain") {
      options.axial_strain = ParseNumber(flag, value);
      // Simple shear (gamma_xz) may go far: the engine reduces the sheared cell as it goes.
      const double largest = options.path == "simple-shear" ? 5.0 : 0.5;
      if (options.axial_strain <= 0.0 || options.axial_strain > largest) {
        Usage(options.path == "simple-shear" ? "--axial-strain (gamma_xz) must be in (0, 5]"
                                             : "--axial-strain must be in (0, 0.5]");
      }
    } else if (flag == "--threads") {
      options.rve.threads = static_cast<int>(ParseNumber(flag, value));
    } else if (flag == "--consolidation-friction") {
      options.rve.consolidation_friction = ParseNumber(flag, value);
    } else if (flag == "--rows") {
      options.rows = static_cast<int>(ParseNumber(flag, value));
      if (options.rows < 1) Usage("--rows must be >= 1");
    } else if (flag == "--load") {
      options.load_file = value;
    } else if (flag == "--save") {
      options.save_file = value;
    } else {
      Usage("unknown flag " + flag);
    }
  }
  if (options.axial_strain < 0.0) {
    options.axial_strain = options.path == "isotropic" ? 0.01
                           : options.path == "triaxial" ? 0.2
                                                        : 0.3;
  }
  return options;
}

void PrintHeader() {
  std::printf(
      "step,time_s,axial_strain,volumetric_strain,shear_strain,p_pa,q_pa,sigma_xx_pa,"
      "sigma_yy_pa,sigma_zz_pa,sigma_yz_pa,sigma_xz_pa,sigma_xy_pa,mobilised_friction_deg,"
      "solid_fraction,coordination_number,unbalanced_force_ratio\n");
}

void PrintRow(long step, const RveSnapshot& snapshot) {
  // Compression positive: flip the signs of the tension-positive RVE quantities.
  const Matrix3 stress = -snapshot.stress_pa;
  const Matrix3 strain = -snapshot.strain;
  const double p = stress.trace() / 3.0;
  const Matrix3 deviator = stress - p * Matrix3::Identity();
  const double q = std::sqrt(1.5 * deviator.cwiseProduct(deviator).sum());
  const Eigen::Vector3d principal = Eigen::SelfAdjointEigenSolver<Matrix3>(stress).eigenvalues();
  const double major = principal[2], minor = principal[0];
  // Mohr-Coulomb mobilised friction: sin(phi) = (s1 - s3) / (s1 + s3), cohesionless.
  const double friction_deg =
      major + minor > 0.0 ? std::asin((major - minor) / (major + minor)) * 180.0 / kPi : 0.0;
  std::printf("%ld,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.4f,%.5f,%.4f,%.3e\n",
              step, snapshot.time_s, strain(2, 2), strain.trace(), -2.0 * strain(0, 2), p, q,
              stress(0, 0), stress(1, 1), stress(2, 2), stress(1, 2), stress(0, 2), stress(0, 1),
              friction_deg, snapshot.solid_fraction, snapshot.coordination_number,
              snapshot.unbalanced_force_ratio);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw gonogo::InputError("--load", "cannot open " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = Parse(argc, argv);
  try {
    Rve rve = options.load_file.empty()
                  ? Rve::Generate(options.rve,
                                  [](double fraction) {
                                    std::fprintf(stderr, "\rconsolidating: p/target %.2f",
                                                 fraction);
                                  })
                  : Rve::Restore(ReadFile(options.load_file));
    if (options.load_file.empty()) std::fprintf(stderr, "\n");
    const double confining_pa = options.load_file.empty()
                                    ? options.rve.consolidation_pressure_pa
                                    : rve.params().consolidation_pressure_pa;
    const double rate_1_s = rve.StableRate1S();
    MixedControl control;
    if (options.path == "isotropic") {
      control.strain_rate_1_s = -rate_1_s * Matrix3::Identity();
    } else if (options.path == "triaxial") {
      control.strain_rate_1_s(2, 2) = -rate_1_s;
      for (int d = 0; d < 2; ++d) {
        control.stress_controlled[d][d] = true;
        control.target_stress_pa(d, d) = -confining_pa;
      }
    } else {
      control.strain_rate_1_s(0, 2) = rate_1_s;  // u_x = gamma z
      control.stress_controlled[2][2] = true;
      control.target_stress_pa(2, 2) = -confining_pa;
    }
    const long total_steps =
        static_cast<long>(std::ceil(options.axial_strain / (rate_1_s * rve.time_step_s())));
    const long steps_per_row = std::max(1L, total_steps / options.rows);
    PrintHeader();
    PrintRow(0, rve.Snapshot());
    for (long step = 0; step < total_steps;) {
      const long chunk = std::min(steps_per_row, total_steps - step);
      rve.Run(control, static_cast<int>(chunk));
      step += chunk;
      PrintRow(step, rve.Snapshot());
      std::fprintf(stderr, "\r%s: %3.0f %%", options.path.c_str(), 100.0 * step / total_steps);
    }
    std::fprintf(stderr, "\n");
    if (!options.save_file.empty()) {
      std::ofstream out(options.save_file, std::ios::binary);
      const std::string bytes = rve.Save();
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      if (!out) throw gonogo::InputError("--save", "cannot write " + options.save_file);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "\ngonogo-rve: %s\n", error.what());
    return 1;
  }
  return 0;
}
