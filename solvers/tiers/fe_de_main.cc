// gonogo-fe-de: one fe-de traction curve from the command line, alone or collectively under
// mpirun (every rank of MPI_COMM_WORLD in the group: rank 0 runs the FE, all ranks hold RVEs).
//
//   gonogo-fe-de --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2
//                --wheel-load 1000 --preset ci [--slip-step 0.25] [overrides ...]
//   mpirun -np 3 gonogo-fe-de ... (same options on every rank)
//   gonogo-fe-de ... --checkpoint-dir DIR [--checkpoint-every-s 600] --curve-csv FILE
//                (a curve of hours: checkpointed, the same command resumes it; the curve kept
//                in FILE with the configuration it was run on, for gonogo-bench-fe-ann
//                --fe-de-curve); --samples-csv FILE keeps the rig's 5 ms records too
//
//   gonogo-fe-de --calibrate --soil seed000_sand_rve100 --wheel-diameter 0.5 ... --preset ci
//                (RVE triaxials, the Drucker-Prager fit and its twin curve beside fe-de's)
//   gonogo-fe-de --bevameter --soil seed000_sand_rve100 --preset ci [--element-size 0.05]
//                [--ring-pressures 10e3,20e3,40e3] (the virtual bevameter on the same soil)
//   gonogo-fe-de --element-tests --soil seed000_sand [--triaxial-pressures 5e3,40e3]
//                [--ring-pressures 10e3,40e3] (the RVE alone: triaxials, simple shears, and
//                what a shear ring should read of them)
//
// Prints the curve (or the bevameter's curves and fit) as CSV (the columns of `gonogo curve --csv`)
// on stdout and the run's figures (mesh, FE steps, ranks, wall time, load imbalance, migrations,
// bytes per step) on stderr; with --balance-csv FILE, one row per FE step of the balance records.
// Exit status: 0 done, 1 failed, 2 bad options.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "solvers/common/cli_checks.h"
#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/checkpoint_files.h"
#include "solvers/tiers/fe_de_calibration.h"
#include "solvers/tiers/fe_de_curve_file.h"
#include "solvers/tiers/fe_de_pace.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/soil_catalogue.h"

