// WriteMapProducts: the COGs carry the grid's CRS and geotransform exactly, their nodata, palette,
// legend and units, and pass GDAL's COG validator; the class names reach GDAL through the sidecar;
// the QGIS styles name the classes and the speed ramp; GDAL reads the KMZ back in WGS 84 with the
// class colours and finds its legend overlay; the STAC item has the WGS 84 bbox and the native
// grid; the quicklook has the documented layout, legend text, north arrow and scale bar.
// (qgis_products_test.py opens the same products in QGIS and validates the STAC item's schema.)
//
// To look at a quicklook: GONOGO_QUICKLOOK_SAMPLE=/tmp/quicklook.png
// build/tests/server/geo/geo_products_test --gtest_filter='*Quicklook*'
#include "server/geo/products.h"

#include <gdal_rat.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "server/geo/qgis_style.h"
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
      WriteMapProducts(grid, go_class, speed, {"", {{"RUN_ID", "run-42"}}}, dir.path() + "/out");
  EXPECT_EQ(p.gonogo_tif, dir.path() + "/out/gonogo.tif");
  const std::set<std::string> expected_files = {"gonogo.tif",   "gonogo.tif.aux.xml", "gonogo.qml",
                                                "speed.tif",    "speed.qml",          "gonogo.kmz",
                                                "quicklook.png"};
  EXPECT_EQ(FilesIn(dir.path() + "/out"), expected_files);
  std::set<std::string> listed;
  for (const ProductFile& file : p.files) listed.insert(file.name);
  EXPECT_EQ(listed, expected_files);

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
  const MapProducts p =
      WriteMapProducts(grid, go_class, speed, {"", {{"VEHICLE", "truck"}}}, dir.path());

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

// Pixel (x, y) of an RGBA PNG (of an RGB one: alpha 255).
std::array<int, 4> PixelAt(GDALDataset& png, int x, int y) {
  std::array<int, 4> rgba{0, 0, 0, 255};
  for (int b = 0; b < std::min(4, png.GetRasterCount()); ++b) {
    uint8_t v = 0;
    EXPECT_EQ(
        png.GetRasterBand(b + 1)->RasterIO(GF_Read, x, y, 1, 1, &v, 1, 1, GDT_Byte, 0, 0, nullptr),
        CE_None);
    rgba[b] = v;
  }
  return rgba;
}

// Counts of text-like pixels in a box: opaque greys darker than 96 (ink) and between 96 and 224
// (antialiased edges), and the rows the ink spans.
struct Ink {
  int dark = 0, edge = 0, rows = 0;
};
Ink InkIn(GDALDataset& png, int x0, int y0, int w, int h) {
  Ink ink;
  int top = 1 << 30, bottom = -1;
  for (int y = y0; y < y0 + h; ++y) {
    for (int x = x0; x < x0 + w; ++x) {
      const auto v = PixelAt(png, x, y);
      if (v[3] != 255 || v[0] != v[1] || v[1] != v[2]) continue;
      if (v[0] < 96) {
        ++ink.dark;
        top = std::min(top, y);
        bottom = std::max(bottom, y);
      } else if (v[0] < 224) {
        ++ink.edge;
      }
    }
  }
  ink.rows = bottom >= top ? bottom - top + 1 : 0;
  return ink;
}

