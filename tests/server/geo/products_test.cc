// WriteMapProducts: the COGs carry the grid's CRS and geotransform exactly, their nodata, palette,
// legend and units, and pass GDAL's COG validator; the quicklook has the documented size and
// legend, its labels set in an antialiased font.
//
// To look at a quicklook: GONOGO_QUICKLOOK_SAMPLE=/tmp/quicklook.png
// build/tests/server/geo/geo_products_test --gtest_filter='*Quicklook*'
#include "server/geo/products.h"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>

#include "solvers/common/errors.h"
#include "tests/server/geo/test_rasters.h"

namespace gonogo::geo {
namespace {

using fixtures::OpenForCheck;
using fixtures::TempDir;

Grid UtmGrid(int width, int height) {
  Grid grid;
  grid.width = width;
  grid.height = height;
  grid.geotransform = {500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0};
  grid.crs_wkt = fixtures::WktOfEpsg(32617);
  return grid;
}

// Bands of classes across the grid (NO-GO, SLOW-GO, GO, no data) and speeds to match.
void FillPattern(const Grid& grid, std::vector<uint8_t>* go_class, std::vector<float>* speed_kmh) {
  const uint8_t classes[] = {kClassNoGo, kClassSlowGo, kClassGo, kClassNoData};
  go_class->resize(static_cast<size_t>(grid.CellCount()));
  speed_kmh->resize(go_class->size());
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const size_t i = static_cast<size_t>(row) * grid.width + col;
      const uint8_t c = classes[(4 * col) / grid.width];
      (*go_class)[i] = c;
      (*speed_kmh)[i] = c == kClassNoData ? std::nanf("") : 10.0f * c + 0.01f * row;
    }
  }
}

bool SameCrs(const GDALDataset& ds, const std::string& wkt) {
  OGRSpatialReference expected;
  expected.importFromWkt(wkt.c_str());
  // GDAL datasets map data axes in GIS order (x = longitude); compare the CRS definitions only.
  const char* const options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", nullptr};
  return ds.GetSpatialRef() != nullptr && ds.GetSpatialRef()->IsSame(&expected, options);
}

void ExpectValidCog(const std::string& path) {
  std::string output;
  const int status = fixtures::RunCommand(
      "/usr/bin/python3 -m osgeo_utils.samples.validate_cloud_optimized_geotiff '" + path + "'",
      &output);
  EXPECT_EQ(status, 0) << output;
}

