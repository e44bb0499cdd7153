// The seed 000 RVE's drained triaxial test against a peer code: LIGGGHTS 3.8 runs the same
// protocol (500 grains, random gas at solid fraction 0.25, frictionless isotropic consolidation
// to 100 kPa, drained triaxial compression at inertial number 1e-3 with the lateral stresses held
// at 100 kPa, to 10 % axial strain) with the same contact law, seeds 1..8 in each code. A single
// 500-grain packing is one sample of a chaotic system, so the two codes are compared as samples:
// the difference of their means against the seed-to-seed scatter of both.
//
// Data: tests/solvers/dem/data/liggghts_rve_triaxial.csv (solvers/dem/bench/
// liggghts_rve_triaxial.sh) and gonogo_rve_triaxial.csv (solvers/dem/bench/
// gonogo_rve_triaxial_seeds.sh); solvers/dem/rve/README.md, "Triaxial against LIGGGHTS".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/common/units.h"
#include "solvers/dem/rve/rve.h"

namespace gonogo::dem::rve {
namespace {

// |mean_gonogo - mean_liggghts| <= kScatterMultiple x the pooled seed-to-seed standard deviation.
// With n seeds per code the standard error of the difference is sd sqrt(2 / n), so the bound is
// |t| <= 2 sqrt(n / 2): with the committed n = 8 a two-sided t-test (14 degrees of freedom) at
// 0.13 % (|t| <= 4); with n = 4, 3 % (|t| <= 2.83). A fresh sample from codes that agree thus fails
// rarely, while a shift of 5 deg in the peak friction angle (about 0.2 in q/p, five pooled
// standard deviations) fails for certain (checked below).
constexpr double kScatterMultiple = 2.0;
constexpr int kMinimumSeeds = 4;

struct SeedSummary {
  int seed = 0;
  double peak_q_over_p = 0.0;
  double axial_strain_at_peak = 0.0;
  double largest_dilation = 0.0;
};

std::vector<SeedSummary> ReadSummary(const std::string& file_name) {
  const char* source = std::getenv("GONOGO_SOURCE_DIR");
  const std::string path =
      std::string(source ? source : ".") + "/tests/solvers/dem/data/" + file_name;
  std::ifstream in(path);
  EXPECT_TRUE(in) << path << " not found (GONOGO_SOURCE_DIR)";
  std::string line;
  std::getline(in, line);
  std::map<std::string, int> column;
  {
    std::stringstream header(line);
    std::string name;
    for (int k = 0; std::getline(header, name, ','); ++k) column[name] = k;
  }
  for (const char* name : {"seed", "peak_q_over_p", "axial_strain_at_peak", "largest_dilation"}) {
    EXPECT_TRUE(column.count(name)) << file_name << " has no column " << name;
    if (!column.count(name)) return {};
  }
  std::vector<SeedSummary> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string field; std::getline(ss, field, ',');) fields.push_back(field);
    auto at = [&](const char* name) { return std::atof(fields.at(column.at(name)).c_str()); };
    rows.push_back({static_cast<int>(at("seed")), at("peak_q_over_p"), at("axial_strain_at_peak"),
                    at("largest_dilation")});
  }
  return rows;
}

const std::vector<SeedSummary>& Gonogo() {
  static const std::vector<SeedSummary> rows = ReadSummary("gonogo_rve_triaxial.csv");
  return rows;
}
const std::vector<SeedSummary>& Liggghts() {
  static const std::vector<SeedSummary> rows = ReadSummary("liggghts_rve_triaxial.csv");
  return rows;
}

struct Sample {
  double mean = 0.0;
  double sd = 0.0;  // sample standard deviation (n - 1)
  int n = 0;
};

Sample SampleOf(const std::vector<double>& values) {
  Sample s;
  s.n = static_cast<int>(values.size());
  for (double v : values) s.mean += v / s.n;
  for (double v : values) s.sd += (v - s.mean) * (v - s.mean) / (s.n - 1);
  s.sd = std::sqrt(s.sd);
  return s;
}

std::vector<double> Column(const std::vector<SeedSummary>& rows, double SeedSummary::*field) {
  std::vector<double> values;
  for (const SeedSummary& row : rows) values.push_back(row.*field);
  return values;
}