namespace {

using namespace gonogo;

struct CommandLine {
  std::string soil_name = "seed000_sand";
  double grains_per_rve = 0;  // 0: the soil's
  double consolidation_pressure_pa = 0;
  double wheel_diameter_m = 0, wheel_width_m = 0, wheel_load_n = 0;
  double slip_step = 0.1;
  std::string preset = "default";
  double elements_per_radius = 0, fe_time_step_s = 0, inertial_number = 0, balance_threshold = -1;
  double slip_ramp_s = 0, self_propelled_s = 0;
  int min_de_steps = 0, threads = 1;
  unsigned packing_seed = 0;  // 0: the RVE numerics' own (1)
  int relax_steps = -1;  // -1: the preset's; 0 is a valid choice (no relaxation)
  std::string balance_csv;
  double stop_after_s = 0;  // > 0: stop the curve after this much wall time and report its pace
  std::string checkpoint_dir;  // empty: no checkpoints
  double checkpoint_every_s = 600;
  std::string curve_csv;  // empty: the curve on stdout only
  std::string samples_csv;  // empty: the rig's records not kept
  bool bevameter = false;
  bool twin = false;
  bool calibrate = false;
  bool element_tests = false;
  double shear_strain = 1.0;
  std::vector<double> triaxial_pressures_pa = {5e3, 15e3, 40e3};
  double triaxial_strain = 0.1;
  double element_size_m = 0;
  rig::BevameterSpec bevameter_spec;
};

tiers::FeDeOptions OptionsOf(const CommandLine& line) {

  tiers::FeDeOptions options = tiers::FeDeOptions::Preset(line.preset);
  if (line.elements_per_radius > 0) options.elements_per_radius = line.elements_per_radius;
  if (line.fe_time_step_s > 0) options.fe_time_step_s = line.fe_time_step_s;
  if (line.inertial_number > 0) options.numerics.max_inertial_number = line.inertial_number;
  if (line.min_de_steps > 0) options.numerics.min_steps_per_increment = line.min_de_steps;
  if (line.packing_seed > 0) options.numerics.seed = line.packing_seed;
  if (line.relax_steps >= 0) options.numerics.relax_steps = line.relax_steps;
  if (line.balance_threshold >= 0) options.balance.threshold = line.balance_threshold;
  if (line.slip_ramp_s > 0) options.procedure.slip_ramp_s = line.slip_ramp_s;
  if (line.self_propelled_s > 0) options.procedure.self_propelled_s = line.self_propelled_s;
  options.threads = line.threads;
  options.checkpoint_every_s = line.checkpoint_every_s;
  return options;
}

// The options that change the preset's configuration, as "name:value" words ("none" when there
// are none): a curve kept with --curve-csv is comparable only with a run of the same ones.
std::string OverridesOf(const CommandLine& line) {
  std::string words;
  const auto add = [&](const char* name, double value, bool set) {
    if (!set) return;
    char text[96];
    std::snprintf(text, sizeof text, "%s%s:%.17g", words.empty() ? "" : ",", name, value);
    words += text;
  };
  add("grains_per_rve", line.grains_per_rve, line.grains_per_rve > 0);
  add("consolidation_pressure_pa", line.consolidation_pressure_pa,
      line.consolidation_pressure_pa > 0);
  add("elements_per_radius", line.elements_per_radius, line.elements_per_radius > 0);
  add("fe_time_step_s", line.fe_time_step_s, line.fe_time_step_s > 0);
  add("inertial_number", line.inertial_number, line.inertial_number > 0);
  add("min_de_steps", line.min_de_steps, line.min_de_steps > 0);
  add("packing_seed", line.packing_seed, line.packing_seed > 0);
  add("relax_steps", line.relax_steps, line.relax_steps >= 0);
  add("slip_ramp_s", line.slip_ramp_s, line.slip_ramp_s > 0);
  add("self_propelled_s", line.self_propelled_s, line.self_propelled_s > 0);
  return words.empty() ? "none" : words;
}

SoilParameters SoilOf(const CommandLine& line) {
  const tiers::CatalogueEntry* entry =
      tiers::BuiltinSoilCatalogue().Find(line.soil_name, "dem-hertz-mindlin");
  if (entry == nullptr) {
    throw InputError("--soil", "no dem-hertz-mindlin soil '" + line.soil_name + "' in the catalogue");
  }
  SoilParameters soil = entry->parameters;
  if (line.grains_per_rve > 0) soil.values["grains_per_rve"] = line.grains_per_rve;
  if (line.consolidation_pressure_pa > 0) {
    soil.values["consolidation_pressure_pa"] = line.consolidation_pressure_pa;
  }
  return soil;
}

void PrintFigures(const tiers::FeDeRunFigures& figures) {
  if (figures.balance.empty()) return;
  std::fprintf(stderr,
               "load imbalance (max / mean - 1 of RVE seconds per step): mean %.3f, max %.3f; "
               "%d RVEs migrated; %.0f bytes per FE step through rank 0\n",
               figures.MeanImbalance(), figures.MaxImbalance(), figures.PointsMoved(),
               figures.MeanBytesPerStep());
}

ComputeContext ContextOf(const CommandLine& line, int rank) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  ComputeContext context;
  context.threads = line.threads;
  context.communicator = size > 1 ? MPI_COMM_WORLD : MPI_COMM_NULL;
  context.checkpoint_dir = line.checkpoint_dir;
  if (rank == 0) {
    context.progress = [](double fraction) {
      std::fprintf(stderr, "\r  %5.1f %%", 100 * fraction);
      std::fflush(stderr);
    };
  }
  return context;
}

