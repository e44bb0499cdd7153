// LoadTerrain: input checks (every error names its field), warping from other grids and CRSs, and
// nodata handling.
#include "server/geo/terrain.h"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <thread>

#include "solvers/common/errors.h"
#include "tests/server/geo/test_rasters.h"

namespace gonogo::geo {
namespace {

using fixtures::MakeGeoTiff;
using fixtures::RasterSpec;

constexpr double kNoData = -9999.0;

RasterSpec Filled(double value) {
  RasterSpec spec;
  spec.fill = value;
  return spec;
}

// A valid 20 x 20 cone-index grid with a 5 % slope raster on the same grid.
TerrainInputs BasicInputs() {
  TerrainInputs inputs;
  inputs.cone_index.bytes = MakeGeoTiff(Filled(500.0));
  inputs.slope = RasterInput{MakeGeoTiff(Filled(5.0))};
  return inputs;
}

// LoadTerrain must throw InputError naming `field`; returns the message.
std::string InputErrorOf(const TerrainInputs& inputs, const std::string& field,
                         const GeoLimits& limits = {}) {
  try {
    LoadTerrain(inputs, limits);
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError(" << field << "), got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected InputError(" << field << "), got success";
  return "";
}

std::string LimitErrorOf(const TerrainInputs& inputs, const std::string& field,
                         const GeoLimits& limits) {
  try {
    LoadTerrain(inputs, limits);
  } catch (const LimitError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected LimitError(" << field << "), got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected LimitError(" << field << "), got success";
  return "";
}

bool SameCrs(const std::string& wkt, int epsg) {
  OGRSpatialReference a, b;
  a.importFromWkt(wkt.c_str());
  b.importFromEPSG(epsg);
  return a.IsSame(&b);
}

TEST(LoadTerrain, SameGridLayersKeepValuesAndNodata) {
  RasterSpec cone = Filled(500.0);
  cone.nodata = kNoData;
  cone.values.assign(400, 500.0);
  cone.values[0] = kNoData;
  cone.values[7] = 1234.5;
  RasterSpec soil;
  soil.type = GDT_Byte;
  soil.nodata = 0;
  soil.values.resize(400);
  for (int i = 0; i < 400; ++i) soil.values[i] = (i % 20) < 10 ? 1 : 2;
  soil.values[5 * 20 + 5] = 0;
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(cone);
  inputs.soil_class = RasterInput{MakeGeoTiff(soil)};

  const TerrainLayers t = LoadTerrain(inputs, {});
  EXPECT_EQ(t.grid.width, 20);
  EXPECT_EQ(t.grid.height, 20);
  EXPECT_EQ(t.grid.geotransform, cone.geotransform);
  EXPECT_TRUE(SameCrs(t.grid.crs_wkt, 32617));
  ASSERT_EQ(t.cone_index_kpa.size(), 400u);
  ASSERT_EQ(t.slope_percent.size(), 400u);
  ASSERT_EQ(t.soil_class.size(), 400u);
  ASSERT_EQ(t.valid.size(), 400u);
  EXPECT_TRUE(std::isnan(t.cone_index_kpa[0]));
  EXPECT_FLOAT_EQ(t.cone_index_kpa[7], 1234.5f);
  EXPECT_EQ(t.soil_class[5 * 20 + 5], -1);
  EXPECT_EQ(t.soil_class[3], 1);
  EXPECT_EQ(t.soil_class[15], 2);
  int valid = 0;
  for (int i = 0; i < 400; ++i) {
    EXPECT_NEAR(t.slope_percent[i], 5.0, 1e-5);
    valid += t.valid[i];
  }
  EXPECT_EQ(valid, 398);
  EXPECT_EQ(t.valid[0], 0);
  EXPECT_EQ(t.valid[5 * 20 + 5], 0);
}

TEST(LoadTerrain, NanConeCellsAreNodata) {
  RasterSpec cone = Filled(500.0);
  cone.values.assign(400, 500.0);
  cone.values[42] = std::nan("");
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(cone);
  const TerrainLayers t = LoadTerrain(inputs, {});
  EXPECT_TRUE(std::isnan(t.cone_index_kpa[42]));
  EXPECT_EQ(t.valid[42], 0);
  EXPECT_EQ(t.valid[43], 1);
  EXPECT_TRUE(t.soil_class.empty());
}

TEST(LoadTerrain, AcceptsOtherSelfContainedFormats) {
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{fixtures::MakeRasterFile(Filled(8.0), "HFA")};
  const TerrainLayers t = LoadTerrain(inputs, {});
  EXPECT_NEAR(t.slope_percent[123], 8.0, 1e-5);
}

TEST(LoadTerrain, RejectsFilesThatAreNotRasters) {
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = "this is not a raster";
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("not a raster"), std::string::npos);
  inputs.cone_index.bytes = "";
  InputErrorOf(inputs, "cone_index");

  inputs = BasicInputs();
  inputs.slope = RasterInput{R"({"type": "FeatureCollection", "features": []})"};
  InputErrorOf(inputs, "slope");

  // A VRT could make the server read its own files; only self-contained formats are opened.
  inputs = BasicInputs();
  inputs.soil_class = RasterInput{
      R"(<VRTDataset rasterXSize="2" rasterYSize="2"><VRTRasterBand dataType="Byte" band="1">)"
      R"(<SimpleSource><SourceFilename>/etc/passwd</SourceFilename></SimpleSource>)"
      R"(</VRTRasterBand></VRTDataset>)"};
  InputErrorOf(inputs, "soil_class");
}

TEST(LoadTerrain, RejectsRasterWithoutBands) {
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = fixtures::MakeTwoTableGeoPackage();
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("no bands"), std::string::npos);
}

TEST(LoadTerrain, RejectsMissingCrsOrGeotransform) {
  RasterSpec no_crs = Filled(500.0);
  no_crs.epsg = 0;
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(no_crs);
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("no CRS"), std::string::npos);

