// The empirical tier: every TractionPoint field from the Brixius ratios, the zero-cone-index limit,
// similarity through the tier, input errors and registration.
#include "solvers/tiers/empirical_tier.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "solvers/common/errors.h"
#include "solvers/common/tier.h"
#include "solvers/terramech/brixius.h"

namespace gonogo::tiers {
namespace {
using namespace gonogo::terramech;  // the kernels the adapters call

// FED Alpha 335/65R22.5 of seed 001 Table 4: d 1.011 m, b 0.335 m, h = 0.65 b, delta = 0.15 h,
// r = 0.505 m, wheel load 13438 N.
TractionRequest FedAlphaRequest(double cone_index_pa) {
  TractionRequest r;
  r.soil.cone_index_pa = cone_index_pa;
  r.tyre = TyreGeometry{1.011, 0.335, 0.65 * 0.335, 0.15 * 0.65 * 0.335, 0.505};
  r.wheel_load_n = 13438;
  r.slips = TractionRequest::SlipSweep(0.05);
  return r;
}

bool AllFinite(const TractionPoint& p) {
  return std::isfinite(p.slip) && std::isfinite(p.drawbar_pull_n) && std::isfinite(p.torque_nm) &&
         std::isfinite(p.sinkage_m) && std::isfinite(p.tractive_efficiency) &&
         std::isfinite(p.gross_traction_n) && std::isfinite(p.motion_resistance_n);
}

TEST(EmpiricalTier, NameAndVersion) {
  EmpiricalTier tier;
  EXPECT_EQ(tier.Name(), "empirical");
  EXPECT_EQ(tier.Version(), "empirical-1");
  const TractionCurve c = tier.Compute(FedAlphaRequest(1e6));
  EXPECT_EQ(c.tier, "empirical");
  EXPECT_EQ(c.tier_version, "empirical-1");
}

TEST(EmpiricalTier, FillsEveryFieldFromTheBrixiusRatios) {
  const TractionRequest req = FedAlphaRequest(1e6);
  const TractionCurve c = EmpiricalTier().Compute(req);
  ASSERT_EQ(c.points.size(), req.slips.size());
  const double w = req.wheel_load_n;
  const double bn = MobilityNumber(req.soil.cone_index_pa, req.tyre, w);
  const double z = PoweredSinkage(req.soil.cone_index_pa, req.tyre, w);
  for (size_t i = 0; i < c.points.size(); ++i) {
    const TractionPoint& p = c.points[i];
    ASSERT_TRUE(AllFinite(p));
    const BrixiusRatios r = EvaluateBrixius(bn, req.slips[i]);
    EXPECT_DOUBLE_EQ(p.slip, req.slips[i]);
    EXPECT_NEAR(p.gross_traction_n, r.gross_traction * w, 1e-9);
    EXPECT_NEAR(p.motion_resistance_n, r.motion_resistance * w, 1e-9);
    EXPECT_NEAR(p.drawbar_pull_n, p.gross_traction_n - p.motion_resistance_n, 1e-9);
    // T = GT r with r = 0.505 m from the request.
    EXPECT_NEAR(p.torque_nm, p.gross_traction_n * 0.505, 1e-9);
    // eta = D (1 - s) / (T / r) where D > 0 (TractionPoint contract).
    const double eta =
        p.drawbar_pull_n > 0 ? p.drawbar_pull_n * (1 - p.slip) / (p.torque_nm / 0.505) : 0.0;
    EXPECT_NEAR(p.tractive_efficiency, eta, 1e-12);
    EXPECT_DOUBLE_EQ(p.sinkage_m, z);
    EXPECT_GT(p.sinkage_m, 0.0);
    EXPECT_LT(p.sinkage_m, req.tyre.diameter_m);
  }
  // s = 0: gross traction is the tyre loss 0.04 W; firm soil gives positive pull at 20 % slip.
  EXPECT_NEAR(c.points.front().gross_traction_n, 0.04 * w, 1e-9);
  EXPECT_GT(c.DrawbarPullAt(0.2), 0.0);
}

TEST(EmpiricalTier, DerivedRollingRadiusWhenZero) {
  TractionRequest req = FedAlphaRequest(1e6);
  req.tyre.rolling_radius_m = 0;  // r = d/2 - delta
  const TractionCurve c = EmpiricalTier().Compute(req);
  const double r = 0.5 * 1.011 - 0.15 * 0.65 * 0.335;
  for (const TractionPoint& p : c.points) EXPECT_NEAR(p.torque_nm, p.gross_traction_n * r, 1e-9);
}

TEST(EmpiricalTier, ZeroConeIndexIsFiniteAndImmobile) {
  const TractionRequest req = FedAlphaRequest(0.0);
  const TractionCurve c = EmpiricalTier().Compute(req);
  for (const TractionPoint& p : c.points) {
    ASSERT_TRUE(AllFinite(p)) << "slip " << p.slip;
    EXPECT_LT(p.drawbar_pull_n, 0.0);
    EXPECT_NEAR(p.drawbar_pull_n, -0.96 * req.wheel_load_n, 1e-9);
    EXPECT_EQ(p.tractive_efficiency, 0.0);
    EXPECT_DOUBLE_EQ(p.sinkage_m, req.tyre.diameter_m);
  }
}

TEST(EmpiricalTier, SimilarTyresGiveTheSamePullCoefficient) {
  // Seed 001: equal W/(b d), b/d and delta/h on the same soil give equal D/W; T scales as k^3.
  const TractionRequest full = FedAlphaRequest(5e5);
  const TractionCurve cf = EmpiricalTier().Compute(full);
  for (double k : {0.7, 0.5, 0.25}) {
    TractionRequest small = full;
    small.tyre = TyreGeometry{full.tyre.diameter_m * k, full.tyre.width_m * k,
                              full.tyre.section_height_m * k, full.tyre.deflection_m * k,
                              full.tyre.rolling_radius_m * k};
    small.wheel_load_n = full.wheel_load_n * k * k;
    const TractionCurve cs = EmpiricalTier().Compute(small);
    for (size_t i = 0; i < cf.points.size(); ++i) {
      EXPECT_NEAR(cs.points[i].drawbar_pull_n / small.wheel_load_n,
                  cf.points[i].drawbar_pull_n / full.wheel_load_n, 1e-12);
      EXPECT_NEAR(cs.points[i].torque_nm / cf.points[i].torque_nm, k * k * k, 1e-12);
      EXPECT_NEAR(cs.points[i].tractive_efficiency, cf.points[i].tractive_efficiency, 1e-12);
    }
  }
}

TEST(EmpiricalTier, RejectsBadRequestsNamingTheField) {
  auto field_of = [](const TractionRequest& r) {
    try {
      EmpiricalTier().Compute(r);
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("(accepted)");
  };
  TractionRequest r = FedAlphaRequest(1e6);
  r.soil.cone_index_pa = NAN;
  EXPECT_EQ(field_of(r), "soil.cone_index_pa");
  r = FedAlphaRequest(1e6);
  r.soil.cone_index_pa = -5;
  EXPECT_EQ(field_of(r), "soil.cone_index_pa");
  r = FedAlphaRequest(1e6);
  r.wheel_load_n = -1;
  EXPECT_EQ(field_of(r), "wheel_load_n");
  r = FedAlphaRequest(1e6);
  r.slips.clear();
  EXPECT_EQ(field_of(r), "slips");
  r = FedAlphaRequest(1e6);
  r.slips = {0.1, 1.2};
  EXPECT_EQ(field_of(r), "slips");
  r = FedAlphaRequest(1e6);
  r.tyre.deflection_m = r.tyre.section_height_m;
  EXPECT_EQ(field_of(r), "tyre.deflection_m");
}

TEST(EmpiricalTier, RegistersUnderItsName) {
  TierRegistry registry;
  registry.Register(std::make_unique<EmpiricalTier>());
  const TractionTier& tier = registry.Get("empirical");
  EXPECT_EQ(tier.Version(), "empirical-1");
  EXPECT_EQ(tier.Compute(FedAlphaRequest(1e6)).points.size(), 21u);
}

}  // namespace
}  // namespace gonogo::tiers
