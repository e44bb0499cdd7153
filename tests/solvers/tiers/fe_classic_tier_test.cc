// The fe-classic tier's adapter: which soils it resolves (a library name or drucker-prager
// parameters) and an immobile curve for a soil that cannot carry the wheel. The rig's physics is
// tested in tests/solvers/rig.
#include "solvers/tiers/fe_classic_tier.h"

#include <gtest/gtest.h>

#include "solvers/common/errors.h"

namespace gonogo::tiers {
namespace {

TEST(FeClassicTierTest, NamesTheSoilItCannotResolve) {
  FeClassicTier tier;
  SoilState soil;
  soil.soil_name = "no_such_soil";
  try {
    tier.ValidateSoil(soil, "soil");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.soil_name");
    EXPECT_NE(std::string(e.what()).find("lll_dry_sand"), std::string::npos) << e.what();
  }
  soil.soil_name = "lll_dry_sand";
  EXPECT_NO_THROW(tier.ValidateSoil(soil, "soil"));
  soil.parameters = BekkerParameters{}.ToSoilModel();
  EXPECT_THROW(tier.ValidateSoil(soil, "soil"), InputError);
}

TEST(FeClassicTierTest, ASoilThatCannotCarryTheWheelGivesAnImmobileCurve) {
  FeClassicTier tier(rig::FeSoilLibrary::Builtin(), FeClassicOptions{3, 2});
  TractionRequest r;
  r.soil.soil_name = "thailand_clayey_soil_38pct";
  r.tyre.diameter_m = 0.505;
  r.tyre.width_m = 0.167;
  r.tyre.section_height_m = 0.1;
  r.wheel_load_n = 60000;  // ~700 kPa under a small wheel on soft clay
  r.slips = TractionRequest::SlipSweep(0.25);
  const TractionCurve curve = tier.Compute(r);
  EXPECT_TRUE(curve.points.empty());
  EXPECT_NE(curve.immobile_reason.find("axle"), std::string::npos) << curve.immobile_reason;
}

TEST(FeClassicTierTest, DruckerPragerParametersStandInForALibrarySoil) {
  FeClassicTier tier;
  const rig::FeSoil& dry = *rig::FeSoilLibrary::Builtin().Find("lll_dry_sand");
  SoilState soil;
  soil.parameters = SoilParameters{"drucker-prager",
                                   {{"density_kg_m3", dry.density_kg_m3},
                                    {"young_pa", dry.strength.young_pa},
                                    {"poisson", dry.strength.poisson},
                                    {"cohesion_pa", dry.strength.cohesion_pa},
                                    {"friction_angle_deg", dry.strength.friction_angle_deg}}};
  const rig::FeSoil resolved = tier.ResolveSoil(soil, "soil");
  EXPECT_EQ(resolved.density_kg_m3, dry.density_kg_m3);
  EXPECT_EQ(resolved.strength.young_pa, dry.strength.young_pa);
  EXPECT_EQ(resolved.strength.friction_angle_deg, dry.strength.friction_angle_deg);
  EXPECT_EQ(resolved.strength.dilation_angle_deg, 0.0) << "the model's default";
  soil.parameters->values["poisson"] = 0.6;
  try {
    tier.ValidateSoil(soil, "soil");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.parameters.poisson");
  }
  soil.parameters = SoilParameters{"dem-eepa", {}};
  try {
    tier.ValidateSoil(soil, "soil");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil.parameters.model");
  }
}

}  // namespace
}  // namespace gonogo::tiers
