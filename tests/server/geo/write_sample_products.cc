// Writes the map products of a synthetic 240 x 160 map (UTM 17N, 10 m cells) into a folder, with
// the STAC item, for the tests that open them in other software (qgis_products_test.py):
//
//   geo_write_sample_products OUT_DIR
//
// The map: GO ground, a SLOW-GO band along a slope, a NO-GO stream and pond, a no-data corner;
// speeds fall with the class (GO 15-40 km/h, SLOW-GO 3-12 km/h, NO-GO 0).
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "server/geo/products.h"
#include "tests/server/geo/test_rasters.h"

namespace {

using namespace gonogo::geo;

uint8_t ClassAt(int col, int row) {
  if (col > 200 && row > 120) return kClassNoData;  // outside the survey
  const double stream_row = 40.0 + 12.0 * std::sin(col / 18.0);
  if (std::abs(row - stream_row) < 3.0) return kClassNoGo;
  if (std::hypot(col - 60.0, row - 110.0) < 16.0) return kClassNoGo;  // pond
  if (col > 140 && col < 175) return kClassSlowGo;                    // slope
  if (std::abs(row - stream_row) < 9.0) return kClassSlowGo;          // wet banks
  return kClassGo;
}

float SpeedAt(int col, int row, uint8_t go_class) {
  switch (go_class) {
    case kClassGo:
      return 15.0f + 25.0f * static_cast<float>(row) / 159.0f;
    case kClassSlowGo:
      return 3.0f + 9.0f * static_cast<float>(col % 10) / 9.0f;
    case kClassNoGo:
      return 0.0f;
    default:
      return std::nanf("");
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: geo_write_sample_products OUT_DIR\n";
    return 2;
  }
  const std::string out_dir = argv[1];
  Grid grid;
  grid.width = 240;
  grid.height = 160;
  grid.geotransform = {500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0};
  grid.crs_wkt = fixtures::WktOfEpsg(32617);
  std::vector<uint8_t> go_class(static_cast<size_t>(grid.CellCount()));
  std::vector<float> speed_kmh(go_class.size());
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const size_t i = static_cast<size_t>(row) * grid.width + col;
      go_class[i] = ClassAt(col, row);
      speed_kmh[i] = SpeedAt(col, row, go_class[i]);
    }
  }
  const std::string title = "Synthetic valley - FED Alpha, empirical tier";
  const MapProducts products = WriteMapProducts(
      grid, go_class, speed_kmh, {title, {{"GONOGO_JOB_ID", "sample-job"}}}, out_dir);
  WriteStacItem(grid,
                {"sample-job", "2024-05-01T12:00:00Z", title,
                 R"({"gonogo:provenance": {"tier": "empirical", "vehicle_name": "FED Alpha"}})"},
                products.files, out_dir + "/item.json");
  for (const ProductFile& file : products.files) std::cout << file.name << "\n";
  std::cout << "item.json\n";
  return 0;
}