struct Comparison {
  Sample gonogo, liggghts;
  double difference = 0.0;  // mean gonogo - mean LIGGGHTS
  double pooled_sd = 0.0;
  bool agree = false;
};

Comparison Compare(const std::vector<double>& gonogo, const std::vector<double>& liggghts) {
  Comparison c;
  c.gonogo = SampleOf(gonogo);
  c.liggghts = SampleOf(liggghts);
  c.difference = c.gonogo.mean - c.liggghts.mean;
  c.pooled_sd = std::sqrt(((c.gonogo.n - 1) * c.gonogo.sd * c.gonogo.sd +
                           (c.liggghts.n - 1) * c.liggghts.sd * c.liggghts.sd) /
                          (c.gonogo.n + c.liggghts.n - 2));
  c.agree = std::abs(c.difference) <= kScatterMultiple * c.pooled_sd;
  return c;
}

void Print(const char* what, const Comparison& c) {
  std::printf(
      "%s: gonogo %.4f +- %.4f (n %d), LIGGGHTS %.4f +- %.4f (n %d); difference %.4f, "
      "bound %.1f x pooled sd %.4f = %.4f\n",
      what, c.gonogo.mean, c.gonogo.sd, c.gonogo.n, c.liggghts.mean, c.liggghts.sd, c.liggghts.n,
      c.difference, kScatterMultiple, c.pooled_sd, kScatterMultiple * c.pooled_sd);
}

// Triaxial compression: sin(phi) = 3 M / (6 + M) with M = q / p, and back.
double FrictionAngleDeg(double q_over_p) {
  return units::RadiansToDegrees(std::asin(3.0 * q_over_p / (6.0 + q_over_p)));
}
double QOverP(double friction_deg) {
  const double s = std::sin(units::DegreesToRadians(friction_deg));
  return 6.0 * s / (3.0 - s);
}

TEST(RvePeerTriaxial, BothCodesRanTheSameSeeds) {
  ASSERT_GE(static_cast<int>(Gonogo().size()), kMinimumSeeds);
  ASSERT_EQ(Gonogo().size(), Liggghts().size());
  for (std::size_t k = 0; k < Gonogo().size(); ++k) {
    EXPECT_EQ(Gonogo()[k].seed, Liggghts()[k].seed);
  }
}

TEST(RvePeerTriaxial, PeakStressRatioAgreesWithinTheSeedScatter) {
  const Comparison c = Compare(Column(Gonogo(), &SeedSummary::peak_q_over_p),
                               Column(Liggghts(), &SeedSummary::peak_q_over_p));
  Print("peak q/p", c);
  std::printf("peak friction angle: gonogo %.2f deg, LIGGGHTS %.2f deg\n",
              FrictionAngleDeg(c.gonogo.mean), FrictionAngleDeg(c.liggghts.mean));
  RecordProperty("peak_q_over_p_difference", std::to_string(c.difference));
  EXPECT_TRUE(c.agree) << "mean peak q/p differs by " << c.difference << ", more than "
                       << kScatterMultiple << " x the pooled seed-to-seed sd " << c.pooled_sd;
}

// The strain at the peak is the loosest of the three: q/p stays within a few per cent of its
// peak from about 3 % to 8 % axial strain, so which row holds the largest value scatters by
// 1-2 % of axial strain between seeds (sd 0.010 and 0.023 about means of 0.042 and 0.058); the
// same scatter rule still bounds it.
TEST(RvePeerTriaxial, AxialStrainAtThePeakAgreesWithinTheSeedScatter) {
  const Comparison c = Compare(Column(Gonogo(), &SeedSummary::axial_strain_at_peak),
                               Column(Liggghts(), &SeedSummary::axial_strain_at_peak));
  Print("axial strain at the peak", c);
  EXPECT_TRUE(c.agree) << "mean axial strain at the peak differs by " << c.difference;
}

TEST(RvePeerTriaxial, LargestDilationAgreesWithinTheSeedScatter) {
  const Comparison c = Compare(Column(Gonogo(), &SeedSummary::largest_dilation),
                               Column(Liggghts(), &SeedSummary::largest_dilation));
  Print("largest dilation", c);
  EXPECT_TRUE(c.agree) << "mean largest dilation differs by " << c.difference;
}