// The Drucker-Prager fit to the soil's RVE triaxials, printed as comment lines (rank 0).
material::DruckerPragerParams FitTwin(const CommandLine& line, const tiers::FeDeTier& tier,
                                      const SoilParameters& soil) {
  const dem::rve::RveMaterialParams params =
      dem::rve::RveMaterialParamsFromSoil(soil, tier.options().numerics, "soil.parameters");
  const auto rve = dem::rve::SharedRveMaterial(params);
  std::vector<tiers::TriaxialCurve> curves;
  for (double pressure : line.triaxial_pressures_pa) {
    std::fprintf(stderr, "triaxial at %.0f Pa\n", pressure);
    curves.push_back(tiers::RunRveTriaxial(*rve, pressure, line.triaxial_strain, 200));
  }
  const tiers::TriaxialFit fit = tiers::FitDruckerPragerToTriaxials(curves);
  std::printf("# RVE drained triaxials (compression positive): sigma3_pa,sigma3_at_peak_pa,"
              "peak_q_pa,axial_strain_at_peak,peak_friction_deg,E50_pa,nu50,dilatancy_at_peak,"
              "psi_deg\n");
  for (size_t k = 0; k < curves.size(); ++k) {
    const tiers::TriaxialCurveFit& c = fit.curves[k];
    const double s3 = c.lateral_stress_at_peak_pa, s1 = s3 + c.peak_deviator_pa;
    std::printf("# %.0f,%.1f,%.1f,%.4f,%.2f,%.4g,%.3f,%.3f,%.2f\n", curves[k].confining_pa, s3,
                c.peak_deviator_pa, c.axial_strain_at_peak,
                units::RadiansToDegrees(std::asin((s1 - s3) / (s1 + s3))), c.secant_young_pa,
                c.secant_poisson, c.dilatancy_at_peak, c.dilation_angle_deg);
  }
  const material::DruckerPragerParams& dp = fit.strength;
  std::printf("# fitted Drucker-Prager (triaxial-compression match): E=%.4g Pa, nu=%.3f, "
              "c=%.1f Pa, phi=%.2f deg, psi=%.2f deg\n",
              dp.young_pa, dp.poisson, dp.cohesion_pa, dp.friction_angle_deg,
              dp.dilation_angle_deg);
  std::fflush(stdout);
  return dp;
}

// Mean of values[from, end).
double MeanFrom(const std::vector<double>& values, std::size_t from) {
  double sum = 0;
  for (std::size_t k = from; k < values.size(); ++k) sum += values[k];
  return sum / static_cast<double>(values.size() - from);
}