std::set<std::string> FilesIn(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

TEST(WriteMapProducts, ClassCogHasPaletteLegendAndGrid) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(300, 200);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p =
      WriteMapProducts(grid, go_class, speed, {{"RUN_ID", "run-42"}}, dir.path() + "/out");
  EXPECT_EQ(p.gonogo_tif, dir.path() + "/out/gonogo.tif");
  EXPECT_EQ(FilesIn(dir.path() + "/out"),
            (std::set<std::string>{"gonogo.tif", "speed.tif", "quicklook.png"}));

  auto ds = OpenForCheck(p.gonogo_tif);
  ASSERT_NE(ds, nullptr);
  EXPECT_STREQ(ds->GetDriver()->GetDescription(), "GTiff");
  EXPECT_EQ(ds->GetRasterXSize(), 300);
  EXPECT_EQ(ds->GetRasterYSize(), 200);
  ASSERT_EQ(ds->GetRasterCount(), 1);
  std::array<double, 6> gt{};
  ds->GetGeoTransform(gt.data());
  EXPECT_EQ(gt, grid.geotransform);
  EXPECT_TRUE(SameCrs(*ds, grid.crs_wkt));
  EXPECT_STREQ(ds->GetMetadataItem("LEGEND"), "0=NO-GO;1=SLOW-GO;2=GO;255=no data");
  EXPECT_STREQ(ds->GetMetadataItem("RUN_ID"), "run-42");
  EXPECT_STREQ(ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE"), "COG");

  GDALRasterBand* band = ds->GetRasterBand(1);
  EXPECT_EQ(band->GetRasterDataType(), GDT_Byte);
  int has_nodata = 0;
  EXPECT_EQ(band->GetNoDataValue(&has_nodata), 255.0);
  EXPECT_TRUE(has_nodata);
  EXPECT_STREQ(band->GetDescription(), "go_class");
  EXPECT_EQ(band->GetColorInterpretation(), GCI_PaletteIndex);
  const GDALColorTable* palette = band->GetColorTable();
  ASSERT_NE(palette, nullptr);
  const GDALColorEntry* no_go = palette->GetColorEntry(0);
  const GDALColorEntry* slow_go = palette->GetColorEntry(1);
  const GDALColorEntry* go = palette->GetColorEntry(2);
  const GDALColorEntry* no_data = palette->GetColorEntry(255);
  EXPECT_GT(no_go->c1, 200);  // red
  EXPECT_LT(no_go->c2, 60);
  EXPECT_GT(slow_go->c1, 200);  // amber: red and green, little blue
  EXPECT_GT(slow_go->c2, 120);
  EXPECT_LT(slow_go->c3, 60);
  EXPECT_GT(go->c2, go->c1);  // green
  EXPECT_EQ(no_data->c4, 0);  // transparent
  EXPECT_EQ(no_go->c4, 255);

  std::vector<uint8_t> read_back(go_class.size());
  ASSERT_EQ(
      band->RasterIO(GF_Read, 0, 0, 300, 200, read_back.data(), 300, 200, GDT_Byte, 0, 0, nullptr),
      CE_None);
  EXPECT_EQ(read_back, go_class);
  ds.reset();
  ExpectValidCog(p.gonogo_tif);
}

TEST(WriteMapProducts, SpeedCogIsFloatKmhWithNanNodata) {
  TempDir dir("geo_products");
  // Larger than one 512-pixel COG block, so overviews are built too.
  const Grid grid = UtmGrid(1100, 700);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {{"VEHICLE", "truck"}}, dir.path());

  auto ds = OpenForCheck(p.speed_tif);
  ASSERT_NE(ds, nullptr);
  std::array<double, 6> gt{};
  ds->GetGeoTransform(gt.data());
  EXPECT_EQ(gt, grid.geotransform);
  EXPECT_TRUE(SameCrs(*ds, grid.crs_wkt));
  EXPECT_STREQ(ds->GetMetadataItem("UNITS"), "km/h");
  EXPECT_STREQ(ds->GetMetadataItem("VEHICLE"), "truck");
  GDALRasterBand* band = ds->GetRasterBand(1);
  EXPECT_EQ(band->GetRasterDataType(), GDT_Float32);
  EXPECT_STREQ(band->GetUnitType(), "km/h");
  EXPECT_STREQ(band->GetDescription(), "speed_kmh");
  int has_nodata = 0;
  EXPECT_TRUE(std::isnan(band->GetNoDataValue(&has_nodata)));
  EXPECT_TRUE(has_nodata);
  EXPECT_GT(band->GetOverviewCount(), 0);
  std::vector<float> read_back(speed.size());
  ASSERT_EQ(band->RasterIO(GF_Read, 0, 0, 1100, 700, read_back.data(), 1100, 700, GDT_Float32, 0, 0,
                           nullptr),
            CE_None);
  for (size_t i = 0; i < speed.size(); ++i) {
    if (std::isnan(speed[i])) {
      ASSERT_TRUE(std::isnan(read_back[i])) << i;
    } else {
      ASSERT_EQ(read_back[i], speed[i]) << i;
    }
  }
  ds.reset();
  ExpectValidCog(p.speed_tif);
  ExpectValidCog(p.gonogo_tif);
  auto classes = OpenForCheck(p.gonogo_tif);
  EXPECT_GT(classes->GetRasterBand(1)->GetOverviewCount(), 0);
}

TEST(WriteMapProducts, GeographicGridKeepsItsCrs) {
  TempDir dir("geo_products");
  Grid grid;
  grid.width = 50;
  grid.height = 40;
  grid.geotransform = {-81.01, 1e-4, 0.0, 36.11, 0.0, -1e-4};
  grid.crs_wkt = fixtures::WktOfEpsg(4326);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  for (const std::string& path : {p.gonogo_tif, p.speed_tif}) {
    auto ds = OpenForCheck(path);
    ASSERT_NE(ds, nullptr);
    std::array<double, 6> gt{};
    ds->GetGeoTransform(gt.data());
    EXPECT_EQ(gt, grid.geotransform) << path;
    EXPECT_TRUE(SameCrs(*ds, grid.crs_wkt)) << path;
  }
}

// Pixel (x, y) of an RGBA PNG.
std::array<int, 4> PixelAt(GDALDataset& png, int x, int y) {
  std::array<int, 4> rgba{};
  for (int b = 0; b < 4; ++b) {
    uint8_t v = 0;
    EXPECT_EQ(
        png.GetRasterBand(b + 1)->RasterIO(GF_Read, x, y, 1, 1, &v, 1, 1, GDT_Byte, 0, 0, nullptr),
        CE_None);
    rgba[b] = v;
  }
  return rgba;
}

