// gonogo curve | scalability: one wheel on one soil, through the server's traction tiers.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "clients/cli_commands.h"
#include "clients/cli_wheel_soil.h"

namespace gonogo::cli {
namespace {

namespace fs = std::filesystem;

struct CurveOptions {
  std::string tier;
  WheelOptions wheel;
  SoilOptions soil;
  double slip_step = 0;  // 0: the server's default, 0.05
  bool csv = false;
  bool no_similarity = false;
  bool job = false;
  bool no_wait = false;
  SurrogateOptions surrogate;  // fe-ann
};

struct ScalabilityOptions {
  std::string tier;
  WheelOptions wheel;
  SoilOptions soil;
  double slip_step = 0;
  std::vector<double> scales = {1, 0.7, 0.5, 0.25};
  std::string out_dir;
};

// Whether the server computes curves of `tier` only as jobs (SubmitCurve); false when the tier is
// unknown (the curve query then reports it).
bool CurvesAreJobs(Client& client, const std::string& tier) {
  grpc::ClientContext ctx;
  v1::ListTiersResponse resp;
  if (!client.stub().ListTiers(&ctx, v1::ListTiersRequest{}, &resp).ok()) return false;
  for (const auto& t : resp.tiers()) {
    if (t.name() == tier) return t.curves_are_jobs();
  }
  return false;
}

// A curve that takes minutes is a job: submitted, watched with a progress bar, then fetched.
// Returns kExitOk with `curve` filled, or the exit code. With `no_wait` it prints the job id and
// returns kExitOk with `curve` untouched.
int CurveAsJob(Client& client, const v1::GetTractionCurveRequest& req, bool no_wait,
               v1::TractionCurve* curve) {
  v1::Job job;
  {
    grpc::ClientContext ctx;
    const grpc::Status s = client.stub().SubmitCurve(&ctx, req, &job);
    if (!s.ok()) return Fail(s);
  }
  std::cerr << "curve job " << job.job_id() << " (gonogo watch / cancel " << job.job_id() << ")\n";
  if (no_wait) {
    std::cout << job.job_id() << "\n";
    return kExitOk;
  }
  return client.WaitForSummary(job.job_id(), "curve job", curve);
}

void PrintCurveCsv(const v1::TractionCurve& curve) {
  std::cout << "slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency,gross_traction_n,"
               "motion_resistance_n\n";
  for (const auto& pt : curve.points()) {
    std::cout << pt.slip() << "," << pt.drawbar_pull_n() << "," << pt.torque_nm() << ","
              << pt.sinkage_m() << "," << pt.tractive_efficiency() << "," << pt.gross_traction_n()
              << "," << pt.motion_resistance_n() << "\n";
  }
}

// How an fe-ann curve answered its points: "surrogate run: 3 of its points fell back to their
// RVEs, at steps 449, 450 and 637 of 900 (3 paths kept for training); network 2.28 s for 114041
// point updates, fallbacks 1.01 s"; "..., at steps 0, 0, ... of 900, 66 below the pressure floor
// (...)" where the guard's floor flagged them.
void PrintSurrogateRun(const v1::SurrogateRun& run) {
  constexpr int kStepsShown = 8;
  std::cout << "surrogate run: ";
  if (run.fallbacks() == 0) {
    std::cout << "no point fell back to its RVE in " << run.fe_steps() << " FE steps";
  } else {
    std::cout << run.fallbacks() << (run.fallbacks() == 1 ? " point" : " of its points")
              << " fell back to " << (run.fallbacks() == 1 ? "its RVE" : "their RVEs")
              << ", at step";
    const int steps = run.fallback_point_steps_size();
    std::cout << (steps == 1 ? " " : "s ");
    for (int k = 0; k < std::min(steps, kStepsShown); ++k) {
      std::cout << (k == 0 ? "" : k + 1 == steps ? " and " : ", ") << run.fallback_point_steps(k);
    }
    if (steps > kStepsShown) std::cout << " and " << steps - kStepsShown << " more";
    std::cout << " of " << run.fe_steps();
    // Which of the guard's tests flagged them (one point may be flagged by several).
    if (run.fallbacks_beyond_distance() > 0) {
      std::cout << ", " << run.fallbacks_beyond_distance() << " beyond the envelope's distance";
    }
    if (run.fallbacks_beyond_spread() > 0) {
      std::cout << ", " << run.fallbacks_beyond_spread() << " beyond the members' spread";
    }
    if (run.fallbacks_below_pressure_floor() > 0) {
      std::cout << ", " << run.fallbacks_below_pressure_floor() << " below the pressure floor";
    }
    if (run.returns() > 0) std::cout << ", " << run.returns() << " sent back to the network";
    if (run.fallback_paths_kept() > 0) {
      std::cout << " (" << run.fallback_paths_kept() << " paths kept for training)";
    }
  }
  if (run.unanswered_flags() > 0) {
    std::cout << "; " << run.unanswered_flags() << " flagged updates answered by the network "
              << "(fallback off)";
  }
  std::cout << "; network " << FormatNumber(run.network_seconds()) << " s for "
            << run.network_point_updates() << " point updates";
  if (run.fallbacks() > 0) {
    std::cout << ", fallbacks " << FormatNumber(run.fallback_seconds()) << " s";
  }
  std::cout << "\n";
}

// Where the curve came from: tier, load, soil, cache or computation, similarity.
void PrintCurveHeading(const v1::TractionCurve& curve) {
  const auto& p = curve.provenance();
  std::cout << "tier " << p.tier() << " (" << p.tier_version() << "), wheel load "
            << curve.wheel_load_n() << " N, ";
  if (!curve.soil().soil_name().empty()) std::cout << "soil " << curve.soil().soil_name() << ", ";
  if (curve.soil().has_parameters()) {
    std::cout << "explicit " << curve.soil().parameters().model() << " parameters, ";
  }
  if (curve.soil().cone_index_pa() > 0) {
    std::cout << "cone index " << curve.soil().cone_index_pa() / 1000 << " kPa, ";
  }
  if (!p.surrogate_model().empty()) std::cout << "surrogate model " << p.surrogate_model() << ", ";
  std::cout << (p.cache_hit() ? "from the cache" : "computed") << " by " << p.computed_by() << "\n";
  if (p.has_surrogate_run()) PrintSurrogateRun(p.surrogate_run());
  if (p.similarity_hit()) {
    const auto& r = p.reliability();
    std::cout << "similarity hit: scaled from a tyre " << 1 / p.similarity_scale_ratio()
              << " times this size; seed 001 measured at scale " << r.reference_scale() << " on "
              << r.reference_soil() << ": " << r.drawbar_pull_pct() << " % (D/W), "
              << r.gross_traction_pct() << " % (T/rW), " << r.efficiency_pct()
              << " % (efficiency) of points inside the full-scale band\n";
  }
}

void PrintCurveTable(const v1::TractionCurve& curve) {
  PrintCurveHeading(curve);
  std::cout << std::right << std::setw(6) << "slip" << std::setw(14) << "drawbar_N" << std::setw(14)
            << "torque_Nm" << std::setw(12) << "sinkage_m" << std::setw(12) << "efficiency"
            << "\n";
  for (const auto& pt : curve.points()) {
    std::cout << std::fixed << std::setprecision(3) << std::setw(6) << pt.slip()
              << std::setprecision(1) << std::setw(14) << pt.drawbar_pull_n() << std::setw(14)
              << pt.torque_nm() << std::setprecision(4) << std::setw(12) << pt.sinkage_m()
              << std::setprecision(3) << std::setw(12) << pt.tractive_efficiency() << "\n";
  }
}

int RunCurve(Client& client, const CurveOptions& o) {
  v1::GetTractionCurveRequest req;
  req.set_tier(o.tier);
  *req.mutable_soil() = SoilFromOptions(o.soil);
  req.set_slip_step(o.slip_step);
  req.set_disable_similarity(o.no_similarity);
  req.set_surrogate_model(o.surrogate.model);
  *req.mutable_surrogate_guard() = GuardFromOptions(o.surrogate);
  double load = 0;
  WheelFromOptions(o.wheel, req.mutable_tyre(), &load);
  req.set_wheel_load_n(load);
  v1::TractionCurve curve;
  if (o.job || CurvesAreJobs(client, req.tier())) {
    const int rc = CurveAsJob(client, req, o.no_wait, &curve);
    if (rc != kExitOk || o.no_wait) return rc;
  } else {
    grpc::ClientContext ctx;
    const grpc::Status s = client.stub().GetTractionCurve(&ctx, req, &curve);
    if (!s.ok()) return Fail(s);
  }
  if (o.csv) {
    PrintCurveCsv(curve);
  } else {
    PrintCurveTable(curve);
  }
  std::cerr << (curve.provenance().similarity_hit() ? "source cache key: " : "cache key: ")
            << curve.provenance().cache_key() << "\n";
  return kExitOk;
}

// One row of the scalability study in each table: curves CSV, summary CSV and the printed table.
void WriteScalabilityRow(const v1::ScalabilityRow& row, std::ostream& curves,
                         std::ostream& summary) {
  const double r = row.tyre().rolling_radius_m() > 0
                       ? row.tyre().rolling_radius_m()
                       : row.tyre().diameter_m() / 2 - row.tyre().deflection_m();
  for (const auto& p : row.points()) {
    curves << row.scale() << "," << p.slip() << "," << p.drawbar_pull_n() / row.wheel_load_n()
           << "," << p.torque_nm() / (r * row.wheel_load_n()) << "," << p.tractive_efficiency()
           << "," << p.drawbar_pull_n() << "," << p.torque_nm() << "," << p.sinkage_m() << ","
           << row.wheel_load_n() << "," << r << "\n";
  }
  const auto& m = row.seed_measured();
  summary << row.scale() << "," << row.tyre().diameter_m() << "," << row.tyre().width_m() << ","
          << row.wheel_load_n() << "," << row.drawbar_pull_inside_pct() << ","
          << row.gross_traction_inside_pct() << "," << row.efficiency_inside_pct() << ","
          << m.reference_soil() << "," << m.reference_scale() << "," << m.drawbar_pull_pct() << ","
          << m.gross_traction_pct() << "," << m.efficiency_pct() << ","
          << (row.immobile_reason().empty() ? "" : "yes") << "\n";
  std::ostringstream inside, seed;
  inside << std::fixed << std::setprecision(1) << row.drawbar_pull_inside_pct() << "  "
         << row.gross_traction_inside_pct() << "  " << row.efficiency_inside_pct();
  if (!row.immobile_reason().empty()) {
    inside.str("cannot carry");
    std::cerr << "scale " << row.scale() << ": " << row.immobile_reason() << "\n";
  }
  if (row.has_seed_measured()) {
    seed << m.reference_soil() << " " << m.reference_scale() << ": " << m.drawbar_pull_pct() << "  "
         << m.gross_traction_pct() << "  " << m.efficiency_pct();
  }
  std::cout << std::left << std::setw(7) << row.scale() << std::setw(10) << row.tyre().diameter_m()
            << std::setw(11) << row.wheel_load_n() << std::setw(22) << inside.str() << "  "
            << seed.str() << "\n";
}

// The plot, scalability_curves.csv and scalability_summary.csv in `out`, the table on stdout.
void WriteScalabilityReport(const v1::ScalabilityReport& report, const fs::path& out) {
  fs::create_directories(out);
  std::ofstream(out / "scalability.png", std::ios::binary) << report.plot_png();
  std::ofstream curves(out / "scalability_curves.csv");
  curves << "scale,slip,drawbar_pull_coefficient,gross_traction_coefficient,tractive_efficiency,"
            "drawbar_pull_n,torque_nm,sinkage_m,wheel_load_n,rolling_radius_m\n";
  std::ofstream summary(out / "scalability_summary.csv");
  summary << "scale,diameter_m,width_m,wheel_load_n,drawbar_pull_inside_pct,"
             "gross_traction_inside_pct,efficiency_inside_pct,seed_soil,seed_scale,"
             "seed_drawbar_pull_pct,seed_gross_traction_pct,seed_efficiency_pct,immobile\n";
  std::cout << "band (one SD of the full-scale coefficient): D/W " << report.band_drawbar_pull()
            << ", T/(rW) " << report.band_gross_traction() << ", efficiency "
            << report.band_efficiency() << "\n";
  std::cout << std::left << std::setw(7) << "scale" << std::setw(10) << "d_m" << std::setw(11)
            << "W_N" << std::setw(22) << "inside: D/W  T/rW  eff"
            << "  seed 001 measured\n";
  for (const auto& row : report.rows()) WriteScalabilityRow(row, curves, summary);
  std::cerr << "wrote " << (out / "scalability.png").string() << ", "
            << (out / "scalability_curves.csv").string() << ", "
            << (out / "scalability_summary.csv").string() << "\n";
}

int RunScalability(Client& client, const ScalabilityOptions& o) {
  v1::ScalabilityRequest req;
  req.set_tier(o.tier);
  *req.mutable_soil() = SoilFromOptions(o.soil);
  double load = 0;
  WheelFromOptions(o.wheel, req.mutable_tyre(), &load);
  req.set_wheel_load_n(load);
  req.set_slip_step(o.slip_step);
  for (const double scale : o.scales) req.add_scales(scale);
  grpc::ClientContext ctx;
  v1::ScalabilityReport report;
  const grpc::Status s = client.stub().RunScalability(&ctx, req, &report);
  if (!s.ok()) return Fail(s);
  WriteScalabilityReport(report, o.out_dir);
  return kExitOk;
}

// --tier and --slip-step, which both commands take.
void AddTierAndSlipStep(CLI::App& app, std::string* tier, double* slip_step) {
  app.add_option("--tier", *tier, "traction tier (gonogo tiers lists them)")
      ->required()
      ->type_name("T");
  app.add_option("--slip-step", *slip_step, "spacing of the slip sweep, 0..1 (default 0.05)")
      ->type_name("S")
      ->check(Fraction());
}

}  // namespace

Command AddCurveCommand(CLI::App& parent) {
  auto o = std::make_shared<CurveOptions>();
  CLI::App* curve = parent.add_subcommand("curve", "one wheel's traction curve on one soil");
  curve->footer(
      "Prints drawbar pull, torque, sinkage and tractive efficiency over slip, and the cache key.\n"
      "A tier that takes minutes (gonogo tiers) runs as a job with a progress bar; --job does so "
      "for any tier,\n--no-wait then prints the job id and returns (gonogo watch / cancel ID).");
  AddTierAndSlipStep(*curve, &o->tier, &o->slip_step);
  AddWheelOptions(*curve, &o->wheel);
  AddSoilOptions(*curve, &o->soil);
  curve->add_flag("--csv", o->csv,
                  "print CSV: slip, drawbar_pull_n, torque_nm, sinkage_m, "
                  "tractive_efficiency, gross_traction_n, motion_resistance_n");
  curve->add_flag("--no-similarity", o->no_similarity,
                  "answer only from an exact cache key or fresh computation");
  AddSurrogateOptions(*curve, &o->surrogate,
                      "the surrogate model (gonogo models lists them); default: the soil's best");
  curve->add_flag("--job", o->job, "run as a job with a progress bar, whatever the tier");
  curve->add_flag("--no-wait", o->no_wait, "when the curve runs as a job: print its id, return");
  return {curve, [o](Client& client) { return RunCurve(client, *o); }};
}

Command AddScalabilityCommand(CLI::App& parent) {
  auto o = std::make_shared<ScalabilityOptions>();
  CLI::App* scalability = parent.add_subcommand(
      "scalability", "seed 001's scaled-tyre study for one wheel on one soil");
  scalability->footer(
      "The tyre is scaled down at equal W/(b d) and each scale's curve compared with the "
      "full-scale tyre's\nband. Writes scalability.png, scalability_curves.csv and "
      "scalability_summary.csv into --out.");
  AddTierAndSlipStep(*scalability, &o->tier, &o->slip_step);
  AddWheelOptions(*scalability, &o->wheel);
  AddSoilOptions(*scalability, &o->soil);
  scalability
      ->add_option("--scales", o->scales, "length ratios in (0, 1], one of them 1; at most 8")
      ->delimiter(',')
      ->type_name("S,S,...")
      ->capture_default_str();
  scalability->add_option("--out", o->out_dir, "directory for the plot and the tables")
      ->required()
      ->type_name("DIR");
  return {scalability, [o](Client& client) { return RunScalability(client, *o); }};
}

}  // namespace gonogo::cli