  inputs = BasicInputs();
  inputs.soil_class = RasterInput{MakeGeoTiff(no_crs)};
  InputErrorOf(inputs, "soil_class");

  RasterSpec no_geotransform = Filled(300.0);
  no_geotransform.georeferenced = false;
  no_geotransform.epsg = 0;
  inputs = BasicInputs();
  inputs.slope.reset();
  inputs.elevation = RasterInput{MakeGeoTiff(no_geotransform)};
  InputErrorOf(inputs, "elevation");
}

TEST(LoadTerrain, RejectsAllNodata) {
  RasterSpec all_nodata = Filled(kNoData);
  all_nodata.nodata = kNoData;
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(all_nodata);
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("all cells are nodata"), std::string::npos);

  RasterSpec all_nan = Filled(std::nan(""));
  inputs.cone_index.bytes = MakeGeoTiff(all_nan);
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("all cells are nodata"), std::string::npos);

  inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(all_nodata)};
  EXPECT_NE(InputErrorOf(inputs, "slope").find("all cells are nodata"), std::string::npos);

  inputs.slope.reset();
  inputs.elevation = RasterInput{MakeGeoTiff(all_nan)};
  EXPECT_NE(InputErrorOf(inputs, "elevation").find("all cells are nodata"), std::string::npos);
}

TEST(LoadTerrain, RejectsNegativeConeIndexWithItsCell) {
  RasterSpec cone = Filled(500.0);
  cone.values.assign(400, 500.0);
  cone.values[2 * 20 + 3] = -5.0;
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(cone);
  const std::string message = InputErrorOf(inputs, "cone_index");
  EXPECT_NE(message.find("negative value -5"), std::string::npos) << message;
  EXPECT_NE(message.find("row 2 col 3"), std::string::npos) << message;
}

TEST(LoadTerrain, RejectsOutOfRangeSlopeAndSoilCodes) {
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(Filled(-2.0))};
  InputErrorOf(inputs, "slope");

  inputs = BasicInputs();
  inputs.soil_class = RasterInput{MakeGeoTiff(Filled(1.5))};
  EXPECT_NE(InputErrorOf(inputs, "soil_class").find("not an integer"), std::string::npos);
  inputs.soil_class = RasterInput{MakeGeoTiff(Filled(-3.0))};
  InputErrorOf(inputs, "soil_class");
}

TEST(LoadTerrain, NeedsExactlyOneOfSlopeAndElevation) {
  TerrainInputs inputs = BasicInputs();
  inputs.slope.reset();
  InputErrorOf(inputs, "slope");
  inputs = BasicInputs();
  inputs.elevation = RasterInput{MakeGeoTiff(Filled(100.0))};
  InputErrorOf(inputs, "elevation");
}