// The RVE alone (rank 0): drained triaxials and simple shears, the friction angles each mobilises
// at its peak and over the last fifth of the test, and what Davis's relation
// (HorizontalPlaneFrictionAngleDeg) makes of the triaxials' for a shear ring's horizontal plane.
int RunElementTests(const CommandLine& line, int rank) {
  if (rank != 0) return 0;
  // Checked before any test runs: the fit needs two confinements (the peaks' envelope).
  const std::set<double> confinements(line.triaxial_pressures_pa.begin(),
                                      line.triaxial_pressures_pa.end());
  if (confinements.size() < 2) {
    throw InputError("--triaxial-pressures", "needs two different confining pressures at least");
  }
  const tiers::FeDeTier tier(OptionsOf(line));
  const SoilParameters soil = SoilOf(line);
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(soil, tier.options().numerics, "soil.parameters"));
  const int rows = 200, tail = rows / 5;
  std::vector<tiers::TriaxialCurve> curves;
  for (double pressure : line.triaxial_pressures_pa) {
    std::fprintf(stderr, "triaxial at %.0f Pa\n", pressure);
    curves.push_back(tiers::RunRveTriaxial(*rve, pressure, line.triaxial_strain, rows));
  }
  const tiers::TriaxialFit fit = tiers::FitDruckerPragerToTriaxials(curves);
  std::printf("# RVE drained triaxials to axial strain %.3g (compression positive; end: the last "
              "fifth of the test)\n",
              line.triaxial_strain);
  std::printf("sigma3_pa,peak_friction_deg,axial_strain_at_peak,psi_at_peak_deg,"
              "end_friction_deg,end_dilatancy,ring_peak_deg_davis,ring_end_deg_davis\n");
  for (std::size_t k = 0; k < curves.size(); ++k) {
    const tiers::TriaxialCurve& curve = curves[k];
    const tiers::TriaxialCurveFit& at_peak = fit.curves[k];
    const std::size_t peak = static_cast<std::size_t>(
        std::max_element(curve.deviator_pa.begin(), curve.deviator_pa.end()) -
        curve.deviator_pa.begin());
    const double peak_phi = tiers::MobilisedFrictionAngleDeg(curve, peak);
    double end_phi = 0;
    const std::size_t from = curve.deviator_pa.size() - tail;
    for (std::size_t r = from; r < curve.deviator_pa.size(); ++r) {
      end_phi += tiers::MobilisedFrictionAngleDeg(curve, r) / tail;
    }
    const std::size_t last = curve.axial_strain.size() - 1;
    const double end_dilatancy =
        (curve.volumetric_strain[last] - curve.volumetric_strain[from]) /
        (curve.axial_strain[last] - curve.axial_strain[from]);
    std::printf("%.0f,%.2f,%.4f,%.2f,%.2f,%.3f,%.2f,%.2f\n", curve.confining_pa, peak_phi,
                at_peak.axial_strain_at_peak, at_peak.dilation_angle_deg, end_phi, end_dilatancy,
                tiers::HorizontalPlaneFrictionAngleDeg(
                    peak_phi, std::min(at_peak.dilation_angle_deg, peak_phi)),
                tiers::HorizontalPlaneFrictionAngleDeg(end_phi, 0));
  }
  const material::DruckerPragerParams& dp = fit.strength;
  std::printf("# envelope of the peaks: c %.1f Pa, phi %.2f deg, psi %.2f deg; Davis: a ring "
              "peaks at %.2f deg\n",
              dp.cohesion_pa, dp.friction_angle_deg, dp.dilation_angle_deg,
              tiers::HorizontalPlaneFrictionAngleDeg(dp.friction_angle_deg,
                                                     dp.dilation_angle_deg));
  std::printf("# RVE simple shear to gamma %.3g, sigma_zz held (friction angle: atan(tau / "
              "sigma_zz))\n",
              line.shear_strain);
  std::printf("normal_pa,peak_tau_pa,peak_friction_deg,gamma_at_peak,end_tau_pa,"
              "end_friction_deg\n");
  for (double pressure : line.bevameter_spec.ring_normal_pressures_pa) {
    std::fprintf(stderr, "simple shear at %.0f Pa\n", pressure);
    const tiers::SimpleShearCurve shear =
        tiers::RunRveSimpleShear(*rve, pressure, line.shear_strain, rows);
    const std::size_t peak = static_cast<std::size_t>(
        std::max_element(shear.shear_stress_pa.begin(), shear.shear_stress_pa.end()) -
        shear.shear_stress_pa.begin());
    const std::size_t from = shear.shear_stress_pa.size() - tail;
    const double end_tau = MeanFrom(shear.shear_stress_pa, from);
    const double end_normal = MeanFrom(shear.normal_stress_pa, from);
    std::printf("%.0f,%.1f,%.2f,%.3f,%.1f,%.2f\n", pressure, shear.shear_stress_pa[peak],
                units::RadiansToDegrees(
                    std::atan(shear.shear_stress_pa[peak] / shear.normal_stress_pa[peak])),
                shear.shear_strain[peak], end_tau,
                units::RadiansToDegrees(std::atan(end_tau / end_normal)));
  }
  return 0;
}

