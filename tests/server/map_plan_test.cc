#include "server/map_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/tiers/empirical_tier.h"

namespace gonogo::server {
namespace {

mobility::VehicleSpec Vehicle() {
  mobility::VehicleSpec v;
  v.mass_kg = 5481;
  const TyreGeometry tyre{1.011, 0.335, 0.2178, 0.0327, 0};
  v.axles = {{0.54, 2, tyre, true}, {0.46, 2, tyre, true}};
  v.drive_power_w = 149000;
  v.max_speed_kmh = 110;
  return v;
}

geo::TerrainLayers Terrain() {
  geo::TerrainLayers t;
  t.grid.width = 3;
  t.grid.height = 2;
  // Two cells share a cone index, one differs by under half a bin, one is no data.
  t.cone_index_kpa = {300, 300, 300.4, 2000, NAN, 300};
  t.slope_percent = {0, 10, 0, 0, 0, 200};
  t.soil_class = {1, 1, 1, 1, 1, 2};
  t.valid = {1, 1, 1, 1, 0, 1};
  return t;
}

TEST(PlanMap, CellsWithTheSameSoilAndBinShareAUnit) {
  tiers::EmpiricalTier tier;
  const std::map<int32_t, SoilClassInfo> soils = {{1, {"sand", 1.0, std::nullopt}}, {2, {"clay", 0.5, std::nullopt}}};
  const MapPlan plan = PlanMap(Terrain(), Vehicle(), soils, tier, TractionRequest::SlipSweep(0.05));
  EXPECT_EQ(plan.cell_unit[0], plan.cell_unit[1]);
  EXPECT_EQ(plan.cell_unit[0], plan.cell_unit[2]) << "300.4 kPa falls in the 300 kPa bin";
  EXPECT_NE(plan.cell_unit[0], plan.cell_unit[3]);
  EXPECT_EQ(plan.cell_unit[4], -1);
  ASSERT_EQ(plan.units.size(), 3u);
  // Class 2 has RI 0.5: RCI = 150 kPa.
  EXPECT_NEAR(plan.units[plan.cell_unit[5]].rating_cone_index_pa, 150e3, 0.006 * 150e3);
  // Two axles with different loads: two tasks per unit.
  EXPECT_EQ(plan.tasks.size(), 6u);
  EXPECT_EQ(plan.units[plan.cell_unit[0]].cells, 3);
}

TEST(PlanMap, UnknownSoilClassNamesTheCell) {
  tiers::EmpiricalTier tier;
  try {
    PlanMap(Terrain(), Vehicle(), {{1, {"sand", 1.0, std::nullopt}}}, tier, {0, 0.5, 1});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "soil_class");
    EXPECT_NE(std::string(e.what()).find("row 1 col 2"), std::string::npos) << e.what();
  }
}

TEST(EvaluateMap, SteepAndNoDataCellsAreClassified) {
  tiers::EmpiricalTier tier;
  const auto terrain = Terrain();
  const std::map<int32_t, SoilClassInfo> soils = {{1, {"sand", 1.0, std::nullopt}}, {2, {"clay", 1.0, std::nullopt}}};
  const MapPlan plan = PlanMap(terrain, Vehicle(), soils, tier, TractionRequest::SlipSweep(0.05));
  std::vector<TractionCurve> curves;
  for (const auto& t : plan.tasks) curves.push_back(tier.Compute(t));
  mobility::Criteria criteria;
  const MapVerdicts v = EvaluateMap(plan, terrain, Vehicle(), criteria, curves, 0);
  EXPECT_EQ(v.go_class[4], 255) << "no data";
  EXPECT_TRUE(std::isnan(v.speed_kmh[4]));
  EXPECT_EQ(v.go_class[5], 0) << "a 200 % slope is NO-GO";
  EXPECT_EQ(v.go_class[3], 2) << "2 MPa flat ground is GO";
  EXPECT_GT(v.speed_kmh[3], 0);
  // The soft-soil test alone turns every cell below the VCI to NO-GO.
  const MapVerdicts soft = EvaluateMap(plan, terrain, Vehicle(), criteria, curves, 1e9);
  for (int c : {0, 1, 2, 3, 5}) EXPECT_EQ(soft.go_class[c], 0) << c;
}

}  // namespace
}  // namespace gonogo::server
