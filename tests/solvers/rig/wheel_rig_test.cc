// The single-wheel rig on the fe-classic soil: the invariants of a rigid wheel on soft soil
// (Wong 2008, ch. 2.7; seed 001 Figs. 14-21): a positive motion resistance at zero slip and
// drawbar pull rising with slip; free rolling (no torque) pulls minus the motion resistance;
// torque and sinkage rising with load; the slip ramp agreeing with a constant-slip run; a soil
// that cannot carry the wheel gives an immobile curve.
#include "solvers/rig/wheel_rig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "solvers/common/errors.h"
#include "solvers/rig/fe_soils.h"

namespace gonogo::rig {
namespace {

// The 0.5-scale tyre of seed 001 Table 4 as a rigid wheel, on a coarse bin.
RigWheel HalfScaleWheel(double load_factor = 1.0) { return {0.2525, 0.167, 3359 * load_factor}; }

RigOptions Coarse() {
  RigOptions o;
  o.elements_per_radius = 4;
  o.threads = 2;
  return o;
}

const FeSoil& DrySand() { return *FeSoilLibrary::Builtin().Find("lll_dry_sand"); }

double MeanOver(const std::vector<TractionPoint>& c, double from, double to,
                double TractionPoint::*field) {
  double sum = 0;
  int n = 0;
  for (const TractionPoint& p : c) {
    if (p.slip >= from - 1e-9 && p.slip <= to + 1e-9) {
      sum += p.*field;
      ++n;
    }
  }
  return sum / n;
}

class WheelRigTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    base_ = new RigRun(RunDrawbarPullTest(DrySand(), HalfScaleWheel(), {}, Coarse()));
    heavy_ = new RigRun(RunDrawbarPullTest(DrySand(), HalfScaleWheel(1.5), {}, Coarse()));
  }
  static void TearDownTestSuite() {
    delete base_;
    delete heavy_;
  }
  static RigRun* base_;
  static RigRun* heavy_;
};
RigRun* WheelRigTest::base_ = nullptr;
RigRun* WheelRigTest::heavy_ = nullptr;

TEST_F(WheelRigTest, MotionResistanceAtZeroSlipAndDrawbarPullGrowsWithSlip) {
  const double w = HalfScaleWheel().load_n;
  const auto curve = CurveFromRun(*base_, TractionRequest::SlipSweep(0.1), 0.2525);
  for (const TractionPoint& p : curve) {
    std::printf("slip %.2f D/W %.3f T/(rW) %.3f z %.4f m\n", p.slip, p.drawbar_pull_n / w,
                p.torque_nm / (0.2525 * w), p.sinkage_m);
  }
  // Zero slip: the wheel pays a motion resistance, T/r - D > 0, and pulls little (the rim shears
  // the soil even at zero slip, j > 0 over the arc, Wong 2008 eq. 2.56, so D(0) may be slightly
  // positive when the compaction resistance is small).
  EXPECT_LT(curve[0].drawbar_pull_n, 0.1 * w);
  EXPECT_GT(curve[0].motion_resistance_n, 0.1 * w);
  // The usual range: drawbar pull rises from low to moderate slip.
  const double low = MeanOver(curve, 0.0, 0.1, &TractionPoint::drawbar_pull_n);
  const double mid = MeanOver(curve, 0.3, 0.5, &TractionPoint::drawbar_pull_n);
  EXPECT_GT(mid, low + 0.05 * w);
  // Sinkage is positive and well below the radius.
  for (const TractionPoint& p : curve) {
    EXPECT_GT(p.sinkage_m, 0.0);
    EXPECT_LT(p.sinkage_m, 0.5 * 0.2525);
  }
}

// Free rolling: a towed wheel (no torque) needs a pull equal to its motion resistance, D = -R
// (Wong 2008, sec. 2.7: with T = 0, T/r - D = R). R is read from the driven run at zero slip;
// the towed wheel skids a little (s < 0), so the two states differ and the tolerance is 30 %.
TEST_F(WheelRigTest, FreeRollingPullsMinusTheMotionResistance) {
  const double w = HalfScaleWheel().load_n;
  const RigRun towed = RunTowedTest(DrySand(), HalfScaleWheel(), 1.0, {}, Coarse());
  double d = 0, t = 0, slip = 0;
  int n = 0;
  for (const RigSample& s : towed.samples) {
    if (s.phase == 6 && s.time_s > towed.samples.back().time_s - 0.5) {
      d += s.drawbar_pull_n;
      t += s.torque_nm;
      slip += s.slip;
      ++n;
    }
  }
  ASSERT_GT(n, 10);
  d /= n;
  t /= n;
  slip /= n;
  const double resistance = CurveFromRun(*base_, {0.0}, 0.2525)[0].motion_resistance_n;
  std::printf("towed: D %.0f N, T %.1f N m, slip %.3f; driven at s = 0: R %.0f N\n", d, t, slip,
              resistance);
  EXPECT_LT(std::abs(t) / (0.2525 * w), 0.02);  // the wheel turns freely
  EXPECT_LT(slip, 0.0);                         // and skids
  EXPECT_GT(slip, -0.5);
  EXPECT_NEAR(-d, resistance, 0.3 * resistance);
}

TEST_F(WheelRigTest, TorqueAndSinkageGrowWithLoad) {
  const auto slips = TractionRequest::SlipSweep(0.1);
  const auto light = CurveFromRun(*base_, slips, 0.2525);
  const auto heavy = CurveFromRun(*heavy_, slips, 0.2525);
  EXPECT_GT(MeanOver(heavy, 0.1, 0.6, &TractionPoint::torque_nm),
            1.2 * MeanOver(light, 0.1, 0.6, &TractionPoint::torque_nm));
  EXPECT_GT(MeanOver(heavy, 0.0, 0.6, &TractionPoint::sinkage_m),
            1.1 * MeanOver(light, 0.0, 0.6, &TractionPoint::sinkage_m));
}

TEST_F(WheelRigTest, SlipRampAgreesWithAConstantSlipRun) {
  const double slip = 0.3;
  const RigRun held = RunConstantSlipTest(DrySand(), HalfScaleWheel(), slip, 0.6, {}, Coarse());
  double d = 0;
  int n = 0;
  for (const RigSample& s : held.samples) {
    if (s.phase == 5 && s.time_s > held.samples.back().time_s - 0.3) {
      d += s.drawbar_pull_n;
      ++n;
    }
  }
  d /= n;
  const double ramp = CurveFromRun(*base_, {slip}, 0.2525)[0].drawbar_pull_n;
  std::printf("slip 0.3: constant-slip D %.0f N, ramp D %.0f N\n", d, ramp);
  EXPECT_NEAR(d, ramp, 0.05 * HalfScaleWheel().load_n + 0.25 * std::abs(d));
}

TEST(FeSoilLibraryTest, ParsesTheBuiltinAndRejectsBadRows) {
  const FeSoilLibrary& lib = FeSoilLibrary::Builtin();
  ASSERT_NE(lib.Find("LETE_SAND"), nullptr);
  EXPECT_DOUBLE_EQ(lib.Find("lete_sand")->strength.friction_angle_deg, 31.1);
  const std::string header =
      "name,density_kg_m3,young_pa,poisson,cohesion_pa,friction_angle_deg,dilation_angle_deg,"
      "source\n";
  try {
    FeSoilLibrary::Parse(header + "x,1500,1e7,0.3,1000,95,0,somewhere\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("friction_angle_deg"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gonogo::rig
