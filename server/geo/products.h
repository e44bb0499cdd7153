// Map products of a finished go/no-go run: two Cloud-Optimized GeoTIFFs and a PNG quicklook.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo {

// Values of the go/no-go class raster.
inline constexpr uint8_t kClassNoGo = 0;
inline constexpr uint8_t kClassSlowGo = 1;
inline constexpr uint8_t kClassGo = 2;
inline constexpr uint8_t kClassNoData = 255;

// Paths of the files written.
struct MapProducts {
  std::string gonogo_tif;     // Byte COG: classes above, nodata 255, colour table, LEGEND metadata
  std::string speed_tif;      // Float32 COG: speed in km/h, nodata NaN
  std::string quicklook_png;  // RGBA PNG of the classes with a legend
};

// Writes out_dir/gonogo.tif, out_dir/speed.tif and out_dir/quicklook.png (creating out_dir if
// needed; each file appears complete or not at all). `go_class` and `speed_kmh` have
// grid.width * grid.height entries, row-major; speed NaN means no data. Every `metadata` entry goes
// into both GeoTIFFs' dataset metadata (LEGEND and UNITS are set by this function and win).
// Throws InputError for inconsistent arguments ("grid", "go_class", "speed_kmh", "metadata",
// "out_dir") and std::runtime_error when a file cannot be written.
MapProducts WriteMapProducts(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::vector<float>& speed_kmh,
                             const std::map<std::string, std::string>& metadata,
                             const std::string& out_dir);

}  // namespace gonogo::geo