TEST(WriteMapProducts, QuicklookHasDocumentedLayoutColoursLegendNorthArrowAndScaleBar) {
  // Layout (quicklook.h): 12 px margins, a 40 px title band, the map, a 168 px panel column with
  // the legend (24 px rows), a 64 px north arrow box and a 44 px scale bar box below it.
  struct Case {
    int width, height, map_width, map_height, png_width, png_height;
  };
  const int panel_bottom = 40 + 4 * 24 + 12 + 64 + 44;                                 // 256
  for (const Case& c : {Case{300, 200, 900, 600, 12 + 900 + 12 + 168, 40 + 600 + 12},  // x3
                        Case{10, 5, 1020, 510, 12 + 1020 + 12 + 168, 40 + 510 + 12},   // x102
                        Case{2048, 1024, 1024, 512, 1216, 40 + 512 + 12},   // shrunk to 1024 px
                        Case{600, 20, 600, 20, 792, panel_bottom + 12}}) {  // panel taller
    TempDir dir("geo_quicklook");
    const Grid grid = UtmGrid(c.width, c.height);
    std::vector<uint8_t> go_class;
    std::vector<float> speed;
    FillPattern(grid, &go_class, &speed);
    const MapProducts p = WriteMapProducts(
        grid, go_class, speed, {"Test map - FED Alpha, empirical tier", {}}, dir.path());
    const char* keep = std::getenv("GONOGO_QUICKLOOK_SAMPLE");
    if (keep != nullptr && c.width == 300) {
      std::filesystem::copy_file(p.quicklook_png, keep,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    const std::string name = std::to_string(c.width) + "x" + std::to_string(c.height);
    auto png = OpenForCheck(p.quicklook_png);
    ASSERT_NE(png, nullptr);
    EXPECT_STREQ(png->GetDriver()->GetDescription(), "PNG");
    EXPECT_EQ(png->GetRasterXSize(), c.png_width) << name;
    EXPECT_EQ(png->GetRasterYSize(), c.png_height) << name;
    ASSERT_EQ(png->GetRasterCount(), 4);
    // Map at (12, 40): left quarter NO-GO red, right quarter no data in opaque light grey; white
    // page around it.
    EXPECT_EQ(PixelAt(*png, 12, 40), (std::array<int, 4>{215, 25, 28, 255})) << name;
    EXPECT_EQ(PixelAt(*png, 12 + c.map_width - 1, 40 + c.map_height - 1),
              (std::array<int, 4>{224, 224, 224, 255}))
        << name;
    EXPECT_EQ(PixelAt(*png, 5, 40), (std::array<int, 4>{255, 255, 255, 255})) << name;
    // Swatches in the class colours: GO green, SLOW-GO amber, NO-GO red, no data grey.
    const int panel_x = 12 + c.map_width + 12;
    EXPECT_EQ(PixelAt(*png, panel_x + 8, 40 + 8), (std::array<int, 4>{26, 150, 65, 255})) << name;
    EXPECT_EQ(PixelAt(*png, panel_x + 8, 40 + 8 + 24), (std::array<int, 4>{255, 176, 0, 255}));
    EXPECT_EQ(PixelAt(*png, panel_x + 8, 40 + 8 + 48), (std::array<int, 4>{215, 25, 28, 255}));
    EXPECT_EQ(PixelAt(*png, panel_x + 8, 40 + 8 + 72), (std::array<int, 4>{224, 224, 224, 255}));
    // Each label is text: dark ink right of its swatch with antialiased grey edges that a bitmap
    // font would not have, over at least 9 rows (14 px type).
    for (int row = 0; row < 4; ++row) {
      const Ink label = InkIn(*png, panel_x + 22, 40 + 24 * row - 2, 140, 20);
      EXPECT_GT(label.dark, 20) << name << " legend row " << row;
      EXPECT_GT(label.edge, 5) << name << " legend row " << row;
      EXPECT_GE(label.rows, 9) << name << " legend row " << row;
    }
    // Title: a line of bold text in the band above the map, capitals 12-14 px tall.
    const Ink title = InkIn(*png, 0, 0, c.png_width, 40);
    EXPECT_GT(title.dark, 300) << name;
    EXPECT_GE(title.rows, 11) << name;
    EXPECT_LE(title.rows, 20) << name;
    // North arrow: a solid black left half under its tip, in the column's top-left.
    const int arrow_y = 40 + 4 * 24 + 12;
    EXPECT_EQ(PixelAt(*png, panel_x + 9, arrow_y + 28), (std::array<int, 4>{0, 0, 0, 255})) << name;
    EXPECT_GT(InkIn(*png, panel_x, arrow_y, 40, 64).dark, 200) << name;
  }
}

TEST(WriteMapProducts, QuicklookScaleBarHasARoundLengthInGroundMetres) {
  // 300 x 200 cells of 10 m drawn x3: 3.33 m per pixel; at most 144 px = 480 m, so the bar is
  // 200 m = 60 px long, from the panel's left edge, 8 px below the top of its box.
  TempDir dir("geo_quicklook");
  const Grid grid = UtmGrid(300, 200);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  auto png = OpenForCheck(p.quicklook_png);
  ASSERT_NE(png, nullptr);
  // Layout: panel column at x = 12 + 900 + 12, scale bar box at y = 40 + 4 * 24 + 12 + 64.
  const int panel_x = 12 + 900 + 12;
  const int bar_y = 40 + 4 * 24 + 12 + 64 + 8;
  const std::array<int, 4> black{0, 0, 0, 255}, white{255, 255, 255, 255};
  EXPECT_EQ(PixelAt(*png, panel_x, bar_y), black);       // left end
  EXPECT_EQ(PixelAt(*png, panel_x + 59, bar_y), black);  // right end
  EXPECT_EQ(PixelAt(*png, panel_x + 60, bar_y), white);  // just past it
  // Alternate segments: the second quarter is white inside its outline, the first black.
  EXPECT_EQ(PixelAt(*png, panel_x + 7, bar_y + 4), black);
  EXPECT_EQ(PixelAt(*png, panel_x + 22, bar_y + 4), white);
  // Labels "0" and "200 m" under the bar's ends.
  EXPECT_GT(InkIn(*png, panel_x, bar_y + 10, 10, 20).dark, 5);
  EXPECT_GT(InkIn(*png, panel_x + 20, bar_y + 10, 42, 20).dark, 30);

  // A geographic grid: 0.001 degree cells at 36 N are 90.2 m wide; 200 cells x5 = 18 m per px;
  // 144 px = 2.6 km, so the bar is 2 km = 111 px.
  Grid geographic;
  geographic.width = 200;
  geographic.height = 100;
  geographic.geotransform = {-81.1, 0.001, 0.0, 36.05, 0.0, -0.001};
  geographic.crs_wkt = fixtures::WktOfEpsg(4326);
  FillPattern(geographic, &go_class, &speed);
  const MapProducts q = WriteMapProducts(geographic, go_class, speed, {}, dir.path() + "/geo");
  auto geo_png = OpenForCheck(q.quicklook_png);
  ASSERT_EQ(geo_png->GetRasterXSize(), 12 + 1000 + 12 + 168);
  const int geo_panel_x = 12 + 1000 + 12;
  const double metres_per_px =
      0.001 * M_PI / 180.0 * 6378137.0 * std::cos(36.0 * M_PI / 180.0) * 200 / 1000.0;
  const int expected_px = static_cast<int>(2000.0 / metres_per_px + 0.5);
  EXPECT_NEAR(expected_px, 111, 1);
  EXPECT_EQ(PixelAt(*geo_png, geo_panel_x + expected_px - 2, bar_y), black);
  EXPECT_EQ(PixelAt(*geo_png, geo_panel_x + expected_px + 2, bar_y), white);
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
  EXPECT_EQ(png->GetRasterXSize(), 12 + 1024 + 12 + 168);
  // Cell (row 1025, col 1026) lands in map pixel x = 1026 * 1024 / 2050, y = 1025 * 1024 / 2050,
  // both 512 after truncation, drawn at (12 + 512, 40 + 512); a nearest-neighbour shrink would
  // drop it.
  const auto pixel = PixelAt(*png, 12 + 512, 40 + 512);
  EXPECT_GT(pixel[0], 200);
  EXPECT_LT(pixel[1], 60);
}

TEST(WriteMapProducts, ClassNamesLiveInTheSidecarThatShipsWithTheCog) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(40, 30);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  EXPECT_EQ(p.gonogo_aux_xml, p.gonogo_tif + ".aux.xml");
  {
    auto ds = OpenForCheck(p.gonogo_tif);
    ASSERT_NE(ds, nullptr);
    GDALRasterBand* band = ds->GetRasterBand(1);
    const GDALRasterAttributeTable* table = band->GetDefaultRAT();
    ASSERT_NE(table, nullptr);
    ASSERT_EQ(table->GetRowCount(), 3);
    const int name_column = table->GetColOfUsage(GFU_Name);
    const int value_column = table->GetColOfUsage(GFU_MinMax);
    const int red_column = table->GetColOfUsage(GFU_Red);
    ASSERT_GE(name_column, 0);
    ASSERT_GE(value_column, 0);
    ASSERT_GE(red_column, 0);
    const char* names[] = {"NO-GO", "SLOW-GO", "GO"};
    for (int row = 0; row < 3; ++row) {
      EXPECT_EQ(table->GetValueAsInt(row, value_column), row);
      EXPECT_STREQ(table->GetValueAsString(row, name_column), names[row]);
      EXPECT_EQ(table->GetValueAsInt(row, red_column),
                band->GetColorTable()->GetColorEntry(row)->c1);
    }
    char** categories = band->GetCategoryNames();
    ASSERT_NE(categories, nullptr);
    ASSERT_EQ(CSLCount(categories), 3);
    EXPECT_STREQ(categories[0], "NO-GO");
    EXPECT_STREQ(categories[1], "SLOW-GO");
    EXPECT_STREQ(categories[2], "GO");
  }
  // The TIFF itself cannot hold them: copied alone, the COG has neither.
  const std::string alone = dir.path() + "/alone.tif";
  std::filesystem::copy_file(p.gonogo_tif, alone);
  auto ds = OpenForCheck(alone);
  ASSERT_NE(ds, nullptr);
  EXPECT_EQ(ds->GetRasterBand(1)->GetDefaultRAT(), nullptr);
  EXPECT_EQ(ds->GetRasterBand(1)->GetCategoryNames(), nullptr);
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(WriteMapProducts, QgisStylesNameTheClassesAndTheSpeedRamp) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(40, 30);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);  // speeds up to 20.29 km/h: ramp to 25 km/h
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  const std::string classes = ReadText(p.gonogo_qml);
  EXPECT_NE(classes.find(R"(type="paletted")"), std::string::npos);
  for (const char* entry : {R"(value="2" color="#1a9641" alpha="255" label="GO")",
                            R"(value="1" color="#ffb000" alpha="255" label="SLOW-GO")",
                            R"(value="0" color="#d7191c" alpha="255" label="NO-GO")"}) {
    EXPECT_NE(classes.find(entry), std::string::npos) << entry;
  }
  const std::string speeds = ReadText(p.speed_qml);
  EXPECT_NE(speeds.find(R"(type="singlebandpseudocolor")"), std::string::npos);
  EXPECT_NE(speeds.find(R"(maximumValue="25")"), std::string::npos);
  EXPECT_NE(speeds.find(R"(label="0 km/h")"), std::string::npos);
  EXPECT_NE(speeds.find(R"(label="12.5 km/h")"), std::string::npos);
  EXPECT_NE(speeds.find(R"(label="25 km/h")"), std::string::npos);

  EXPECT_EQ(internal::SpeedRampMaxKmh(0.0), 5.0);
  EXPECT_EQ(internal::SpeedRampMaxKmh(std::nan("")), 5.0);
  EXPECT_EQ(internal::SpeedRampMaxKmh(5.0), 5.0);
  EXPECT_EQ(internal::SpeedRampMaxKmh(5.01), 10.0);
  EXPECT_EQ(internal::SpeedRampMaxKmh(38.2), 40.0);
}

TEST(WriteMapProducts, GdalReadsTheKmzBackInWgs84WithClassColoursAndALegendOverlay) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(300, 200);  // 3 km x 2 km at 36.1 N 81 W
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p =
      WriteMapProducts(grid, go_class, speed, {"Ridge & valley - FED Alpha", {}}, dir.path());
  EXPECT_EQ(p.kmz, dir.path() + "/gonogo.kmz");
  auto kmz = OpenForCheck(p.kmz);
  ASSERT_NE(kmz, nullptr);
  EXPECT_STREQ(kmz->GetDriver()->GetDescription(), "KMLSUPEROVERLAY");
  ASSERT_EQ(kmz->GetRasterCount(), 4);
  std::array<double, 6> gt{};
  ASSERT_EQ(kmz->GetGeoTransform(gt.data()), CE_None);
  // Its extent is the grid's, in degrees (corners transformed with PROJ, a 10 m cell is about
  // 0.0001 degree).
  const auto north_west = fixtures::Transform(32617, 4326, 500000.0, 4000000.0);
  const auto south_east = fixtures::Transform(32617, 4326, 503000.0, 3998000.0);
  EXPECT_NEAR(gt[0], north_west[0], 2e-4);
  EXPECT_NEAR(gt[3], north_west[1], 2e-4);
  EXPECT_NEAR(gt[0] + gt[1] * kmz->GetRasterXSize(), south_east[0], 2e-4);
  EXPECT_NEAR(gt[3] + gt[5] * kmz->GetRasterYSize(), south_east[1], 2e-4);
  // Colours, read through GDAL's KML reader: the left quarter NO-GO red, the right no data clear.
  std::array<uint8_t, 4> left{}, right{};
  const int middle_row = kmz->GetRasterYSize() / 2;
  for (int b = 0; b < 4; ++b) {
    ASSERT_EQ(kmz->GetRasterBand(b + 1)->RasterIO(GF_Read, 5, middle_row, 1, 1, &left[b], 1, 1,
                                                  GDT_Byte, 0, 0, nullptr),
              CE_None);
    ASSERT_EQ(kmz->GetRasterBand(b + 1)->RasterIO(GF_Read, kmz->GetRasterXSize() - 5, middle_row, 1,
                                                  1, &right[b], 1, 1, GDT_Byte, 0, 0, nullptr),
              CE_None);
  }
  EXPECT_EQ(left, (std::array<uint8_t, 4>{215, 25, 28, 255}));
  EXPECT_EQ(right[3], 0);
  kmz.reset();

  // doc.kml pins legend.png to the view; the legend is a PNG with the title and the rows.
  const std::string zip = "/vsizip/" + p.kmz;
  VSILFILE* doc = VSIFOpenL((zip + "/doc.kml").c_str(), "rb");
  ASSERT_NE(doc, nullptr);
  std::string kml(1 << 16, '\0');
  kml.resize(VSIFReadL(kml.data(), 1, kml.size(), doc));
  VSIFCloseL(doc);
  EXPECT_NE(kml.find("<ScreenOverlay>"), std::string::npos) << kml;
  EXPECT_NE(kml.find("<href>legend.png</href>"), std::string::npos) << kml;
  EXPECT_NE(kml.find("Ridge &amp; valley - FED Alpha"), std::string::npos) << kml;
  auto legend = OpenForCheck(zip + "/legend.png");
  ASSERT_NE(legend, nullptr);
  EXPECT_EQ(legend->GetRasterXSize(), 220);
  EXPECT_EQ(legend->GetRasterYSize(), 34 + 4 * 24 + 6);
  EXPECT_GT(InkIn(*legend, 0, 0, 220, 34).dark, 200);  // the title
}

