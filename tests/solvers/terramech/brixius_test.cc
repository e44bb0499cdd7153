// Brixius (1987) traction equations and the ERDC VTI sinkage relation: hand-evaluated points of the
// published equations, closed-form limits, bounds, monotonicity and dimensional similarity (the
// scaled FED Alpha tyre series of seed 001, /work/shared/reference/tyres.csv).
#include "solvers/terramech/brixius.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/common/errors.h"

namespace gonogo::terramech {
namespace {

// b = 0.3 m, d = 1.0 m, h = 0.2 m, delta = 0.03 m (15 % of h); with CI = 1 MPa and W = 10 kN the
// wheel numeric CI b d / W is 30.
TyreGeometry TestTyre() { return TyreGeometry{1.0, 0.3, 0.2, 0.03, 0.0}; }

TyreGeometry Scaled(const TyreGeometry& t, double scale) {
  return TyreGeometry{t.diameter_m * scale, t.width_m * scale, t.section_height_m * scale,
                      t.deflection_m * scale, t.rolling_radius_m * scale};
}

TEST(BrixiusMobilityNumber, MatchesEquation17) {
  // Bn = 30 (1 + 5 * 0.15) / (1 + 3 * 0.3) = 30 * 1.75 / 1.9.
  EXPECT_NEAR(MobilityNumber(1e6, TestTyre(), 1e4), 27.63157894736842, 1e-12);
  // A rigid wheel (delta = 0) drops the deflection term.
  TyreGeometry rigid = TestTyre();
  rigid.deflection_m = 0;
  EXPECT_NEAR(MobilityNumber(1e6, rigid, 1e4), 30.0 / 1.9, 1e-12);
  EXPECT_DOUBLE_EQ(MobilityNumber(0.0, TestTyre(), 1e4), 0.0);
}

TEST(BrixiusRatios, HandEvaluatedPointAtBn30Slip20Percent) {
  // Literal values of the published equations at Bn = 30, s = 0.2, evaluated independently:
  //   GT/W = 0.88 (1 - e^-3)(1 - e^-1.5) + 0.04,  MR/W = 1/30 + 0.04 + 0.1 / sqrt(30).
  // A wrong constant (0.88, 0.1, 7.5, 0.04, 0.5) moves these by far more than the tolerance.
  const BrixiusRatios r = EvaluateBrixius(30.0, 0.2);
  EXPECT_NEAR(r.gross_traction, 0.6896087558593148, 1e-12);
  EXPECT_NEAR(r.motion_resistance, 0.09159075191683887, 1e-12);
  EXPECT_NEAR(r.net_traction, 0.598018003942476, 1e-12);
  EXPECT_NEAR(r.tractive_efficiency, 0.6937475765629357, 1e-12);
  EXPECT_DOUBLE_EQ(NetTractionRatio(30.0, 0.2), r.net_traction);
  EXPECT_DOUBLE_EQ(TractiveEfficiency(30.0, 0.2), r.tractive_efficiency);
}

TEST(BrixiusRatios, ZeroSlipGrossTractionIsTheTyreLoss) {
  // s = 0: (1 - e^0) = 0, so GT = 0.04 W for any soil; MR/W = 1/Bn + 0.04.
  for (double bn : {0.0, 0.5, 5.0, 20.0, 80.0, 1e4}) {
    EXPECT_DOUBLE_EQ(GrossTractionRatio(bn, 0.0), 0.04) << "Bn " << bn;
  }
  for (double bn : {5.0, 20.0, 80.0}) {
    EXPECT_NEAR(MotionResistanceRatio(bn, 0.0), 1.0 / bn + 0.04, 1e-15) << "Bn " << bn;
  }
}

TEST(BrixiusRatios, LargeMobilityNumberLimits) {
  // Bn -> infinity: GT/W -> 0.88 (1 - e^(-7.5 s)) + 0.04, MR/W -> 0.04, NT/W(s=1) -> 0.8795.
  const double bn = 1e8;
  for (double s : {0.0, 0.1, 0.3, 1.0}) {
    EXPECT_NEAR(GrossTractionRatio(bn, s), 0.88 * (1 - std::exp(-7.5 * s)) + 0.04, 1e-12);
    EXPECT_NEAR(MotionResistanceRatio(bn, s), 0.04, 1e-4);
  }
  EXPECT_NEAR(NetTractionRatio(bn, 1.0), 0.8795132857542699, 1e-4);
  // Gross traction can never exceed 0.92 W.
  EXPECT_LT(GrossTractionRatio(bn, 1.0), 0.92);
}

TEST(BrixiusRatios, EfficiencyBoundedAndZeroWithoutPull) {
  for (double bn : {0.0, 0.5, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0, 200.0}) {
    for (int i = 0; i <= 100; ++i) {
      const double s = i / 100.0;
      const BrixiusRatios r = EvaluateBrixius(bn, s);
      EXPECT_GE(r.tractive_efficiency, 0.0);
      EXPECT_LE(r.tractive_efficiency, 1.0 - s + 1e-15);
      if (r.net_traction <= 0) {
        EXPECT_EQ(r.tractive_efficiency, 0.0) << bn << " " << s;
      }
      EXPECT_NEAR(r.net_traction, r.gross_traction - r.motion_resistance, 1e-15);
    }
    EXPECT_EQ(TractiveEfficiency(bn, 1.0), 0.0);
  }
}

TEST(BrixiusRatios, NetTractionGrowsWithSlipInTheUsualRange) {
  // d(NT/W)/ds = 6.6 (1 - e^(-0.1 Bn)) e^(-7.5 s) - 0.5 / sqrt(Bn) > 0 up to s = 0.52 for Bn >= 20.
  for (double bn : {20.0, 30.0, 50.0, 80.0}) {
    double previous = NetTractionRatio(bn, 0.0);
    for (int i = 1; i <= 50; ++i) {
      const double nt = NetTractionRatio(bn, i / 100.0);
      EXPECT_GT(nt, previous) << "Bn " << bn << " s " << i / 100.0;
      previous = nt;
    }
  }
}

TEST(BrixiusRatios, StrongerSoilPullsMore) {
  for (double s : {0.05, 0.2, 0.5}) {
    double previous_nt = NetTractionRatio(1.0, s);
    double previous_mr = MotionResistanceRatio(1.0, s);
    for (double bn : {2.0, 5.0, 10.0, 20.0, 40.0, 80.0}) {
      EXPECT_GT(NetTractionRatio(bn, s), previous_nt);
      EXPECT_LE(MotionResistanceRatio(bn, s), previous_mr);
      previous_nt = NetTractionRatio(bn, s);
      previous_mr = MotionResistanceRatio(bn, s);
    }
  }
}

TEST(BrixiusRatios, ZeroMobilityNumberIsFiniteAndImmobile) {
  for (double s : {0.0, 0.2, 1.0}) {
    const BrixiusRatios r = EvaluateBrixius(0.0, s);
    EXPECT_TRUE(std::isfinite(r.gross_traction) && std::isfinite(r.motion_resistance));
    EXPECT_DOUBLE_EQ(r.gross_traction, 0.04);
    EXPECT_DOUBLE_EQ(r.motion_resistance, kMaxMotionResistanceRatio);
    EXPECT_DOUBLE_EQ(r.net_traction, 0.04 - kMaxMotionResistanceRatio);
    EXPECT_EQ(r.tractive_efficiency, 0.0);
  }
  // The cap is continuous: just above Bn = 0 the ratio is already at the cap.
  EXPECT_DOUBLE_EQ(MotionResistanceRatio(1e-300, 0.5), kMaxMotionResistanceRatio);
  EXPECT_LT(MotionResistanceRatio(5.0, 1.0), kMaxMotionResistanceRatio);
}

TEST(BrixiusRatios, RejectsBadArguments) {
  EXPECT_THROW(GrossTractionRatio(-1.0, 0.1), InputError);
  EXPECT_THROW(GrossTractionRatio(NAN, 0.1), InputError);
  EXPECT_THROW(MotionResistanceRatio(10.0, 1.5), InputError);
  EXPECT_THROW(EvaluateBrixius(10.0, -0.1), InputError);
  try {
    MobilityNumber(-1.0, TestTyre(), 1e4);
    FAIL() << "negative cone index accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "cone_index_pa");
  }
  try {
    MobilityNumber(1e6, TestTyre(), 0.0);
    FAIL() << "zero load accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "wheel_load_n");
  }
  TyreGeometry bad = TestTyre();
  bad.width_m = NAN;
  EXPECT_THROW(MobilityNumber(1e6, bad, 1e4), InputError);
}

TEST(BrixiusSimilarity, ScalingLengthsAndLoadKeepsPullRatio) {
  // CI b d / W, b/d and delta/h are unchanged when lengths scale by k and W by k^2 (seed 001,
  // section 4: equal W/(b d) on the same soil), so D/W must be unchanged and D must scale as k^2.
  const TyreGeometry full = TestTyre();
  const double load_n = 1e4;
  const double bn_full = MobilityNumber(1e6, full, load_n);
  for (double k : {0.25, 0.5, 0.7, 2.0}) {
    const double bn = MobilityNumber(1e6, Scaled(full, k), load_n * k * k);
    EXPECT_NEAR(bn / bn_full, 1.0, 1e-12) << "scale " << k;
    for (double s : {0.05, 0.2, 0.6}) {
      EXPECT_NEAR(NetTractionRatio(bn, s), NetTractionRatio(bn_full, s), 1e-12);
    }
    const double z_full = PoweredSinkage(1e6, full, load_n);
    EXPECT_NEAR(PoweredSinkage(1e6, Scaled(full, k), load_n * k * k) / z_full, k, 1e-12);
  }
}

// Rows of tyres.csv: scale, d_mm, b_mm, r_mm, rim_in, b_over_d, W_N, bd_over_W.
struct TyreRow {
  double scale, d_mm, b_mm, w_n;
};

std::vector<TyreRow> ReadSeedTyres() {
  const char* shared = std::getenv("GONOGO_SHARED_DIR");
  const std::string dir = shared ? shared : "/work/shared";
  std::ifstream in(dir + "/reference/tyres.csv");
  std::vector<TyreRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("scale", 0) == 0) continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::atof(cell.c_str()));
    if (v.size() >= 7) rows.push_back({v[0], v[1], v[2], v[6]});
  }
  return rows;
}