int RunBevameter(const CommandLine& line, int rank) {
  const tiers::FeDeTier tier(OptionsOf(line));
  SoilState soil;
  soil.parameters = SoilOf(line);
  std::optional<material::DruckerPragerParams> twin;
  if (line.twin) twin = FitTwin(line, tier, *soil.parameters);
  const tiers::FeDeBevameterReport report =
      tier.RunBevameter(soil, line.bevameter_spec, line.element_size_m, ContextOf(line, rank),
                        twin ? &*twin : nullptr);
  if (rank != 0) return 0;
  std::fprintf(stderr, "\r");
  if (line.twin) {  // what the ring imposes, on the RVE alone: simple shear at its pressures
    const auto rve = dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(
        *soil.parameters, tier.options().numerics, "soil.parameters"));
    std::printf("# RVE simple shear at the ring pressures: normal_pa,peak_tau_pa,gamma_at_peak,"
                "tau_at_gamma_0.5_pa,held_normal_at_peak_pa\n");
    for (double pressure : line.bevameter_spec.ring_normal_pressures_pa) {
      const tiers::SimpleShearCurve shear = tiers::RunRveSimpleShear(*rve, pressure, 0.5, 100);
      const size_t peak = static_cast<size_t>(
          std::max_element(shear.shear_stress_pa.begin(), shear.shear_stress_pa.end()) -
          shear.shear_stress_pa.begin());
      std::printf("# %.0f,%.1f,%.3f,%.1f,%.1f\n", pressure, shear.shear_stress_pa[peak],
                  shear.shear_strain[peak], shear.shear_stress_pa.back(),
                  shear.normal_stress_pa[peak]);
    }
  }
  rig::PrintBevameter(report.bevameter, stdout);
  std::fprintf(stderr, "%s bevameter (%s): %d rank(s) x %d thread(s), %.1f s wall\n",
               tier.Version().c_str(), line.soil_name.c_str(), report.ranks, line.threads,
               report.wall_seconds);
  PrintFigures(report);
  return 0;
}

TractionRequest RequestOf(const CommandLine& line) {
  for (const auto& [value, name] : {std::pair{line.wheel_diameter_m, "--wheel-diameter"},
                                    std::pair{line.wheel_width_m, "--wheel-width"},
                                    std::pair{line.wheel_load_n, "--wheel-load"}}) {
    if (!(value > 0)) throw InputError(name, "is required (a positive number) for a curve");
  }
  TractionRequest request;
  request.soil.parameters = SoilOf(line);
  request.tyre.diameter_m = line.wheel_diameter_m;
  request.tyre.width_m = line.wheel_width_m;
  request.tyre.section_height_m = 0.25 * line.wheel_diameter_m;  // not read by the tier
  request.wheel_load_n = line.wheel_load_n;
  request.slips = TractionRequest::SlipSweep(line.slip_step);
  return request;
}

// The calibration chain (fe_de_calibration.h): RVE triaxials, the Drucker-Prager fit, its
// continuum twin on rank 0, then the fe-de curve on every rank; both curves side by side.
int RunCalibration(const CommandLine& line, int rank) {
  const tiers::FeDeTier tier(OptionsOf(line));
  const TractionRequest request = RequestOf(line);
  tiers::FeDeRunReport twin;
  if (rank == 0) {
    const material::DruckerPragerParams dp = FitTwin(line, tier, *request.soil.parameters);
    ComputeContext alone = ContextOf(line, rank);
    alone.communicator = MPI_COMM_NULL;
    twin = tier.RunContinuumTwin(request, dp, alone);
    std::fprintf(stderr, "\rtwin: %d elements, %d FE steps, %.1f s wall\n", twin.elements,
                 twin.fe_steps, twin.wall_seconds);
  }
  const tiers::FeDeRunReport report = tier.Run(request, ContextOf(line, rank));
  if (rank != 0) return 0;
  std::fprintf(stderr, "\rfe-de: %d elements, %d FE steps, %d rank(s), %.1f s wall\n",
               report.elements, report.fe_steps, report.ranks, report.wall_seconds);
  const double load = request.wheel_load_n, rw = 0.5 * request.tyre.diameter_m * load;
  std::printf("slip,fe_de_DW,twin_DW,fe_de_T_rW,twin_T_rW,fe_de_sinkage_mm,twin_sinkage_mm\n");
  for (size_t k = 0; k < report.curve.points.size() && k < twin.curve.points.size(); ++k) {
    const TractionPoint& a = report.curve.points[k];
    const TractionPoint& b = twin.curve.points[k];
    std::printf("%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%.1f\n", a.slip, a.drawbar_pull_n / load,
                b.drawbar_pull_n / load, a.torque_nm / rw, b.torque_nm / rw, 1e3 * a.sinkage_m,
                1e3 * b.sinkage_m);
  }
  return 0;
}

