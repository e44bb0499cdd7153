// The soil-model declarations: validation names the field, the unit and the range; defaults fill in;
// the canonical text is sorted, nine digits, and reads back; every built-in model accepts its own
// defaults or a documented set (seed values).
#include "solvers/common/soil_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/traction.h"

namespace gonogo {
namespace {

std::string FieldOf(const SoilParameters& p) {
  try {
    SoilModels().Validate(p, "soil.parameters");
  } catch (const InputError& e) {
    return e.field() + " | " + e.what();
  }
  return "";
}

TEST(SoilModel, ValidationNamesTheFieldTheUnitAndTheRange) {
  SoilParameters lete = BekkerParameters{0.79, 102000, 5301000, 1300, 31.1, 0.0115}.ToSoilModel();
  EXPECT_EQ(FieldOf(lete), "");

  SoilParameters steep = lete;
  steep.values["friction_angle_deg"] = 95;
  const std::string e = FieldOf(steep);
  EXPECT_EQ(e.rfind("soil.parameters.friction_angle_deg | ", 0), 0u) << e;
  EXPECT_NE(e.find("(0, 90) deg"), std::string::npos) << e;
  EXPECT_NE(e.find("got 95"), std::string::npos) << e;

  SoilParameters missing = lete;
  missing.values.erase("kphi");
  EXPECT_EQ(FieldOf(missing).rfind("soil.parameters.kphi | ", 0), 0u) << FieldOf(missing);

  SoilParameters unknown = lete;
  unknown.values["kphi2"] = 1;
  EXPECT_NE(FieldOf(unknown).find("soil.parameters.kphi2 | "), std::string::npos);
  EXPECT_NE(FieldOf(unknown).find("its parameters: n, kc, kphi"), std::string::npos);

  SoilParameters both_zero = lete;
  both_zero.values["kc"] = 0;
  both_zero.values["kphi"] = 0;
  EXPECT_EQ(FieldOf(both_zero).rfind("soil.parameters.kphi | ", 0), 0u) << "the model's own rule";

  SoilParameters nan = lete;
  nan.values["n"] = NAN;
  EXPECT_EQ(FieldOf(nan).rfind("soil.parameters.n | ", 0), 0u);

  EXPECT_EQ(FieldOf(SoilParameters{"moon-dust", {}}).rfind("soil.parameters.model | ", 0), 0u);
  EXPECT_NE(FieldOf(SoilParameters{"moon-dust", {}}).find("known: bekker, "), std::string::npos);
}

TEST(SoilModel, DefaultsFillInAndSeedValuesAreTheDefaults) {
  // dem-hertz-mindlin with nothing given is seed 000's grain set (rve_hertz_mindlin.csv).
  const SoilParameters seed = SoilModels().Validate({"dem-hertz-mindlin", {}}, "soil");
  EXPECT_DOUBLE_EQ(seed.Get("young_pa"), 1.5e9);
  EXPECT_DOUBLE_EQ(seed.Get("poisson"), 0.293);
  EXPECT_DOUBLE_EQ(seed.Get("friction"), 0.452);
  EXPECT_DOUBLE_EQ(seed.Get("rolling_stiffness"), 2.25);
  EXPECT_DOUBLE_EQ(seed.Get("rolling_limit"), 0.99);
  EXPECT_DOUBLE_EQ(seed.Get("particle_radius_m"), 0.87e-3);
  EXPECT_DOUBLE_EQ(seed.Get("grains_per_rve"), 500);
  // dem-eepa defaults are seed 001 Table 3's FGS column (soils_dem_eepa.csv).
  const SoilParameters fgs = SoilModels().Validate({"dem-eepa", {}}, "soil");
  EXPECT_DOUBLE_EQ(fgs.Get("shear_modulus_pa"), 5.0e8);
  EXPECT_DOUBLE_EQ(fgs.Get("pull_off_force_n"), -2.0);
  EXPECT_DOUBLE_EQ(fgs.Get("surface_energy_j_m2"), 7.0);
  EXPECT_DOUBLE_EQ(fgs.Get("plasticity_ratio"), 0.9);
  // Bekker has no defaults: every parameter is the soil.
  EXPECT_NE(FieldOf({"bekker", {}}), "");
  // Drucker-Prager: dilation defaults to 0 and may not exceed friction.
  SoilParameters dp{"drucker-prager",
                    {{"density_kg_m3", 1500}, {"young_pa", 1.5e7}, {"poisson", 0.3},
                     {"cohesion_pa", 1040}, {"friction_angle_deg", 28}}};
  EXPECT_DOUBLE_EQ(SoilModels().Validate(dp, "soil").Get("dilation_angle_deg"), 0);
  dp.values["dilation_angle_deg"] = 30;
  EXPECT_EQ(FieldOf(dp).rfind("soil.parameters.dilation_angle_deg | ", 0), 0u);
}

TEST(SoilModel, CanonicalTextIsSortedNineDigitsAndReadsBack) {
  const SoilParameters p{"bekker", {{"n", 0.79}, {"kc", 102000}, {"kphi", 5301000},
                                    {"cohesion_pa", 1300}, {"friction_angle_deg", 31.1},
                                    {"shear_deformation_m", 0.0115}}};
  EXPECT_EQ(CanonicalText(p),
            "bekker{cohesion_pa=1300,friction_angle_deg=31.1,kc=102000,kphi=5301000,n=0.79,"
            "shear_deformation_m=0.0115}");
  EXPECT_EQ(ParseCanonicalText(CanonicalText(p)), p);
  EXPECT_EQ(CanonicalText(std::nullopt), "");
  EXPECT_FALSE(ParseCanonicalText("").has_value());
  EXPECT_THROW(ParseCanonicalText("bekker{n=}"), std::invalid_argument);
  EXPECT_THROW(ParseCanonicalText("n=0.7,kc=1"), std::invalid_argument);
  SoilParameters long_digits{"bekker", {{"n", 0.1234567891234}}};
  EXPECT_DOUBLE_EQ(SnapToCanonical(long_digits).Get("n"), 0.123456789);
}

TEST(SoilModel, BekkerParametersRoundTripThroughTheModel) {
  const BekkerParameters b{0.79, 102000, 5301000, 1300, 31.1, 0.0115};
  const BekkerParameters back = BekkerParameters::FromSoilModel(b.ToSoilModel());
  EXPECT_EQ(back.n, b.n);
  EXPECT_EQ(back.kc, b.kc);
  EXPECT_EQ(back.kphi, b.kphi);
  EXPECT_EQ(back.cohesion_pa, b.cohesion_pa);
  EXPECT_EQ(back.friction_angle_deg, b.friction_angle_deg);
  EXPECT_EQ(back.shear_deformation_m, b.shear_deformation_m);
  EXPECT_THROW(BekkerParameters::FromSoilModel({"dem-eepa", {}}), InputError);
}

TEST(SoilModel, RegistryRefusesDuplicatesAndListsNames) {
  SoilModelRegistry registry;
  RegisterBuiltinSoilModels(registry);
  EXPECT_EQ(registry.Names(), (std::vector<std::string>{"bekker", "dem-eepa", "dem-hertz-mindlin",
                                                        "drucker-prager", "linear-elastic"}));
  SoilModelSpec again;
  again.name = "bekker";
  EXPECT_THROW(registry.Register(again), InputError);
}

}  // namespace
}  // namespace gonogo
