#include "solvers/mobility/gonogo.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/mobility/soft_soil.h"
#include "solvers/mobility/vehicle.h"

namespace gonogo::mobility {
namespace {

VehicleSpec TwoAxle() {
  VehicleSpec v;
  v.name = "test";
  v.mass_kg = 1000.0 / units::kStandardGravityMps2 * 4;  // weight exactly 4000 N
  const TyreGeometry tyre{1.0, 0.3, 0.2, 0.03, 0.47};
  v.axles = {{0.5, 2, tyre, true}, {0.5, 2, tyre, true}};
  v.drive_power_w = 10000;
  v.max_speed_kmh = 90;
  v.driveline_efficiency = 0.8;
  v.ground_clearance_m = 0.3;
  return v;
}

// A curve with drawbar pull linear in slip, D(s) = d0 + d1 s, and constant gross traction.
TractionCurve LinearCurve(double d0, double d1, double gross_n) {
  TractionCurve c;
  for (double s : TractionRequest::SlipSweep(0.05)) {
    c.points.push_back({s, d0 + d1 * s, gross_n * 0.47, 0.0, 0.0, gross_n, 0.0});
  }
  return c;
}

TEST(Vehicle, WheelLoadsFollowTheSplit) {
  VehicleSpec v = TwoAxle();
  v.axles[0].load_fraction = 0.54;
  v.axles[1].load_fraction = 0.46;
  EXPECT_NEAR(v.WheelLoadN(0), 4000 * 0.54 / 2, 1e-9);
  EXPECT_NEAR(v.WheelLoadN(1), 4000 * 0.46 / 2, 1e-9);
  EXPECT_EQ(v.WheelCount(), 4);
}

TEST(Vehicle, SplitFromCentreOfGravityBalancesMoments) {
  VehicleSpec v = TwoAxle();
  SetTwoAxleSplitFromCg(v, 1.71, 3.30);
  // Moments about the front axle: rear load x wheelbase = weight x cg distance.
  EXPECT_NEAR(v.axles[1].load_fraction * 3.30, 1.71, 1e-12);
  EXPECT_NEAR(v.axles[0].load_fraction + v.axles[1].load_fraction, 1.0, 1e-12);
  EXPECT_THROW(SetTwoAxleSplitFromCg(v, 3.5, 3.3), InputError);
}

TEST(Vehicle, ValidationNamesTheField) {
  auto field_of = [](VehicleSpec v) {
    try {
      v.Validate();
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("none");
  };
  VehicleSpec v = TwoAxle();
  EXPECT_EQ(field_of(v), "none");
  v.mass_kg = -1;
  EXPECT_EQ(field_of(v), "vehicle.mass_kg");
  v = TwoAxle();
  v.axles[1].tyre.width_m = NAN;
  EXPECT_EQ(field_of(v), "vehicle.axles[1].tyre.width_m");
  v = TwoAxle();
  v.axles[0].load_fraction = 0.7;
  EXPECT_EQ(field_of(v), "vehicle.axles");
  v = TwoAxle();
  v.drive_power_w = 0;
  EXPECT_EQ(field_of(v), "vehicle.drive_power_w");
}

TEST(EvaluateCell, ClassesFollowTheGradeAgainstTheDrawbarPullCoefficient) {
  const VehicleSpec v = TwoAxle();
  Criteria c;  // design slip 0.2, max slip 0.5, margin 0.05
  // Per wheel D(s) = -50 + 1000 s, so the vehicle's D/W = (-200 + 4000 s) / 4000 = s - 0.05.
  const TractionCurve curve = LinearCurve(-50, 1000, 500);
  const VehicleTraction t = CombineAxles(v, {&curve, &curve});
  // At the design slip D/W = 0.15: GO while sin(theta) <= 0.10.
  EXPECT_EQ(EvaluateCell(v, c, t, 0).go_class, GoClass::kGo);
  EXPECT_EQ(EvaluateCell(v, c, t, 100 * std::tan(std::asin(0.099))).go_class, GoClass::kGo);
  EXPECT_EQ(EvaluateCell(v, c, t, 100 * std::tan(std::asin(0.101))).go_class, GoClass::kSlowGo);
  // Up to max slip D/W = 0.45: SLOW-GO while sin(theta) < 0.45, NO-GO beyond.
  EXPECT_EQ(EvaluateCell(v, c, t, 100 * std::tan(std::asin(0.44))).go_class, GoClass::kSlowGo);
  EXPECT_EQ(EvaluateCell(v, c, t, 100 * std::tan(std::asin(0.46))).go_class, GoClass::kNoGo);
  EXPECT_EQ(EvaluateCell(v, c, t, NAN).go_class, GoClass::kNoData);
  VehicleTraction soft = t;
  soft.soft_soil_ok = false;
  EXPECT_EQ(EvaluateCell(v, c, soft, 0).go_class, GoClass::kNoGo);
}

TEST(EvaluateCell, SpeedIsPowerLimitedAtTheBalancingSlip) {
  const VehicleSpec v = TwoAxle();
  Criteria c;
  const TractionCurve curve = LinearCurve(-50, 1000, 500);  // gross 500 N per wheel, 2000 N total
  const VehicleTraction t = CombineAxles(v, {&curve, &curve});
  // Grade with sin(theta) = 0.1: balancing slip s* from s - 0.05 = 0.1, s* = 0.15.
  const double slope = 100 * std::tan(std::asin(0.1));
  const double expected_mps = 10000 * 0.8 * (1 - 0.15) / 2000;  // P eta (1 - s*) / F
  EXPECT_NEAR(EvaluateCell(v, c, t, slope).speed_kmh, expected_mps * 3.6, 1e-3);
  // A huge power is capped by the top speed.
  VehicleSpec fast = v;
  fast.drive_power_w = 1e9;
  EXPECT_NEAR(EvaluateCell(fast, c, t, slope).speed_kmh, 90, 1e-4);
  EXPECT_EQ(EvaluateCell(v, c, t, 100).speed_kmh, 0.0f) << "NO-GO cells make no speed";
}

TEST(CombineAxles, TowedAxleAddsItsRollingResistanceOnly) {
  VehicleSpec v = TwoAxle();
  v.axles[1].driven = false;
  const TractionCurve curve = LinearCurve(-50, 1000, 500);
  const VehicleTraction t = CombineAxles(v, {&curve, &curve});
  // Driven: 2 (-50 + 1000 s); towed: 2 (-50) at every slip.
  EXPECT_NEAR(t.drawbar_pull_n[4], 2 * (-50 + 200) + 2 * (-50), 1e-9);
  EXPECT_NEAR(t.gross_traction_n[4], 1000, 1e-9);
}

TEST(Criteria, RejectsNonsense) {
  Criteria c;
  c.passes = 7;
  EXPECT_THROW(c.Validate(), InputError);
  c = {};
  c.max_slip = 0.1;  // below the design slip
  EXPECT_THROW(c.Validate(), InputError);
  c = {};
  c.design_slip = NAN;
  EXPECT_THROW(c.Validate(), InputError);
}

TEST(SoftSoil, FiftyPassesNeedFirmerGroundThanOne) {
  VehicleSpec v = TwoAxle();
  v.mass_kg = 5481;
  v.drive_power_w = 149000;
  const double vci1 = VehicleConeIndexPa(v, 1);
  const double vci50 = VehicleConeIndexPa(v, 50);
  EXPECT_GT(vci1, 0);
  EXPECT_GT(vci50, vci1);
}

}  // namespace
}  // namespace gonogo::mobility