// The check is not vacuous: the same LIGGGHTS seeds with every peak friction angle 5 deg lower
// (or higher) fail it.
TEST(RvePeerTriaxial, AFiveDegreeShiftOfThePeakWouldFail) {
  for (double shift_deg : {-5.0, 5.0}) {
    std::vector<double> shifted;
    for (const SeedSummary& row : Liggghts()) {
      shifted.push_back(QOverP(FrictionAngleDeg(row.peak_q_over_p) + shift_deg));
    }
    const Comparison c = Compare(Column(Gonogo(), &SeedSummary::peak_q_over_p), shifted);
    EXPECT_FALSE(c.agree) << "a " << shift_deg << " deg shift passes: difference " << c.difference
                          << ", pooled sd " << c.pooled_sd;
  }
}

// The committed engine numbers are this build's: seed 1 run live exactly as
// `gonogo-rve triaxial --seed 1 --axial-strain 0.1 --rows 100` runs it (same chunks, same rows)
// gives the file's row (to the 6 decimals the file keeps). A change in the engine's order of
// floating-point operations gives another, equally valid packing (solvers/dem/rve/README.md,
// "Friction angle") and fails this check: rerun gonogo_rve_triaxial_seeds.sh --seeds 8 and
// commit its summary; the comparisons above then judge the new sample. About 7 s.
TEST(RvePeerTriaxial, EngineSeedOneIsReproducedLive) {
  ASSERT_FALSE(Gonogo().empty());
  const SeedSummary& committed = Gonogo().front();
  ASSERT_EQ(committed.seed, 1);
  RveParams params;  // seed 000 law, 500 grains, frictionless consolidation to 100 kPa
  params.seed = 1;
  Rve rve = Rve::Generate(params);
  const double rate_1_s = rve.StableRate1S();
  MixedControl triaxial;
  triaxial.strain_rate_1_s(2, 2) = -rate_1_s;
  for (int d = 0; d < 2; ++d) {
    triaxial.stress_controlled[d][d] = true;
    triaxial.target_stress_pa(d, d) = -params.consolidation_pressure_pa;
  }
  constexpr double kFinalAxialStrain = 0.1;
  constexpr long kRows = 100;
  const long total_steps =
      static_cast<long>(std::ceil(kFinalAxialStrain / (rate_1_s * rve.time_step_s())));
  const long steps_per_row = std::max(1L, total_steps / kRows);
  SeedSummary live;
  for (long step = 0; step < total_steps;) {
    const long chunk = std::min(steps_per_row, total_steps - step);
    rve.Run(triaxial, static_cast<int>(chunk));
    step += chunk;
    const RveSnapshot s = rve.Snapshot();
    const Matrix3 stress = -s.stress_pa;  // compression positive
    const double p = stress.trace() / 3.0;
    const Matrix3 deviator = stress - p * Matrix3::Identity();
    const double q = std::sqrt(1.5 * deviator.cwiseProduct(deviator).sum());
    if (q / p > live.peak_q_over_p) {
      live.peak_q_over_p = q / p;
      live.axial_strain_at_peak = -s.strain(2, 2);
    }
    live.largest_dilation = std::max(live.largest_dilation, s.strain.trace());
  }
  std::printf(
      "seed 1 live: peak q/p %.6f at axial strain %.6f, largest dilation %.6f; "
      "committed %.6f, %.6f, %.6f\n",
      live.peak_q_over_p, live.axial_strain_at_peak, live.largest_dilation, committed.peak_q_over_p,
      committed.axial_strain_at_peak, committed.largest_dilation);
  // The file keeps q/p to 6 decimals of values printed to 7 digits, strains to 6 decimals.
  EXPECT_NEAR(live.peak_q_over_p, committed.peak_q_over_p, 1e-5 * committed.peak_q_over_p);
  EXPECT_NEAR(live.axial_strain_at_peak, committed.axial_strain_at_peak, 2e-6);
  EXPECT_NEAR(live.largest_dilation, committed.largest_dilation, 2e-6);
}

}  // namespace
}  // namespace gonogo::dem::rve