TEST(LoadTerrain, RejectsRastersThatDoNotOverlap) {
  RasterSpec far_east = Filled(1.0);
  far_east.geotransform[0] += 100'000.0;  // 100 km east
  TerrainInputs inputs = BasicInputs();
  inputs.soil_class = RasterInput{MakeGeoTiff(far_east)};
  EXPECT_NE(InputErrorOf(inputs, "soil_class").find("does not overlap"), std::string::npos);

  RasterSpec europe = Filled(5.0);  // lon 10 E, lat 50 N: far from the UTM 17N grid
  europe.epsg = 4326;
  europe.geotransform = {10.0, 0.001, 0.0, 50.0, 0.0, -0.001};
  inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(europe)};
  EXPECT_NE(InputErrorOf(inputs, "slope").find("does not overlap"), std::string::npos);
}

TEST(LoadTerrain, RejectsLayersWithNoCellInCommon) {
  RasterSpec west = Filled(5.0);  // slope covers the western half only
  west.width = 10;
  RasterSpec east = Filled(1.0);  // soil covers the eastern half only
  east.width = 10;
  east.geotransform[0] += 100.0;
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(west)};
  inputs.soil_class = RasterInput{MakeGeoTiff(east)};
  InputErrorOf(inputs, "soil_class");
}

TEST(LoadTerrain, RejectsRotatedConeGrid) {
  RasterSpec rotated = Filled(500.0);
  rotated.geotransform = {500000.0, 10.0, 1.0, 4000000.0, 1.0, -10.0};
  TerrainInputs inputs = BasicInputs();
  inputs.cone_index.bytes = MakeGeoTiff(rotated);
  EXPECT_NE(InputErrorOf(inputs, "cone_index").find("rotated"), std::string::npos);
}

TEST(LoadTerrain, LimitsNameTheField) {
  TerrainInputs inputs = BasicInputs();  // 400-cell rasters
  GeoLimits limits;
  limits.max_input_cells = 399;
  LimitErrorOf(inputs, "cone_index", limits);

  limits = GeoLimits{};
  limits.max_output_cells = 399;
  LimitErrorOf(inputs, "cone_index", limits);

  RasterSpec big_slope = Filled(5.0);
  big_slope.width = big_slope.height = 30;  // 900 cells, larger than the cone grid
  inputs.slope = RasterInput{MakeGeoTiff(big_slope)};
  limits = GeoLimits{};
  limits.max_input_cells = 500;
  LimitErrorOf(inputs, "slope", limits);
}

