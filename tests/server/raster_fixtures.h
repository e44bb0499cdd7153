// Small GeoTIFFs made in memory with GDAL, for bad-input cases.
#pragma once

#include <string>
#include <vector>

namespace gonogo::testing {

struct TiffSpec {
  int width = 8, height = 8;
  int epsg = 32617;          // 0: no CRS
  double origin_x = 500000, origin_y = 4000000, cell_m = 10;
  bool has_nodata = true;
  double nodata = -9999;
};

// A Float32 GeoTIFF with `values` (row-major, width*height), returned as file bytes.
std::string MakeTiff(const TiffSpec& spec, const std::vector<float>& values);

}  // namespace gonogo::testing
