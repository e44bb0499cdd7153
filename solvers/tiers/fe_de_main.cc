// gonogo-fe-de: one fe-de traction curve from the command line, alone or collectively under
// mpirun (every rank of MPI_COMM_WORLD in the group: rank 0 runs the FE, all ranks hold RVEs).
//
//   gonogo-fe-de --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2
//                --wheel-load 1000 --preset ci [--slip-step 0.25] [overrides ...]
//   mpirun -np 3 gonogo-fe-de ... (same options on every rank)
//
// Prints the curve as CSV (the columns of `gonogo curve --csv`) on stdout and the run's figures
// (mesh, FE steps, ranks, wall time, load imbalance, migrations, bytes per step) on stderr; with
// --balance-csv FILE, one row per FE step of the balance records. Exit status: 0 done, 1 failed,
// 2 bad options.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include "solvers/common/cli_checks.h"
#include "solvers/common/errors.h"
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
  int relax_steps = -1;  // -1: the preset's; 0 is a valid choice (no relaxation)
  std::string balance_csv;
};

int Run(const CommandLine& line, int rank) {
  tiers::FeDeOptions options = tiers::FeDeOptions::Preset(line.preset);
  if (line.elements_per_radius > 0) options.elements_per_radius = line.elements_per_radius;
  if (line.fe_time_step_s > 0) options.fe_time_step_s = line.fe_time_step_s;
  if (line.inertial_number > 0) options.numerics.max_inertial_number = line.inertial_number;
  if (line.min_de_steps > 0) options.numerics.min_steps_per_increment = line.min_de_steps;
  if (line.relax_steps >= 0) options.numerics.relax_steps = line.relax_steps;
  if (line.balance_threshold >= 0) options.balance.threshold = line.balance_threshold;
  if (line.slip_ramp_s > 0) options.procedure.slip_ramp_s = line.slip_ramp_s;
  if (line.self_propelled_s > 0) options.procedure.self_propelled_s = line.self_propelled_s;
  options.threads = line.threads;
  const tiers::FeDeTier tier(options);

  TractionRequest request;
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
  request.soil.parameters = soil;
  request.tyre.diameter_m = line.wheel_diameter_m;
  request.tyre.width_m = line.wheel_width_m;
  request.tyre.section_height_m = 0.25 * line.wheel_diameter_m;  // not read by the tier
  request.wheel_load_n = line.wheel_load_n;
  request.slips = TractionRequest::SlipSweep(line.slip_step);

  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  ComputeContext context;
  context.threads = line.threads;
  context.communicator = size > 1 ? MPI_COMM_WORLD : MPI_COMM_NULL;
  if (rank == 0) {
    context.progress = [](double fraction) {
      std::fprintf(stderr, "\r  %5.1f %%", 100 * fraction);
      std::fflush(stderr);
    };
  }
  const tiers::FeDeRunReport report = tier.Run(request, context);
  if (rank != 0) return 0;
  std::fprintf(stderr, "\r");
  std::printf("slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency,gross_traction_n,"
              "motion_resistance_n\n");
  for (const TractionPoint& p : report.curve.points) {
    std::printf("%.4f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", p.slip, p.drawbar_pull_n, p.torque_nm,
                p.sinkage_m, p.tractive_efficiency, p.gross_traction_n, p.motion_resistance_n);
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
  if (!report.balance.empty()) {
    std::fprintf(stderr,
                 "load imbalance (max / mean - 1 of RVE seconds per step): mean %.3f, max %.3f; "
                 "%d RVEs migrated; %.0f bytes per FE step through rank 0\n",
                 report.MeanImbalance(), report.MaxImbalance(), report.PointsMoved(),
                 report.MeanBytesPerStep());
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
  CLI::App app{"gonogo-fe-de: one fe-de traction curve (FE soil with a DE RVE per point)"};
  const CLI::Validator finite = cli_checks::FiniteNumber();
  app.add_option("--soil", line.soil_name, "dem-hertz-mindlin soil of the catalogue")
      ->capture_default_str();
  app.add_option("--grains-per-rve", line.grains_per_rve, "override the soil's grains per RVE")
      ->check(finite);
  app.add_option("--consolidation-pressure", line.consolidation_pressure_pa,
                 "override the RVE's preparation pressure, Pa")
      ->check(finite);
  app.add_option("--wheel-diameter", line.wheel_diameter_m, "m")->required()->check(finite);
  app.add_option("--wheel-width", line.wheel_width_m, "m")->required()->check(finite);
  app.add_option("--wheel-load", line.wheel_load_n, "N")->required()->check(finite);
  app.add_option("--slip-step", line.slip_step, "slips 0, step, ... 1")
      ->check(finite)
      ->capture_default_str();
  app.add_option("--preset", line.preset, "default or ci")->capture_default_str();
  app.add_option("--elements-per-radius", line.elements_per_radius, "R / h")->check(finite);
  app.add_option("--fe-time-step", line.fe_time_step_s, "FE step by mass scaling, s")
      ->check(finite);
  app.add_option("--min-de-steps", line.min_de_steps, "DE steps at least per FE increment");
  app.add_option("--relax-steps", line.relax_steps,
                 "DE steps with the cell held after each increment (0: none)")
      ->check(CLI::NonNegativeNumber);
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
  app.add_option("--balance-csv", line.balance_csv, "write the per-step balance records here");
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
