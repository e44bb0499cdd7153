// Throughput of the bekker traction tier: curves per second with 100 slip steps (101 points).
//
//   build/tests/bench/gonogo-bench-bekker [--seconds 2]
//
// For each of a few built-in soils, computes the FED Alpha wheel (seed 001 Table 4: d 1.011 m,
// b 0.335 m, 13438 N, inflation pressure not given, so the Wong-Reece rigid wheel) on slips 0,
// 0.01, ..., 1 for about SECONDS seconds on one thread and prints curves per second, the time
// per curve and the mean time per slip point; then the same for the elastic mode (100 kPa on
// dry sand, below its critical pressure of 171 kPa).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solvers/tiers/bekker_tier.h"

using gonogo::TractionCurve;
using gonogo::TractionRequest;
using gonogo::TyreGeometry;
using Clock = std::chrono::steady_clock;

namespace {

struct Row {
  std::string label;
  TractionRequest request;
};

TractionRequest FedAlpha(const std::string& soil, double inflation_pa) {
  TractionRequest r;
  r.soil.soil_name = soil;
  r.tyre = TyreGeometry{1.011, 0.335, 0.65 * 0.335, 0.15 * 0.65 * 0.335, 0.505, inflation_pa};
  r.wheel_load_n = 13438;
  r.slips = TractionRequest::SlipSweep(0.01);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  CLI::App app(
      "Throughput of the bekker traction tier: for each of a few built-in soils, computes the FED "
      "Alpha wheel on slips 0, 0.01, ..., 1 for about SECONDS seconds on one thread and prints "
      "curves per second, the time per curve and the mean time per slip point; then the same for "
      "the elastic mode.",
      "gonogo-bench-bekker");
  app.add_option("--seconds", seconds, "time spent on each soil and mode, s")
      ->check(CLI::Validator(
          [](std::string& text) {
            double value = 0;
            if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || value <= 0) {
              return "needs a finite number > 0, got '" + text + "'";
            }
            return std::string();
          },
          "> 0", "POSITIVE"))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const gonogo::tiers::BekkerTier tier;
  const std::vector<Row> rows = {
      {"lll_dry_sand rigid", FedAlpha("lll_dry_sand", 0)},
      {"lete_sand rigid", FedAlpha("lete_sand", 0)},
      {"wes_heavy_clay_25pct rigid", FedAlpha("wes_heavy_clay_25pct", 0)},
      {"rubicon_sandy_loam_43pct rigid", FedAlpha("rubicon_sandy_loam_43pct", 0)},
      {"lll_dry_sand elastic 100 kPa", FedAlpha("lll_dry_sand", 100e3)},
  };
  std::printf("bekker tier, %zu slip points per curve, one thread\n",
              rows.front().request.slips.size());
  std::printf("%-32s %12s %12s %14s %10s\n", "soil / mode", "curves/s", "ms/curve", "us/point",
              "D(0.2)/W");
  for (const Row& row : rows) {
    int curves = 0;
    double checksum = 0;
    const auto start = Clock::now();
    double elapsed = 0;
    while (elapsed < seconds) {
      const TractionCurve c = tier.Compute(row.request);
      checksum += c.DrawbarPullAt(0.2);
      ++curves;
      elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    }
    const double per_curve = elapsed / curves;
    std::printf("%-32s %12.1f %12.3f %14.2f %10.4f\n", row.label.c_str(), curves / elapsed,
                per_curve * 1e3, per_curve * 1e6 / row.request.slips.size(),
                checksum / curves / row.request.wheel_load_n);
  }
  return 0;
}