TEST(WriteMapProducts, QuicklookHasDocumentedSizeColoursAndLegend) {
  // Legend panel (quicklook.cc): 122 px wide, 8 + 4 * 24 = 104 px tall; rows of a 16 px swatch at
  // x 8 and a label from x 32, the first at y 8.
  struct Case {
    int width, height, png_width, png_height;
  };
  for (const Case& c : {Case{300, 200, 300 + 122, 200},     // as is
                        Case{10, 5, 250 + 122, 125},        // enlarged x25
                        Case{2048, 1024, 1024 + 122, 512},  // shrunk to 1024 px
                        Case{600, 20, 600 + 122, 104}}) {   // legend taller than the map
    TempDir dir("geo_quicklook");
    const Grid grid = UtmGrid(c.width, c.height);
    std::vector<uint8_t> go_class;
    std::vector<float> speed;
    FillPattern(grid, &go_class, &speed);
    const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
    const char* keep = std::getenv("GONOGO_QUICKLOOK_SAMPLE");
    if (keep != nullptr && c.width == 300) {
      std::filesystem::copy_file(p.quicklook_png, keep,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    auto png = OpenForCheck(p.quicklook_png);
    ASSERT_NE(png, nullptr);
    EXPECT_STREQ(png->GetDriver()->GetDescription(), "PNG");
    EXPECT_EQ(png->GetRasterXSize(), c.png_width) << c.width << "x" << c.height;
    EXPECT_EQ(png->GetRasterYSize(), c.png_height) << c.width << "x" << c.height;
    ASSERT_EQ(png->GetRasterCount(), 4);
    const int map_w = c.png_width - 122;
    // Left quarter NO-GO (red), right quarter no data (transparent).
    const auto red = PixelAt(*png, 0, 0);
    EXPECT_GT(red[0], 200);
    EXPECT_LT(red[1], 60);
    EXPECT_EQ(red[3], 255);
    EXPECT_EQ(PixelAt(*png, map_w - 1, 0)[3], 0);
    // Swatches in the class colours: GO green, SLOW-GO amber, NO-GO red.
    EXPECT_EQ(PixelAt(*png, map_w + 16, 16), (std::array<int, 4>{26, 150, 65, 255}));
    EXPECT_EQ(PixelAt(*png, map_w + 16, 16 + 24), (std::array<int, 4>{255, 176, 0, 255}));
    EXPECT_EQ(PixelAt(*png, map_w + 16, 16 + 48), (std::array<int, 4>{215, 25, 28, 255}));
    // Each label is text: dark ink (grey, opaque) right of its swatch, with antialiased grey edges
    // that a bitmap font would not have, spread over at least 9 rows (14 px type).
    for (int row = 0; row < 4; ++row) {
      int dark = 0, edge = 0, top = 1 << 30, bottom = -1;
      for (int y = 8 + 24 * row - 2; y < 8 + 24 * row + 18; ++y) {
        for (int x = map_w + 30; x < map_w + 122; ++x) {
          const auto v = PixelAt(*png, x, y);
          if (v[3] != 255 || v[0] != v[1] || v[1] != v[2]) continue;
          if (v[0] < 96) {
            ++dark;
            top = std::min(top, y);
            bottom = std::max(bottom, y);
          } else if (v[0] < 224) {
            ++edge;
          }
        }
      }
      EXPECT_GT(dark, 20) << "legend row " << row;
      EXPECT_GT(edge, 5) << "legend row " << row;
      EXPECT_GE(bottom - top + 1, 9) << "legend row " << row;
    }
  }
}

TEST(WriteMapProducts, ShrunkQuicklookKeepsIsolatedNoGoCell) {
  TempDir dir("geo_quicklook");
  const Grid grid = UtmGrid(2050, 2050);
  std::vector<uint8_t> go_class(2050 * 2050, kClassGo);
  go_class[1025 * 2050 + 1026] = kClassNoGo;
  const std::vector<float> speed(go_class.size(), 30.0f);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  auto png = OpenForCheck(p.quicklook_png);
  ASSERT_NE(png, nullptr);
  EXPECT_EQ(png->GetRasterXSize(), 1024 + 122);
  // Cell (row 1025, col 1026) lands in map pixel x = 1026 * 1024 / 2050, y = 1025 * 1024 / 2050,
  // both 512 after truncation; a nearest-neighbour shrink would drop it.
  const auto pixel = PixelAt(*png, 512, 512);
  EXPECT_GT(pixel[0], 200);
  EXPECT_LT(pixel[1], 60);
}

TEST(WriteMapProducts, RejectsInconsistentArguments) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(10, 10);
  std::vector<uint8_t> go_class(100, kClassGo);
  std::vector<float> speed(100, 20.0f);
  auto field_of = [&](const Grid& g, const std::vector<uint8_t>& c, const std::vector<float>& s,
                      const std::map<std::string, std::string>& m) -> std::string {
    try {
      WriteMapProducts(g, c, s, m, dir.path());
    } catch (const InputError& e) {
      return e.field();
    }
    return "(no error)";
  };
  EXPECT_EQ(field_of(grid, std::vector<uint8_t>(99, kClassGo), speed, {}), "go_class");
  std::vector<uint8_t> bad_class = go_class;
  bad_class[55] = 7;
  EXPECT_EQ(field_of(grid, bad_class, speed, {}), "go_class");
  EXPECT_EQ(field_of(grid, go_class, std::vector<float>(100, -1.0f), {}), "speed_kmh");
  EXPECT_EQ(field_of(grid, go_class, speed, {{"BAD=KEY", "x"}}), "metadata");
  Grid no_crs = grid;
  no_crs.crs_wkt.clear();
  EXPECT_EQ(field_of(no_crs, go_class, speed, {}), "grid");
  EXPECT_TRUE(FilesIn(dir.path()).empty());
}

}  // namespace
}  // namespace gonogo::geo