TEST(BrixiusSimilarity, SeedScaledTyreSeriesGivesTheSamePull) {
  // Seed 001 Tables 4 and 6: the 335/65R22.5 tyre and its 0.7 / 0.5 / 0.25 scale models, loads
  // chosen for equal W/(b d) (25.20 m^2/MN) and b/d = 0.33. The table's millimetre rounding spreads
  // CI b d / W by 0.8 % and b/d by 0.5 %, so Bn agrees to 1 % and D/W to 0.005.
  const std::vector<TyreRow> rows = ReadSeedTyres();
  ASSERT_EQ(rows.size(), 4u) << "tyres.csv not found or changed (GONOGO_SHARED_DIR)";
  auto tyre_of = [](const TyreRow& row) {
    // Aspect ratio 65. The table's r (253 mm at d = 505 mm) exceeds d/2 by rounding and plays no
    // part in Bn, so the rolling radius is left to be derived.
    const double b = row.b_mm / 1000, h = 0.65 * b;
    return TyreGeometry{row.d_mm / 1000, b, h, 0.15 * h, 0.0};
  };
  for (double cone_index_pa : {149e3, 1e6}) {  // 2NS sand of seed 001, and a firm soil
    const double bn_full = MobilityNumber(cone_index_pa, tyre_of(rows[0]), rows[0].w_n);
    for (const TyreRow& row : rows) {
      const double bn = MobilityNumber(cone_index_pa, tyre_of(row), row.w_n);
      EXPECT_NEAR(bn / bn_full, 1.0, 0.01) << "scale " << row.scale;
      EXPECT_NEAR(NetTractionRatio(bn, 0.2), NetTractionRatio(bn_full, 0.2), 0.005);
    }
  }
}