// A configuration too long to finish here: run it for line.stop_after_s of wall time (alone),
// then report the FE steps done (from the progress, a fraction of the procedure's simulated time)
// and the pace, and the whole curve at that pace.
int MeasurePace(const CommandLine& line, const tiers::FeDeTier& tier,
                const TractionRequest& request, ComputeContext context, int rank) {
  const tiers::FeDePace pace = tiers::MeasureFeDePace(
      tier, request, line.stop_after_s, context, [](double fraction, double elapsed_s) {
        std::fprintf(stderr, "\r  %5.2f %% after %.0f s", 100 * fraction, elapsed_s);
      });
  if (rank != 0) return 0;
  const double procedure_s = pace.total_steps * tier.options().fe_time_step_s;
  std::fprintf(stderr,
               "\n%s, %g grains per RVE: setup %.1f s; %.0f of %.0f FE steps (%.2f %% of the "
               "procedure, %.3f s simulated) in %.1f s, %.2f s per FE step; the whole procedure "
               "at this pace: %.2f h\n",
               tier.Version().c_str(), request.soil.parameters->Get("grains_per_rve"),
               pace.setup_s, pace.steps_done, pace.total_steps, 100 * pace.fraction_done,
               pace.fraction_done * procedure_s, pace.stepping_s, pace.seconds_per_step(),
               pace.projected_s() / 3600);
  return 0;
}

// Writes `text` to `path` whole (WriteFileAtomically: an interrupted run or a crash leaves no
// partial file there), readable as the user's other files are; `option` names the path in the
// error.
void WriteWhole(const std::string& path, const std::string& text, const char* option) {
  try {
    material::checkpoint::WriteFileAtomically(path, text, 0666);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string(option) + ": " + error.what());
  }
}

