// Prints how long LoadTerrain and WriteMapProducts take on N x N grids (default 1000).
//   geo_bench [N ...]
// Inputs: cone index and elevation on the output grid (UTM 17N, 10 m cells) and a soil-class
// raster in EPSG:4326, so both the same-grid path and a reprojecting warp are timed.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "server/geo/products.h"
#include "server/geo/terrain.h"
#include "tests/server/geo/test_rasters.h"

namespace {

using gonogo::geo::fixtures::RasterSpec;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

gonogo::geo::TerrainInputs MakeInputs(int n) {
  RasterSpec cone;
  cone.width = cone.height = n;
  cone.nodata = -9999.0;
  gonogo::geo::fixtures::FillFromCentres(cone, [](double x, double y) {
    return 300.0 + 200.0 * std::sin(x / 300.0) * std::cos(y / 400.0);
  });
  RasterSpec elevation = cone;
  gonogo::geo::fixtures::FillFromCentres(elevation, [](double x, double y) {
    return 400.0 + 30.0 * std::sin(x / 250.0) + 20.0 * std::cos(y / 350.0);
  });
  const double extent_m = 10.0 * n;
  const auto nw = gonogo::geo::fixtures::Transform(32617, 4326, 499900.0, 4000100.0);
  const auto se =
      gonogo::geo::fixtures::Transform(32617, 4326, 500100.0 + extent_m, 3999900.0 - extent_m);
  RasterSpec soil;
  soil.epsg = 4326;
  soil.type = GDT_Byte;
  soil.width = soil.height = n;
  soil.geotransform = {nw[0], (se[0] - nw[0]) / n, 0.0, nw[1], 0.0, (se[1] - nw[1]) / n};
  gonogo::geo::fixtures::FillFromCentres(soil, [](double lon, double lat) {
    return 1 + (static_cast<int>(lon * 2e3 + lat * 3e3) & 1);
  });

  gonogo::geo::TerrainInputs inputs;
  inputs.cone_index.bytes = gonogo::geo::fixtures::MakeGeoTiff(cone);
  inputs.elevation = gonogo::geo::RasterInput{gonogo::geo::fixtures::MakeGeoTiff(elevation)};
  inputs.soil_class = gonogo::geo::RasterInput{gonogo::geo::fixtures::MakeGeoTiff(soil)};
  return inputs;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes;
  CLI::App app(
      "Prints how long LoadTerrain and WriteMapProducts take on N x N grids: cone index and "
      "elevation on the output grid (UTM 17N, 10 m cells) and a soil-class raster in EPSG:4326, so "
      "both the same-grid path and a reprojecting warp are timed.",
      "geo_bench");
  app.add_option("N", sizes, "grid sizes, cells per side (default 1000)")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()).description(">= 1"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (sizes.empty()) sizes.push_back(1000);
  gonogo::geo::fixtures::TempDir dir("geo_bench");
  std::printf("%8s %12s %12s %14s\n", "N", "load_s", "write_s", "products_MB");
  for (int n : sizes) {
    const gonogo::geo::TerrainInputs inputs = MakeInputs(n);
    auto start = Clock::now();
    const gonogo::geo::TerrainLayers layers = gonogo::geo::LoadTerrain(inputs, {});
    const double load_s = SecondsSince(start);

    std::vector<uint8_t> go_class(layers.valid.size());
    std::vector<float> speed_kmh(layers.valid.size());
    for (size_t i = 0; i < go_class.size(); ++i) {
      const float slope = layers.slope_percent[i];
      go_class[i] = !layers.valid[i] ? 255 : slope > 30.0f ? 0 : slope > 15.0f ? 1 : 2;
      speed_kmh[i] = layers.valid[i] ? std::max(0.0f, 40.0f - slope) : NAN;
    }
    start = Clock::now();
    const gonogo::geo::MapProducts products = gonogo::geo::WriteMapProducts(
        layers.grid, go_class, speed_kmh, {"bench", {{"BENCH", "1"}}}, dir.path());
    const double write_s = SecondsSince(start);
    double bytes = 0;
    for (const gonogo::geo::ProductFile& file : products.files) {
      const std::string path = dir.path() + "/" + file.name;
      if (FILE* f = std::fopen(path.c_str(), "rb")) {
        std::fseek(f, 0, SEEK_END);
        bytes += std::ftell(f);
        std::fclose(f);
      }
    }
    std::printf("%8d %12.3f %12.3f %14.2f\n", n, load_s, write_s, bytes / 1e6);
  }
  return 0;
}
