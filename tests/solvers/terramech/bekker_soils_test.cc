// The Bekker soil library: the built-in rows against Wong (2008) Table 2.3 as printed (kN units,
// converted here), the embedded text against the file, lookup, and the parser's errors.
#include "solvers/terramech/bekker_soils.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/common/errors.h"

namespace gonogo::terramech {
namespace {

// Wong, Theory of Ground Vehicles, 4th ed. (2008), Table 2.3, in the book's units:
// n, kc kN/m^(n+1), kphi kN/m^(n+2), c kPa, phi degrees.
struct TableRow {
  const char* name;
  double n, kc_kn, kphi_kn, c_kpa, phi_deg;
};
const TableRow kWongTable23[] = {
    {"lll_dry_sand", 1.1, 0.99, 1528.43, 1.04, 28.0},
    {"lll_sandy_loam_15pct", 0.7, 5.27, 1515.04, 1.72, 29.0},
    {"lll_sandy_loam_22pct", 0.2, 2.56, 43.12, 1.38, 38.0},
    {"michigan_sandy_loam_11pct", 0.9, 52.53, 1127.97, 4.83, 20.0},
    {"michigan_sandy_loam_23pct", 0.4, 11.42, 808.96, 9.65, 35.0},
    {"hanamoto_sandy_loam_26pct", 0.3, 2.79, 141.11, 13.79, 22.0},
    {"hanamoto_sandy_loam_32pct", 0.5, 0.77, 51.91, 5.17, 11.0},
    {"thailand_clayey_soil_38pct", 0.5, 13.19, 692.15, 4.14, 13.0},
    {"thailand_clayey_soil_55pct", 0.7, 16.03, 1262.53, 2.07, 10.0},
    {"wes_heavy_clay_25pct", 0.13, 12.70, 1555.95, 68.95, 34.0},
    {"wes_heavy_clay_40pct", 0.11, 1.84, 103.27, 20.69, 6.0},
    {"wes_lean_clay_22pct", 0.2, 16.43, 1724.69, 68.95, 20.0},
    {"wes_lean_clay_32pct", 0.15, 1.52, 119.61, 13.79, 11.0},
    {"lete_sand", 0.79, 102.0, 5301.0, 1.3, 31.1},
    {"upland_sandy_loam_51pct", 1.10, 74.6, 2080.0, 3.3, 33.7},
    {"rubicon_sandy_loam_43pct", 0.66, 6.9, 752.0, 3.7, 29.8},
    {"north_gower_clayey_loam_46pct", 0.73, 41.6, 2471.0, 6.1, 26.6},
    {"grenville_loam_24pct", 1.01, 0.06, 5880.0, 3.1, 29.8},
    {"snow_us", 1.6, 4.37, 196.72, 1.03, 19.7},
    {"snow_us_harrison", 1.6, 2.49, 245.90, 0.62, 23.2},
    {"snow_sweden", 1.44, 10.55, 66.08, 6.0, 20.7},
};

TEST(BekkerSoilLibrary, BuiltinRowsAreWongTable23InSiUnits) {
  const BekkerSoilLibrary& lib = BekkerSoilLibrary::Builtin();
  ASSERT_EQ(lib.Soils().size(), std::size(kWongTable23));
  for (const TableRow& row : kWongTable23) {
    const BekkerSoil* soil = lib.Find(row.name);
    ASSERT_NE(soil, nullptr) << row.name;
    const BekkerParameters& p = soil->parameters;
    // kN/m^(n+1) -> N/m^(n+1) and kN/m^(n+2) -> N/m^(n+2) and kPa -> Pa: x 1000, whatever n.
    EXPECT_NEAR(p.kc, row.kc_kn * 1000, 1e-9 * p.kc) << row.name;
    EXPECT_NEAR(p.kphi, row.kphi_kn * 1000, 1e-9 * p.kphi) << row.name;
    EXPECT_NEAR(p.cohesion_pa, row.c_kpa * 1000, 1e-9 * p.cohesion_pa) << row.name;
    EXPECT_DOUBLE_EQ(p.n, row.n) << row.name;
    EXPECT_DOUBLE_EQ(p.friction_angle_deg, row.phi_deg) << row.name;
    EXPECT_NE(soil->source.find("Table 2.3"), std::string::npos) << row.name;
    EXPECT_NE(soil->source.find("K "), std::string::npos) << row.name << ": K source";
  }
  // Spot values in SI written out: dry sand kc = 990 N/m^2.1, kphi = 1,528,430 N/m^3.1.
  EXPECT_DOUBLE_EQ(lib.Find("lll_dry_sand")->parameters.kc, 990.0);
  EXPECT_DOUBLE_EQ(lib.Find("lll_dry_sand")->parameters.kphi, 1528430.0);
  EXPECT_DOUBLE_EQ(lib.Find("lete_sand")->parameters.kphi, 5301000.0);
}

TEST(BekkerSoilLibrary, ShearDeformationModuliByTerrainClass) {
  // Wong (2008) 2.4.3 after Bekker (1969): loose sand 2.5 cm, firm sand 1 cm, clay at maximum
  // compaction 0.6 cm, fresh snow 2.5 cm.
  const BekkerSoilLibrary& lib = BekkerSoilLibrary::Builtin();
  EXPECT_DOUBLE_EQ(lib.Find("lll_dry_sand")->parameters.shear_deformation_m, 0.025);
  EXPECT_DOUBLE_EQ(lib.Find("lete_sand")->parameters.shear_deformation_m, 0.01);
  EXPECT_DOUBLE_EQ(lib.Find("wes_heavy_clay_25pct")->parameters.shear_deformation_m, 0.006);
  EXPECT_DOUBLE_EQ(lib.Find("snow_sweden")->parameters.shear_deformation_m, 0.025);
}

TEST(BekkerSoilLibrary, EmbeddedTextIsTheDataFile) {
  const char* root = std::getenv("GONOGO_SOURCE_DIR");
  if (root == nullptr) GTEST_SKIP() << "GONOGO_SOURCE_DIR not set";
  std::ifstream in(std::string(root) + "/solvers/terramech/data/bekker_soils.csv");
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), std::string(BuiltinBekkerSoilsCsv()));
}

