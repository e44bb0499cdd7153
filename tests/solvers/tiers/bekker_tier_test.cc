// The bekker tier: soil resolution, every TractionPoint field from the kernels of bekker.h, the
// rigid / elastic mode rule of Wong (2008) 2.7.2, cancellation between slip points, input errors
// and registration.
#include "solvers/tiers/bekker_tier.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/common/tier.h"
#include "solvers/terramech/bekker.h"

namespace gonogo::tiers {
namespace {
using namespace gonogo::terramech;  // the kernels the adapters call

// FED Alpha 335/65R22.5 of seed 001 Table 4 (d 1.011 m, b 0.335 m, h = 0.65 b, delta = 0.15 h,
// r = 0.505 m) carrying 13438 N; inflation pressure not given (0): a rigid wheel.
TractionRequest FedAlphaRequest(const std::string& soil_name) {
  TractionRequest r;
  r.soil.soil_name = soil_name;
  r.tyre = TyreGeometry{1.011, 0.335, 0.65 * 0.335, 0.15 * 0.65 * 0.335, 0.505};
  r.wheel_load_n = 13438;
  r.slips = TractionRequest::SlipSweep(0.1);
  return r;
}

bool AllFinite(const TractionPoint& p) {
  return std::isfinite(p.slip) && std::isfinite(p.drawbar_pull_n) && std::isfinite(p.torque_nm) &&
         std::isfinite(p.sinkage_m) && std::isfinite(p.tractive_efficiency) &&
         std::isfinite(p.gross_traction_n) && std::isfinite(p.motion_resistance_n);
}

TEST(BekkerTier, NameVersionAndSoilName) {
  BekkerTier tier;
  EXPECT_EQ(tier.Name(), "bekker");
  EXPECT_EQ(tier.Version(), "bekker-1");
  EXPECT_TRUE(tier.UsesSoilName());
  const TractionCurve c = tier.Compute(FedAlphaRequest("lete_sand"));
  EXPECT_EQ(c.tier, "bekker");
  EXPECT_EQ(c.tier_version, "bekker-1");
}

TEST(BekkerTier, RigidModeFillsEveryFieldFromTheRigidWheel) {
  const TractionRequest req = FedAlphaRequest("LETE_sand");
  const TractionCurve c = BekkerTier().Compute(req);
  ASSERT_EQ(c.points.size(), req.slips.size());
  const BekkerParameters soil = BekkerSoilLibrary::Builtin().Find("lete_sand")->parameters;
  for (size_t i = 0; i < c.points.size(); ++i) {
    const TractionPoint& p = c.points[i];
    ASSERT_TRUE(AllFinite(p));
    // Rigid wheel of the tyre's diameter: r = d/2 = 0.5055 m (not the 0.505 m rolling radius).
    const RigidWheelState s = SolveRigidWheel(soil, 0.5055, 0.335, 13438, req.slips[i]);
    EXPECT_DOUBLE_EQ(p.slip, req.slips[i]);
    EXPECT_NEAR(p.drawbar_pull_n, s.drawbar_pull_n, 1e-6);
    EXPECT_NEAR(p.torque_nm, s.torque_nm, 1e-6);
    EXPECT_NEAR(p.sinkage_m, s.sinkage_m, 1e-12);
    EXPECT_NEAR(p.gross_traction_n, p.torque_nm / 0.5055, 1e-6);
    EXPECT_NEAR(p.motion_resistance_n, p.gross_traction_n - p.drawbar_pull_n, 1e-6);
    const double eta =
        p.drawbar_pull_n > 0 ? p.drawbar_pull_n * (1 - p.slip) * 0.5055 / p.torque_nm : 0.0;
    EXPECT_NEAR(p.tractive_efficiency, eta, 1e-12);
    EXPECT_GT(p.sinkage_m, 0);
    EXPECT_LT(p.sinkage_m, 0.5055);
  }
}

TEST(BekkerTier, ExplicitParametersOverrideTheLibrary) {
  TractionRequest req = FedAlphaRequest("lete_sand");
  req.soil.parameters = BekkerSoilLibrary::Builtin().Find("lll_dry_sand")->parameters.ToSoilModel();
  const TractionCurve explicit_curve = BekkerTier().Compute(req);
  const TractionCurve dry = BekkerTier().Compute(FedAlphaRequest("lll_dry_sand"));
  for (size_t i = 0; i < dry.points.size(); ++i) {
    EXPECT_DOUBLE_EQ(explicit_curve.points[i].drawbar_pull_n, dry.points[i].drawbar_pull_n);
  }
  // And without any name.
  req.soil.soil_name.clear();
  EXPECT_NO_THROW(BekkerTier().Compute(req));
}

TEST(BekkerTier, UnknownSoilListsTheKnownOnes) {
  for (const std::string& name : {std::string("moon dust"), std::string()}) {
    try {
      BekkerTier().Compute(FedAlphaRequest(name));
      FAIL() << "accepted '" << name << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "soil");
      EXPECT_NE(std::string(e.what()).find("known soils: lll_dry_sand"), std::string::npos)
          << e.what();
    }
  }
  SoilState soil;
  soil.soil_name = "moon dust";
  EXPECT_THROW(BekkerTier().ValidateSoil(soil, "terrain[3].soil"), InputError);
  soil.soil_name = "Snow_Sweden";
  EXPECT_NO_THROW(BekkerTier().ValidateSoil(soil, "terrain[3].soil"));
}

TEST(BekkerTier, ElasticModeBelowTheCriticalPressure) {
  // Dry sand: p_gcr = 170.7 kPa for this wheel. At 100 kPa the tyre flattens (elastic mode), at
  // 400 kPa and when not given it is a rigid wheel.
  TractionRequest req = FedAlphaRequest("lll_dry_sand");
  const BekkerParameters soil = BekkerSoilLibrary::Builtin().Find("lll_dry_sand")->parameters;
  ASSERT_NEAR(CriticalGroundPressurePa(soil, 1.011, 0.335, 13438), 170744, 1);
  const TractionCurve rigid = BekkerTier().Compute(req);
  req.tyre.inflation_pressure_pa = 400e3;
  const TractionCurve hard = BekkerTier().Compute(req);
  req.tyre.inflation_pressure_pa = 100e3;
  const TractionCurve soft = BekkerTier().Compute(req);
  for (size_t i = 0; i < rigid.points.size(); ++i) {
    EXPECT_DOUBLE_EQ(hard.points[i].drawbar_pull_n, rigid.points[i].drawbar_pull_n);
    const FlexibleTyreState s = SolveFlexibleTyre(soil, req.tyre, 100e3, 13438, req.slips[i]);
    const TractionPoint& p = soft.points[i];
    ASSERT_TRUE(AllFinite(p));
    EXPECT_DOUBLE_EQ(p.drawbar_pull_n, s.drawbar_pull_n);
    EXPECT_DOUBLE_EQ(p.sinkage_m, s.sinkage_m);
    EXPECT_DOUBLE_EQ(p.torque_nm, s.gross_traction_n * 0.505);  // the request's rolling radius
    EXPECT_DOUBLE_EQ(p.motion_resistance_n, s.motion_resistance_n);
    // The softer tyre sinks less than the rigid wheel.
    EXPECT_LT(p.sinkage_m, rigid.points[i].sinkage_m);
  }
}

TEST(BekkerTier, ALoadTheSoilCannotCarryGivesAnImmobileCurveWithTheReason) {
  const TractionCurve c = BekkerTier().Compute(FedAlphaRequest("snow_us"));
  EXPECT_TRUE(c.points.empty()) << "no numbers for a wheel the soil cannot carry";
  EXPECT_EQ(c.immobile_reason.rfind("wheel_load_n: the soil cannot carry", 0), 0u)
      << c.immobile_reason;
  EXPECT_NE(c.immobile_reason.find("sink past its axle"), std::string::npos) << c.immobile_reason;
  // The solver itself still throws its typed error, for direct callers.
  try {
    SolveRigidWheel(BekkerSoilLibrary::Builtin().Find("snow_us")->parameters, 0.5055, 0.335,
                    14513, 0.2);
    FAIL();
  } catch (const CannotCarryError& e) {
    EXPECT_EQ(e.field(), "wheel_load_n");
  }
}

TEST(BekkerTier, InvalidRequestsNameTheField) {
  TractionRequest req = FedAlphaRequest("lete_sand");
  req.soil.parameters = BekkerParameters{0.0, 1, 1, 0, 30, 0.01}.ToSoilModel();
  try {
    BekkerTier().Compute(req);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.parameters.n");
  }
  req = FedAlphaRequest("lete_sand");
  req.slips = {0.1, 1.2};
  EXPECT_THROW(BekkerTier().Compute(req), InputError);
  req = FedAlphaRequest("lete_sand");
  req.tyre.width_m = -1;
  EXPECT_THROW(BekkerTier().Compute(req), InputError);
}

TEST(BekkerTier, PollsTheCancelCheckBetweenSlipPoints) {
  const TractionRequest req = FedAlphaRequest("lete_sand");  // 11 slips
  int calls = 0;
  const TractionCurve c = BekkerTier().Compute(req, [&] {
    ++calls;
    return false;
  });
  EXPECT_EQ(calls, 11);
  EXPECT_EQ(c.points.size(), 11u);
  calls = 0;
  EXPECT_THROW(BekkerTier().Compute(req,
                                    [&] {
                                      return ++calls > 3;  // cancelled after three points
                                    }),
               CancelledError);
  EXPECT_EQ(calls, 4);
}

TEST(BekkerTier, RegistersAndIsFoundByName) {
  TierRegistry registry;
  registry.Register(std::make_unique<BekkerTier>());
  ASSERT_NE(registry.Find("bekker"), nullptr);
  EXPECT_TRUE(registry.Find("bekker")->UsesSoilName());
}

}  // namespace
}  // namespace gonogo::tiers
