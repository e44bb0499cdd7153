// The soil catalogue: every built-in table validates against its model, names resolve across
// models, and the tiers' own libraries agree with it.
#include "solvers/tiers/soil_catalogue.h"

#include <gtest/gtest.h>

#include "solvers/common/errors.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/terramech/bekker_soils.h"

namespace gonogo::tiers {
namespace {

TEST(SoilCatalogue, EveryBuiltinTableValidatesAndCarriesItsSource) {
  const SoilCatalogue& c = BuiltinSoilCatalogue();
  EXPECT_GE(c.Entries().size(), terramech::BekkerSoilLibrary::Builtin().Names().size() +
                                    rig::FeSoilLibrary::Builtin().Names().size() + 3);
  for (const CatalogueEntry& e : c.Entries()) {
    EXPECT_FALSE(e.source.empty()) << e.soil;
    EXPECT_NO_THROW(SoilModels().Validate(e.parameters, e.soil)) << e.soil;
  }
}

TEST(SoilCatalogue, ASoilHasASetPerModelItIsCalibratedFor) {
  const SoilCatalogue& c = BuiltinSoilCatalogue();
  // LETE sand: Bekker parameters (Wong Table 2.3) and an FE continuum of the same strength.
  EXPECT_EQ(c.ModelsOf("LETE_sand"), (std::vector<std::string>{"bekker", "drucker-prager"}));
  const CatalogueEntry* bekker = c.Find("lete_sand", "bekker");
  const CatalogueEntry* dp = c.Find("lete_sand", "drucker-prager");
  ASSERT_TRUE(bekker && dp);
  EXPECT_DOUBLE_EQ(bekker->parameters.Get("friction_angle_deg"),
                   dp->parameters.Get("friction_angle_deg"));
  // The tiers' libraries read the same tables.
  const BekkerParameters lib = terramech::BekkerSoilLibrary::Builtin().Find("lete_sand")->parameters;
  EXPECT_EQ(BekkerParameters::FromSoilModel(bekker->parameters).kphi, lib.kphi);
  // Seed 001's EEPA soils and seed 000's RVE grains.
  ASSERT_NE(c.Find("FGS", "dem-eepa"), nullptr);
  EXPECT_DOUBLE_EQ(c.Find("FGS", "dem-eepa")->parameters.Get("surface_energy_j_m2"), 7.0);
  EXPECT_DOUBLE_EQ(c.Find("2NS_sand", "dem-eepa")->parameters.Get("pull_off_force_n"), -60.0);
  EXPECT_DOUBLE_EQ(c.Find("seed000_sand", "dem-hertz-mindlin")->parameters.Get("friction"), 0.452);
  EXPECT_EQ(c.Find("lete_sand", "dem-eepa"), nullptr);
}

TEST(SoilCatalogue, ATableThatDriftsFromItsModelIsRefusedNamingTheColumn) {
  SoilCatalogue c;
  try {
    c.AddTable("bekker", "name,n,kc,kphi,c,friction_angle_deg,shear_deformation_m,source\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "bekker table column c");
  }
  try {
    c.AddTable("dem-eepa", "name,friction,source\nx,-1,somewhere\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "dem-eepa table line 2.friction");
  }
}

}  // namespace
}  // namespace gonogo::tiers
