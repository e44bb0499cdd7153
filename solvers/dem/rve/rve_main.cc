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
#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/dem/rve/rve.h"
#include "solvers/common/cli_checks.h"

namespace {

using gonogo::dem::rve::Matrix3;
using gonogo::dem::rve::MixedControl;
using gonogo::dem::rve::Rve;
using gonogo::dem::rve::RveParams;
using gonogo::dem::rve::RveSnapshot;

struct Options {
  std::string path;
  RveParams rve;
  double axial_strain = 0;  // --axial-strain, or the path's default
  int rows = 100;
  std::string load_file;
  std::string save_file;
};

// The numbers the RVE reads must be finite (CLI11 alone takes "nan" and "inf").
const CLI::Validator kFinite = gonogo::cli_checks::FiniteNumber();

// Fills `options`, or returns the exit code when the program should stop here: 0 after --help, 2
// on a usage error (unknown or mistyped option, value out of range), with the message on stderr.
std::optional<int> Parse(int argc, char** argv, Options* options) {
  CLI::App app(
      "Laboratory stress paths on one periodic DE RVE with the seed 000 parameters: the RVE is "
      "generated and isotropically consolidated to the confining pressure (or loaded from --load), "
      "then\n"
      "  isotropic     all three normal strains compressed equally, to axial strain E "
      "(default 0.01)\n"
      "  triaxial      drained: axial strain compressed to E (default 0.2), lateral stresses held "
      "at P\n"
      "  simple-shear  shear strain gamma_xz to E (default 0.3), no lateral strain, sigma_zz held "
      "at P\n"
      "at the quasi-static rate cap (inertial number 1e-3). Prints CSV on stdout, compression "
      "positive (soil mechanics): strains, p, q, the six stress components, the mobilised friction "
      "angle, the solid fraction and the coordination number. Progress goes to stderr.",
      "gonogo-rve");
  // PATH is checked for presence after parsing, so that an unknown option is reported by name
  // rather than as a missing PATH.
  CLI::Option* path = app.add_option("PATH", options->path, "isotropic, triaxial or simple-shear")
                          ->check(CLI::IsMember({"isotropic", "triaxial", "simple-shear"}));
  app.add_option("--grains", options->rve.grain_count, "grains N of the RVE")
      ->capture_default_str();
  app.add_option("--seed", options->rve.seed, "random seed S of the placement")
      ->capture_default_str();
  app.add_option("--confining-pa", options->rve.consolidation_pressure_pa,
                 "confining pressure P, Pa (consolidation, and lateral or sigma_zz target)")
      ->check(kFinite)
      ->capture_default_str();
  CLI::Option* axial_strain =
      app.add_option("--axial-strain", options->axial_strain,
                     "final axial strain E in (0, 0.5], or gamma_xz in (0, 5] for simple-shear "
                     "(default: the path's)")
          ->check(kFinite);
  app.add_option("--threads", options->rve.threads, "threads T")->capture_default_str();
  app.add_option("--consolidation-friction", options->rve.consolidation_friction,
                 "grain friction MU while the RVE is consolidated")
      ->check(kFinite)
      ->capture_default_str();
  app.add_option("--rows", options->rows, "CSV rows K after the initial one")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()).description(">= 1"))
      ->capture_default_str();
  app.add_option("--load", options->load_file,
                 "restore the RVE from FILE instead of generating it");
  app.add_option("--save", options->save_file, "save the final RVE to FILE");
  app.add_flag("--csv", "accepted and ignored: CSV is the only output format");
  try {
    app.parse(argc, argv);
    if (path->count() == 0) throw CLI::RequiredError("PATH");
    // Simple shear (gamma_xz) may go far: the engine reduces the sheared cell as it goes.
    const bool shear = options->path == "simple-shear";
    if (axial_strain->count() == 0) {
      options->axial_strain = options->path == "isotropic"  ? 0.01
                              : options->path == "triaxial" ? 0.2
                                                            : 0.3;
    } else if (options->axial_strain <= 0.0 || options->axial_strain > (shear ? 5.0 : 0.5)) {
      throw CLI::ValidationError("--axial-strain",
                                 shear ? "gamma_xz must be in (0, 5]" : "must be in (0, 0.5]");
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return std::nullopt;
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
      major + minor > 0.0
          ? gonogo::units::RadiansToDegrees(std::asin((major - minor) / (major + minor)))
          : 0.0;
  std::printf(
      "%ld,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.4f,%.5f,%.4f,%.3e\n", step,
      snapshot.time_s, strain(2, 2), strain.trace(), -2.0 * strain(0, 2), p, q, stress(0, 0),
      stress(1, 1), stress(2, 2), stress(1, 2), stress(0, 2), stress(0, 1), friction_deg,
      snapshot.solid_fraction, snapshot.coordination_number, snapshot.unbalanced_force_ratio);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw gonogo::InputError("--load", "cannot open " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const std::optional<int> exit_code = Parse(argc, argv, &options)) return *exit_code;
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