int Run(const CommandLine& line, int rank) {
  if (line.bevameter) return RunBevameter(line, rank);
  if (line.calibrate) return RunCalibration(line, rank);
  if (line.element_tests) return RunElementTests(line, rank);
  const tiers::FeDeTier tier(OptionsOf(line));
  const TractionRequest request = RequestOf(line);
  const SoilParameters& soil = *request.soil.parameters;
  ComputeContext context = ContextOf(line, rank);
  if (line.stop_after_s > 0) return MeasurePace(line, tier, request, context, rank);
  if (!line.checkpoint_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(line.checkpoint_dir, error);
    if (error) throw InputError("--checkpoint-dir", "cannot be created: " + error.message());
  }
  const tiers::FeDeRunReport report = tier.Run(request, context);
  if (rank != 0) return 0;
  std::fprintf(stderr, "\r");
  tiers::FeDeCurveFile file;
  file.points = report.curve.points;
  file.configuration = tiers::FeDeRigConfiguration(tier.Version(), line.soil_name, line.preset,
                                                    OverridesOf(line), request);
  file.configuration["elements"] = std::to_string(report.elements);
  file.configuration["fe_steps"] = std::to_string(report.fe_steps);
  file.configuration["wall_s_this_run"] = tiers::ConfigurationNumber(report.wall_seconds);
  const std::string text = tiers::FeDeCurveFileText(file);
  std::fputs(text.substr(text.find('\n') + 1).c_str(), stdout);  // the CSV, without the '#' line
  if (!line.curve_csv.empty()) WriteWhole(line.curve_csv, text, "--curve-csv");
  if (!line.samples_csv.empty()) {
    WriteWhole(line.samples_csv, rig::RigSamplesCsv(report.samples), "--samples-csv");
  }
  if (!report.curve.immobile_reason.empty()) {
    std::fprintf(stderr, "immobile: %s\n", report.curve.immobile_reason.c_str());
  }
  std::fprintf(stderr,
               "%s (%s): %d elements (RVEs of %g grains), %d FE steps of %.3g s, %d rank(s) x %d "
               "thread(s), %.1f s wall\n",
               tier.Version().c_str(), line.soil_name.c_str(), report.elements,
               soil.Get("grains_per_rve"), report.fe_steps, report.fe_time_step_s, report.ranks,
               line.threads, report.wall_seconds);
  PrintFigures(report);
  if (!line.checkpoint_dir.empty()) {
    std::fprintf(stderr,
                 "the checkpoint in %s is kept (the same command answers the same curve from it "
                 "without stepping again); delete it when done\n",
                 line.checkpoint_dir.c_str());
  }
  if (!line.balance_csv.empty()) {
    std::ofstream out(line.balance_csv);
    out << "step,imbalance,imbalance_after,points_moved,bytes_sent,bytes_received";
    for (int r = 0; r < report.ranks; ++r) out << ",rank" << r << "_seconds";
    out << "\n";
    for (const bridge::StepBalance& step : report.balance) {
      out << step.step << "," << step.imbalance << "," << step.imbalance_after << ","
          << step.points_moved << "," << step.bytes_sent << "," << step.bytes_received;
      for (double seconds : step.rank_seconds) out << "," << seconds;
      out << "\n";
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine line;
  CLI::App app{"gonogo-fe-de: one fe-de traction curve (FE soil with a DE RVE per point)",
               "gonogo-fe-de"};
  const CLI::Validator finite = cli_checks::FiniteNumber();
  app.add_option("--soil", line.soil_name, "dem-hertz-mindlin soil of the catalogue")
      ->capture_default_str();
  app.add_option("--grains-per-rve", line.grains_per_rve, "override the soil's grains per RVE")
      ->check(finite);
  app.add_option("--consolidation-pressure", line.consolidation_pressure_pa,
                 "override the RVE's preparation pressure, Pa")
      ->check(finite);
  app.add_option("--wheel-diameter", line.wheel_diameter_m, "m (a curve)")->check(finite);
  app.add_option("--wheel-width", line.wheel_width_m, "m (a curve)")->check(finite);
  app.add_option("--wheel-load", line.wheel_load_n, "N (a curve)")->check(finite);
  CLI::Option* calibrate =
      app.add_flag("--calibrate", line.calibrate,
                   "the calibration chain: RVE triaxials, a Drucker-Prager fit, and its continuum "
                   "twin's curve beside the fe-de curve");
  CLI::Option* element_tests =
      app.add_flag("--element-tests", line.element_tests,
                   "the RVE alone: drained triaxials at --triaxial-pressures and simple shears at "
                   "--ring-pressures, their friction angles, and what a shear ring should measure "
                   "(Davis's relation)");
  app.add_option("--shear-strain", line.shear_strain,
                 "element tests: shear strain the simple shears reach")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--triaxial-pressures", line.triaxial_pressures_pa,
                 "calibration: confining pressures of the RVE triaxials, Pa")
      ->delimiter(',')
      ->check(finite);
  app.add_option("--triaxial-strain", line.triaxial_strain,
                 "calibration: axial strain the triaxials reach")
      ->check(finite)
      ->capture_default_str();
  app.add_flag("--twin", line.twin,
               "bevameter: on the continuum twin (the Drucker-Prager fit to the RVE triaxials) "
               "instead of the RVEs");
  CLI::Option* bevameter =
      app.add_flag("--bevameter", line.bevameter,
                   "run the virtual bevameter (plates and shear rings) instead of a curve");
  app.add_option("--element-size", line.element_size_m,
                 "bevameter: bin resolution, m (0: a quarter of the small plate / ring width)")
      ->check(finite);
  app.add_option("--ring-pressures", line.bevameter_spec.ring_normal_pressures_pa,
                 "bevameter: shear-ring normal pressures, Pa")
      ->delimiter(',')
      ->check(finite);
  app.add_option("--plate-radius", line.bevameter_spec.small_plate_radius_m,
                 "bevameter: the small plate's radius, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--large-plate-radius", line.bevameter_spec.large_plate_radius_m,
                 "bevameter: the large plate's radius, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--ring-inner-radius", line.bevameter_spec.ring_inner_radius_m,
                 "bevameter: shear ring, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--ring-outer-radius", line.bevameter_spec.ring_outer_radius_m,
                 "bevameter: shear ring, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--start-ramp-s", line.bevameter_spec.start_ramp_s,
                 "bevameter: smooth start of the plate push and the ring's turn, s")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--ring-damping", line.bevameter_spec.ring_damping_fraction,
                 "bevameter: mass damping while the ring turns, fraction of the settling damping")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--plate-sinkage", line.bevameter_spec.plate_sinkage_m,
                 "bevameter: plate push depth, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--ring-displacement", line.bevameter_spec.ring_shear_displacement_m,
                 "bevameter: ring shear displacement at its mean radius, m")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--slip-step", line.slip_step, "slips 0, step, ... 1")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--preset", line.preset, "default, ci or tiny")->capture_default_str();
  app.add_option("--elements-per-radius", line.elements_per_radius, "R / h")->check(finite);
  app.add_option("--fe-time-step", line.fe_time_step_s, "FE step by mass scaling, s")
      ->check(finite);
  app.add_option("--min-de-steps", line.min_de_steps, "DE steps at least per FE increment");
  app.add_option("--relax-steps", line.relax_steps,
                 "DE steps with the cell held after each increment (0: none)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--packing-seed", line.packing_seed,
                 "seed of the template RVE's random grain placement (0: the numerics' own, 1): "
                 "another packing of the same soil");
  app.add_option("--inertial-number", line.inertial_number, "DE strain-rate cap")->check(finite);
  app.add_option("--balance-threshold", line.balance_threshold,
                 "migrate RVEs when max / mean - 1 of the ranks' RVE seconds exceeds it")
      ->check(finite);
  app.add_option("--slip-ramp-s", line.slip_ramp_s, "procedure: slip ramp, s")->check(finite);
  app.add_option("--self-propelled-s", line.self_propelled_s, "procedure: rolling at slip 0, s")
      ->check(finite);
  app.add_option("--threads", line.threads, "OpenMP threads per rank")
      ->check(cli_checks::AtLeastOne())
      ->capture_default_str();
  CLI::Option* stop_after =
      app.add_option("--stop-after-s", line.stop_after_s,
                     "stop the curve after this wall time and report its pace (configurations too "
                     "long to finish)")
          ->check(finite);
  app.add_option("--balance-csv", line.balance_csv, "write the per-step balance records here");
  CLI::Option* checkpoint_dir =
      app.add_option("--checkpoint-dir", line.checkpoint_dir,
                     "checkpoint the curve here; the same command run again resumes from it (a "
                     "directory on a file system every rank shares)");
  app.add_option("--checkpoint-every-s", line.checkpoint_every_s,
                 "wall seconds between checkpoints")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str()
      ->needs(checkpoint_dir);
  // Both are a whole curve's: the other runs neither checkpoint nor end in one curve.
  app.add_option("--curve-csv", line.curve_csv,
                 "also write the curve here, its configuration on a first '#' line "
                 "(gonogo-bench-fe-ann --fe-de-curve reads it)")
      ->excludes(calibrate, element_tests, bevameter, stop_after);
  app.add_option("--samples-csv", line.samples_csv,
                 "also write the rig's 5 ms records here (time, phase, slip, speeds, drawbar pull, "
                 "torque, vertical force, sinkage; SI units): the curve is their mean over each "
                 "slip's window")
      ->excludes(calibrate, element_tests, bevameter, stop_after);
  checkpoint_dir->excludes(calibrate, element_tests, bevameter, stop_after);
  CLI11_PARSE(app, argc, argv);

  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  int status = 0;
  try {
    status = Run(line, rank);
  } catch (const InputError& e) {
    if (rank == 0) std::fprintf(stderr, "gonogo-fe-de: %s\n", e.what());
    status = 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gonogo-fe-de (rank %d): %s\n", rank, e.what());
    status = 1;
  }
  if (status != 0) MPI_Abort(MPI_COMM_WORLD, status);
  MPI_Finalize();
  return status;
}
