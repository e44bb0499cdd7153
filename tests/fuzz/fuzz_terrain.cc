// libFuzzer target: raster upload and validation. The bytes are an uploaded raster file, read by
// GDAL from memory exactly as an upload is (geo::LoadTerrain): as the cone-index raster with itself
// as the elevation, and with itself as the soil-class raster beside the bundled sample's cone index.
// Limits are small, so that a header claiming a huge raster is refused rather than allocated.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "fuzz_expected.h"
#include "server/geo/terrain.h"

using namespace gonogo;

namespace {
std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // A valid 24 x 24 cone-index raster of the sample terrain, beside which the input is a soil-class
  // or elevation raster (tests/fuzz/corpus/terrain/cone_index.tif).
  static const std::string sample_cone = ReadFile(GONOGO_FUZZ_SAMPLE_CONE);
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  geo::GeoLimits limits;
  limits.max_input_cells = 1 << 20;
  limits.max_output_cells = 1 << 20;
  {
    geo::TerrainInputs inputs;
    inputs.cone_index.bytes = bytes;
    inputs.elevation = geo::RasterInput{bytes};
    ExpectOnlyFieldErrors([&] { geo::LoadTerrain(inputs, limits); });
  }
  {
    geo::TerrainInputs inputs;
    inputs.cone_index.bytes = sample_cone;
    inputs.elevation = geo::RasterInput{bytes};
    inputs.soil_class = geo::RasterInput{bytes};
    ExpectOnlyFieldErrors([&] { geo::LoadTerrain(inputs, limits); });
  }
  return 0;
}