nlohmann::json ReadJson(const std::string& path) { return nlohmann::json::parse(ReadText(path)); }

TEST(WriteStacItem, DescribesTheAssetsWithWgs84BboxAndTheNativeGrid) {
  TempDir dir("geo_stac");
  const Grid grid = UtmGrid(300, 200);
  std::vector<uint8_t> go_class;
  std::vector<float> speed;
  FillPattern(grid, &go_class, &speed);
  const MapProducts p = WriteMapProducts(grid, go_class, speed, {}, dir.path());
  const std::string path = dir.path() + "/item.json";
  WriteStacItem(grid,
                {"job-7", "2024-05-01T12:00:00Z", "Test map", R"({"gonogo:tier": "empirical"})"},
                p.files, path);
  const nlohmann::json item = ReadJson(path);
  EXPECT_EQ(item["type"], "Feature");
  EXPECT_EQ(item["stac_version"], "1.0.0");
  EXPECT_EQ(item["id"], "job-7");
  EXPECT_EQ(item["properties"]["datetime"], "2024-05-01T12:00:00Z");
  EXPECT_EQ(item["properties"]["title"], "Test map");
  EXPECT_EQ(item["properties"]["gonogo:tier"], "empirical");
  EXPECT_EQ(item["properties"]["proj:epsg"], 32617);
  EXPECT_EQ(item["properties"]["proj:shape"], (nlohmann::json{200, 300}));
  EXPECT_EQ(item["properties"]["proj:transform"],
            (nlohmann::json{10.0, 0.0, 500000.0, 0.0, -10.0, 4000000.0}));
  EXPECT_EQ(item["properties"]["proj:bbox"],
            (nlohmann::json{500000.0, 3998000.0, 503000.0, 4000000.0}));
  // bbox: west, south, east, north of the grid's corners in WGS 84 (UTM edges curve only a little
  // over 3 km: the densified bbox is within 1e-6 degree of the corners).
  const auto sw = fixtures::Transform(32617, 4326, 500000.0, 3998000.0);
  const auto se = fixtures::Transform(32617, 4326, 503000.0, 3998000.0);
  const auto nw = fixtures::Transform(32617, 4326, 500000.0, 4000000.0);
  const auto ne = fixtures::Transform(32617, 4326, 503000.0, 4000000.0);
  const auto& bbox = item["bbox"];
  ASSERT_EQ(bbox.size(), 4u);
  EXPECT_NEAR(bbox[0].get<double>(), std::min(sw[0], nw[0]), 1e-6);
  EXPECT_NEAR(bbox[1].get<double>(), std::min(sw[1], se[1]), 1e-6);
  EXPECT_NEAR(bbox[2].get<double>(), std::max(se[0], ne[0]), 1e-6);
  EXPECT_NEAR(bbox[3].get<double>(), std::max(nw[1], ne[1]), 1e-6);
  // The footprint: a closed ring through the corners, every point inside the bbox.
  const auto& ring = item["geometry"]["coordinates"][0];
  EXPECT_EQ(item["geometry"]["type"], "Polygon");
  EXPECT_EQ(ring.front(), ring.back());
  EXPECT_NEAR(ring[0][0].get<double>(), sw[0], 1e-9);
  EXPECT_NEAR(ring[0][1].get<double>(), sw[1], 1e-9);
  for (const auto& point : ring) {
    EXPECT_GE(point[0].get<double>(), bbox[0].get<double>() - 1e-9);
    EXPECT_LE(point[1].get<double>(), bbox[3].get<double>() + 1e-9);
  }
  // Every product is an asset with its media type and roles.
  ASSERT_EQ(item["assets"].size(), p.files.size());
  EXPECT_EQ(item["assets"]["gonogo.tif"]["href"], "./gonogo.tif");
  EXPECT_EQ(item["assets"]["gonogo.tif"]["type"],
            "image/tiff; application=geotiff; profile=cloud-optimized");
  EXPECT_EQ(item["assets"]["gonogo.tif"]["roles"], (nlohmann::json{"data"}));
  EXPECT_EQ(item["assets"]["gonogo.kmz"]["type"], "application/vnd.google-earth.kmz");
  EXPECT_EQ(item["assets"]["quicklook.png"]["roles"], (nlohmann::json{"overview"}));
}