TEST(BekkerSoilLibrary, FindIsCaseInsensitiveAndNamesKeepFileOrder) {
  const BekkerSoilLibrary& lib = BekkerSoilLibrary::Builtin();
  ASSERT_NE(lib.Find("LETE_Sand"), nullptr);
  EXPECT_EQ(lib.Find("LETE_Sand")->name, "lete_sand");
  EXPECT_EQ(lib.Find(" lete_sand "), lib.Find("lete_sand"));
  EXPECT_EQ(lib.Find("moon dust"), nullptr);
  EXPECT_EQ(lib.Find(""), nullptr);
  const std::vector<std::string> names = lib.Names();
  ASSERT_EQ(names.size(), std::size(kWongTable23));
  for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(names[i], kWongTable23[i].name);
}

const char kHeader[] = "name,n,kc,kphi,cohesion_pa,friction_angle_deg,shear_deformation_m,source\n";

TEST(BekkerSoilLibrary, ParsesCommentsBlankLinesAndCommasInTheSource) {
  const BekkerSoilLibrary lib = BekkerSoilLibrary::Parse(
      std::string("# a comment\n\n") + kHeader +
      "  # another\n"
      "Test_Sand, 1.0, 1000, 2e6, 0, 30, 0.02, Somebody (2020), Table 1, row 2\n");
  ASSERT_EQ(lib.Soils().size(), 1u);
  const BekkerSoil& s = lib.Soils()[0];
  EXPECT_EQ(s.name, "Test_Sand");
  EXPECT_EQ(s.source, "Somebody (2020), Table 1, row 2");
  EXPECT_DOUBLE_EQ(s.parameters.kphi, 2e6);
  EXPECT_DOUBLE_EQ(s.parameters.cohesion_pa, 0.0);
  EXPECT_NE(lib.Find("test_sand"), nullptr);
}

void ExpectParseError(const std::string& text, const std::string& field) {
  try {
    BekkerSoilLibrary::Parse(text);
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

TEST(BekkerSoilLibrary, BadRowsNameLineAndColumn) {
  const std::string good = "a,1.0,1000,2e6,500,30,0.02,src\n";
  ExpectParseError("", "line 1 column name");
  ExpectParseError("name,n,kc\n", "line 1 column kphi");
  ExpectParseError(std::string(kHeader) + good + "b,1.0,abc,2e6,500,30,0.02,src\n",
                   "line 3 column kc");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000\n", "line 2 column kphi");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000,2e6,500,30,,src\n",
                   "line 2 column shear_deformation_m");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000,2e6,500,30,0.02,\n", "line 2 column source");
  ExpectParseError(std::string(kHeader) + "b,inf,1000,2e6,500,30,0.02,src\n", "line 2 column n");
  // Physically invalid values: the column of the failing parameter.
  ExpectParseError(std::string(kHeader) + "b,0,1000,2e6,500,30,0.02,src\n", "line 2 column n");
  ExpectParseError(std::string(kHeader) + "b,1.0,-1,2e6,500,30,0.02,src\n", "line 2 column kc");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000,-2e6,500,30,0.02,src\n",
                   "line 2 column kphi");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000,2e6,500,95,0.02,src\n",
                   "line 2 column friction_angle_deg");
  ExpectParseError(std::string(kHeader) + "b,1.0,1000,2e6,500,30,0,src\n",
                   "line 2 column shear_deformation_m");
  ExpectParseError(std::string(kHeader) + good + "A,1.0,1000,2e6,500,30,0.02,src\n",
                   "line 3 column name");
}

}  // namespace
}  // namespace gonogo::terramech