TEST(LoadTerrain, WarpsSoilClassesFromGeographicCrs) {
  // Soil in EPSG:4326 with ~4.5 m cells: class 1 west of the grid's middle meridian, 2 east.
  const auto sw = fixtures::Transform(32617, 4326, 500000.0 - 50.0, 4000000.0 - 250.0);
  const auto ne = fixtures::Transform(32617, 4326, 500000.0 + 250.0, 4000000.0 + 50.0);
  const double split_lon = fixtures::Transform(32617, 4326, 500100.0, 3999900.0)[0];
  RasterSpec soil;
  soil.epsg = 4326;
  soil.type = GDT_Byte;
  const double cell_deg = 0.00005;
  soil.geotransform = {sw[0], cell_deg, 0.0, ne[1], 0.0, -cell_deg};
  soil.width = static_cast<int>((ne[0] - sw[0]) / cell_deg) + 1;
  soil.height = static_cast<int>((ne[1] - sw[1]) / cell_deg) + 1;
  fixtures::FillFromCentres(soil, [&](double lon, double) { return lon < split_lon ? 1 : 2; });
  TerrainInputs inputs = BasicInputs();
  inputs.soil_class = RasterInput{MakeGeoTiff(soil)};

  const TerrainLayers t = LoadTerrain(inputs, {});
  int checked = 0;
  for (int row = 0; row < 20; ++row) {
    for (int col = 0; col < 20; ++col) {
      const double lon = fixtures::Transform(32617, 4326, 500000.0 + 10.0 * col + 5.0,
                                             4000000.0 - 10.0 * row - 5.0)[0];
      const int code = t.soil_class[row * 20 + col];
      ASSERT_EQ(t.valid[row * 20 + col], 1) << row << "," << col;
      // Cells within a source plus a target cell of the boundary may go either way.
      if (std::abs(lon - split_lon) < 1.5e-4) continue;
      EXPECT_EQ(code, lon < split_lon ? 1 : 2) << row << "," << col;
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

TEST(LoadTerrain, WarpsSlopeFromAnotherUtmZone) {
  // The same area in UTM 18N (EPSG:32618), padded by 100 m.
  const auto nw = fixtures::Transform(32617, 32618, 499900.0, 4000100.0);
  const auto se = fixtures::Transform(32617, 32618, 500300.0, 3999700.0);
  RasterSpec slope = Filled(7.0);
  slope.epsg = 32618;
  const double west = std::min(nw[0], se[0]) - 100.0, north = std::max(nw[1], se[1]) + 100.0;
  slope.geotransform = {west, 10.0, 0.0, north, 0.0, -10.0};
  slope.width = static_cast<int>((std::max(nw[0], se[0]) + 100.0 - west) / 10.0);
  slope.height = static_cast<int>((north - std::min(nw[1], se[1]) + 100.0) / 10.0);
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(slope)};
  const TerrainLayers t = LoadTerrain(inputs, {});
  for (int i = 0; i < 400; ++i) {
    ASSERT_EQ(t.valid[i], 1) << i;
    EXPECT_NEAR(t.slope_percent[i], 7.0, 1e-4) << i;
  }
}

TEST(LoadTerrain, AveragingSkipsSourceNodata) {
  // 5 m source cells: every output cell averages 2 x 2 of them. One in four is nodata, and one
  // whole 2 x 2 block (output cell row 3, col 3) is nodata.
  RasterSpec slope;
  slope.width = slope.height = 40;
  slope.geotransform[1] = 5.0;
  slope.geotransform[5] = -5.0;
  slope.nodata = kNoData;
  slope.values.assign(1600, 4.0);
  for (int row = 0; row < 40; row += 2) {
    for (int col = 0; col < 40; col += 2) slope.values[row * 40 + col] = kNoData;
  }
  for (int row = 6; row < 8; ++row) {
    for (int col = 6; col < 8; ++col) slope.values[row * 40 + col] = kNoData;
  }
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(slope)};
  const TerrainLayers t = LoadTerrain(inputs, {});
  for (int i = 0; i < 400; ++i) {
    if (i == 3 * 20 + 3) {
      EXPECT_TRUE(std::isnan(t.slope_percent[i]));
      EXPECT_EQ(t.valid[i], 0);
    } else {
      EXPECT_NEAR(t.slope_percent[i], 4.0, 1e-5) << i;
    }
  }
}

TEST(LoadTerrain, RespectsInternalMask) {
  RasterSpec slope = Filled(6.0);
  slope.mask_left_half = true;
  TerrainInputs inputs = BasicInputs();
  inputs.slope = RasterInput{MakeGeoTiff(slope)};
  const TerrainLayers t = LoadTerrain(inputs, {});
  for (int row = 0; row < 20; ++row) {
    for (int col = 0; col < 20; ++col) {
      const float s = t.slope_percent[row * 20 + col];
      if (col < 10) {
        EXPECT_TRUE(std::isnan(s)) << row << "," << col;
      } else {
        EXPECT_NEAR(s, 6.0, 1e-5) << row << "," << col;
      }
    }
  }
}

TEST(LoadTerrain, CoarseElevationIsInterpolatedNotStepped) {
  // 30 m elevation cells over a 10 m grid: a northward 5 % ramp must stay a plane (bilinear); a
  // nearest-style copy would leave 3-cell terraces and slopes of 0 % and 7.5 %.
  RasterSpec elevation;
  elevation.width = elevation.height = 12;
  elevation.geotransform = {499940.0, 30.0, 0.0, 4000060.0, 0.0, -30.0};
  fixtures::FillFromCentres(elevation, [](double, double y) { return 0.05 * (y - 3999000.0); });
  TerrainInputs inputs = BasicInputs();
  inputs.slope.reset();
  inputs.elevation = RasterInput{MakeGeoTiff(elevation)};
  const TerrainLayers t = LoadTerrain(inputs, {});
  for (int i = 0; i < 400; ++i) EXPECT_NEAR(t.slope_percent[i], 5.0, 1e-3) << i;
}

TEST(LoadTerrain, ConcurrentCallsDoNotInterfere) {
  const TerrainInputs good = BasicInputs();
  TerrainInputs bad = BasicInputs();
  bad.slope = RasterInput{"junk"};
  std::vector<std::thread> threads;
  std::vector<int> failures(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 10; ++i) {
        try {
          const TerrainLayers layers = LoadTerrain(good, {});
          if (layers.valid.size() != 400 || std::abs(layers.slope_percent[17] - 5.0f) > 1e-5f) {
            ++failures[t];
          }
        } catch (...) {
          ++failures[t];
        }
        try {
          LoadTerrain(bad, {});
          ++failures[t];
        } catch (const InputError& e) {
          if (e.field() != "slope") ++failures[t];
        }
      }
    });
  }
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
}

}  // namespace
}  // namespace gonogo::geo