TEST(VtiSinkage, HandEvaluatedPoint) {
  // N_cz = 30 / 0.85^1.5, N_c = N_cz / 1.3^0.75, S_sp = 21 / N_c^2.5 + 0.005,
  // z/d = 1.64 / (N_cz / S_sp^0.19)^1.21, evaluated independently.
  const double n_cz = FineGrainedSinkageNumeric(1e6, TestTyre(), 1e4);
  const double n_c = FineGrainedNumeric(n_cz, TestTyre());
  EXPECT_NEAR(n_cz, 38.28184549740992, 1e-10);
  EXPECT_NEAR(n_c, 31.44382365080414, 1e-10);
  EXPECT_NEAR(SelfPropelledSlip(n_c), 0.008787746581755091, 1e-14);
  EXPECT_NEAR(PoweredSinkageRatio(n_cz, n_c), 0.006709959870858248, 1e-14);
  EXPECT_NEAR(PoweredSinkage(1e6, TestTyre(), 1e4), 0.006709959870858248 * 1.0, 1e-14);
}

TEST(VtiSinkage, BoundedMonotoneAndBuriedAtZeroStrength) {
  const TyreGeometry tyre = TestTyre();
  EXPECT_DOUBLE_EQ(PoweredSinkage(0.0, tyre, 1e4), tyre.diameter_m);
  EXPECT_DOUBLE_EQ(PoweredSinkage(1e-9, tyre, 1e4), tyre.diameter_m);
  double previous = tyre.diameter_m;
  for (double ci : {1e3, 1e4, 5e4, 1e5, 3e5, 1e6, 3e6, 1e7}) {
    const double z = PoweredSinkage(ci, tyre, 1e4);
    EXPECT_TRUE(std::isfinite(z));
    EXPECT_GE(z, 0.0);
    EXPECT_LE(z, previous) << "CI " << ci;
    previous = z;
  }
  EXPECT_LT(previous, 1e-3 * tyre.diameter_m);
  EXPECT_TRUE(std::isinf(SelfPropelledSlip(0.0)));
}

}  // namespace
}  // namespace gonogo::terramech
