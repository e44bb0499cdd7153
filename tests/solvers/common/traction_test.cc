#include "solvers/common/traction.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/tier.h"

namespace gonogo {
namespace {

TyreGeometry FedAlphaTyre() {
  // 335/65R22.5 (seed 001 Table 4): d 1.011 m, b 0.335 m, h = 0.65 b.
  return TyreGeometry{1.011, 0.335, 0.65 * 0.335, 0.15 * 0.65 * 0.335, 0.505};
}

TEST(TractionRequest, SlipSweepEndsAtOneAndIsEven) {
  auto s = TractionRequest::SlipSweep(0.05);
  ASSERT_EQ(s.size(), 21u);
  EXPECT_DOUBLE_EQ(s.front(), 0.0);
  EXPECT_DOUBLE_EQ(s.back(), 1.0);
  EXPECT_NEAR(s[7], 0.35, 1e-12);
  EXPECT_THROW(TractionRequest::SlipSweep(0), InputError);
  EXPECT_THROW(TractionRequest::SlipSweep(NAN), InputError);
}

TEST(TractionRequest, ValidateNamesTheField) {
  TractionRequest r{{300e3, "", std::nullopt}, FedAlphaTyre(), 13438, {0, 0.2}, "", {}};
  EXPECT_NO_THROW(r.Validate());
  r.soil.cone_index_pa = NAN;
  try {
    r.Validate();
    FAIL() << "NaN cone index accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.cone_index_pa");
  }
  r.soil.cone_index_pa = 1e5;
  r.tyre.deflection_m = r.tyre.section_height_m * 2;
  try {
    r.Validate();
    FAIL() << "deflection larger than section height accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tyre.deflection_m");
  }
}

TEST(TractionRequest, ASurrogateGuardIsRefusedByField) {
  TractionRequest r{{300e3, "", std::nullopt}, FedAlphaTyre(), 13438, {0, 0.2}, "", {}};
  r.surrogate_guard.distance_threshold = 0;  // the model's own
  r.surrogate_guard.return_after_steps = 20;
  EXPECT_NO_THROW(r.Validate());
  const auto refused_field = [](const TractionRequest& bad) -> std::string {
    try {
      bad.Validate();
    } catch (const InputError& e) {
      return e.field();
    }
    return "(accepted)";
  };
  TractionRequest bad = r;
  bad.surrogate_guard.distance_threshold = -1;
  EXPECT_EQ(refused_field(bad), "surrogate_guard.distance_threshold");
  bad = r;
  bad.surrogate_guard.spread_threshold = NAN;
  EXPECT_EQ(refused_field(bad), "surrogate_guard.spread_threshold");
  bad = r;
  bad.surrogate_guard.pressure_floor_pa = -500;
  EXPECT_EQ(refused_field(bad), "surrogate_guard.pressure_floor_pa");
  bad = r;
  bad.surrogate_guard.return_after_steps = -3;
  EXPECT_EQ(refused_field(bad), "surrogate_guard.return_after_steps");
  bad = r;
  bad.surrogate_guard.fallback_enabled = false;
  EXPECT_EQ(refused_field(bad), "surrogate_guard.return_after_steps")
      << "a return from a fallback the same guard turns off";
  bad.surrogate_guard.return_after_steps = 0;
  EXPECT_EQ(refused_field(bad), "(accepted)");
}

TEST(TyreGeometry, RollingRadiusDefaultsToLoadedRadius) {
  TyreGeometry t = FedAlphaTyre();
  t.rolling_radius_m = 0;
  EXPECT_NEAR(t.RollingRadius(), 0.5055 - t.deflection_m, 1e-12);
}

TEST(TractionCurve, DrawbarPullInterpolatesLinearly) {
  TractionCurve c;
  c.points = {{0.0, -100}, {0.2, 300}, {1.0, 500}};
  EXPECT_DOUBLE_EQ(c.DrawbarPullAt(0.1), 100);
  EXPECT_DOUBLE_EQ(c.DrawbarPullAt(0.6), 400);
  EXPECT_DOUBLE_EQ(c.DrawbarPullAt(2.0), 500);
}

TEST(TierRegistry, UnknownTierListsKnownOnes) {
  TierRegistry reg;
  try {
    reg.Get("fe-magic");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tier");
    EXPECT_NE(std::string(e.what()).find("fe-magic"), std::string::npos);
  }
}

}  // namespace
}  // namespace gonogo