TEST(WriteStacItem, RejectsAnItemWithoutIdOrTimeOrWithPropertiesThatAreNotAnObject) {
  TempDir dir("geo_stac");
  const Grid grid = UtmGrid(10, 10);
  auto field_of = [&](const StacItemInfo& info) -> std::string {
    try {
      WriteStacItem(grid, info, {}, dir.path() + "/item.json");
    } catch (const InputError& e) {
      return e.field();
    }
    return "(no error)";
  };
  EXPECT_EQ(field_of({"", "2024-05-01T12:00:00Z", "", ""}), "stac");
  EXPECT_EQ(field_of({"job", "", "", ""}), "stac");
  EXPECT_EQ(field_of({"job", "2024-05-01T12:00:00Z", "", "[1, 2]"}), "stac");
  EXPECT_EQ(field_of({"job", "2024-05-01T12:00:00Z", "", "{not json"}), "stac");
  EXPECT_TRUE(FilesIn(dir.path()).empty());
  EXPECT_EQ(field_of({"job", "2024-05-01T12:00:00Z", "", ""}), "(no error)");
}

TEST(WriteMapProducts, RejectsInconsistentArguments) {
  TempDir dir("geo_products");
  const Grid grid = UtmGrid(10, 10);
  std::vector<uint8_t> go_class(100, kClassGo);
  std::vector<float> speed(100, 20.0f);
  auto field_of = [&](const Grid& g, const std::vector<uint8_t>& c, const std::vector<float>& s,
                      const std::map<std::string, std::string>& m) -> std::string {
    try {
      WriteMapProducts(g, c, s, {"", m}, dir.path());
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
