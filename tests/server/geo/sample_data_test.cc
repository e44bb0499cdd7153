// clients/sample-data/make_sample_terrain.py: its rasters load through both input paths, and the
// server's slope from elevation.tif matches the script's slope.tif (same Horn scheme, same grid).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "server/geo/terrain.h"
#include "tests/server/geo/test_rasters.h"

namespace gonogo::geo {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

size_t CountOf(const std::string& text, const std::string& needle) {
  size_t count = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) {
    ++count;
  }
  return count;
}

TEST(SampleTerrain, LoadsThroughBothInputPathsWithMatchingSlopes) {
  const char* source_dir = std::getenv("GONOGO_SOURCE_DIR");
  if (source_dir == nullptr) GTEST_SKIP() << "GONOGO_SOURCE_DIR not set (run through ctest)";
  fixtures::TempDir dir("geo_sample");
  std::string output;
  const int status =
      fixtures::RunCommand(std::string("/usr/bin/python3 '") + source_dir +
                               "/clients/sample-data/make_sample_terrain.py' --out '" + dir.path() +
                               "' --size 120 --cell-m 10",
                           &output);
  ASSERT_EQ(status, 0) << output;

  TerrainInputs inputs;
  inputs.cone_index.bytes = ReadFile(dir.path() + "/cone_index.tif");
  inputs.soil_class = RasterInput{ReadFile(dir.path() + "/soil_class.tif")};
  inputs.elevation = RasterInput{ReadFile(dir.path() + "/elevation.tif")};
  const TerrainLayers from_elevation = LoadTerrain(inputs, {});
  inputs.elevation.reset();
  inputs.slope = RasterInput{ReadFile(dir.path() + "/slope.tif")};
  const TerrainLayers from_slope = LoadTerrain(inputs, {});

  ASSERT_EQ(from_elevation.grid.width, 120);
  ASSERT_EQ(from_elevation.grid.height, 120);
  EXPECT_DOUBLE_EQ(from_elevation.grid.CellAreaM2(0), 100.0);
  int nodata = 0;
  float max_slope = 0.0f;
  for (size_t i = 0; i < from_elevation.valid.size(); ++i) {
    // slope.tif is rounded to 0.001 %.
    ASSERT_NEAR(from_elevation.slope_percent[i], from_slope.slope_percent[i], 2e-3) << i;
    max_slope = std::max(max_slope, from_elevation.slope_percent[i]);
    const float cone = from_elevation.cone_index_kpa[i];
    if (std::isnan(cone)) {
      ++nodata;
      EXPECT_EQ(from_elevation.valid[i], 0);
      continue;
    }
    EXPECT_TRUE(cone >= 100.0f && cone <= 3000.0f) << cone;
    const int32_t soil = from_elevation.soil_class[i];
    EXPECT_TRUE(soil >= 1 && soil <= 3) << soil;
    EXPECT_EQ(from_elevation.valid[i], 1);
  }
  EXPECT_GT(nodata, 0);
  EXPECT_LT(nodata, 100);
  EXPECT_NEAR(max_slope, 80.0, 5.0);

  const std::string table = ReadFile(dir.path() + "/soil_table.json");
  EXPECT_EQ(CountOf(table, "\"remolding_index\""), 3u) << table;
  EXPECT_EQ(CountOf(table, "\"code\""), 3u) << table;
}

}  // namespace
}  // namespace gonogo::geo
