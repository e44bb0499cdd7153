// Terrain input for a mobility map: uploaded rasters (GeoTIFF or another self-contained GDAL raster
// format) turned into co-registered layers on one output grid.
//
// The output grid is the cone-index raster's own grid and CRS; slope, elevation and soil-class
// rasters are warped onto it (README.md explains the resampling). Every mistake in the uploads
// throws InputError naming the field ("cone_index", "slope", "elevation", "soil_class"); an upload
// or grid over GeoLimits throws LimitError naming the field. Thread-safe: each call uses its own
// GDAL datasets, /vsimem/ names and error handler.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gonogo::geo {

// The whole content of one uploaded raster file.
struct RasterInput {
  std::string bytes;
};

struct TerrainInputs {
  RasterInput cone_index;            // required; cone index in kPa, band 1
  std::optional<RasterInput> slope;  // slope in percent (100 * tan angle), band 1
  std::optional<RasterInput>
      elevation;  // elevation in metres, band 1; exactly one of slope/elevation
  std::optional<RasterInput> soil_class;  // integer class codes >= 0, band 1
};

struct GeoLimits {
  int64_t max_input_cells = 25'000'000;   // per uploaded raster (width * height)
  int64_t max_output_cells = 25'000'000;  // output grid (the cone-index grid)
};

// A north-up raster grid. Cell (row, col) covers x in [gt0 + col*gt1, gt0 + (col+1)*gt1) and
// y in [gt3 + row*gt5, gt3 + (row+1)*gt5), GDAL's geotransform convention.
struct Grid {
  int width = 0;
  int height = 0;
  std::array<double, 6> geotransform{};  // GDAL order: x0, dx, row rotation, y0, col rotation, dy
  std::string crs_wkt;                   // WKT2 (2019) of a projected or geographic CRS

  int64_t CellCount() const { return static_cast<int64_t>(width) * height; }
  // Area of one cell of `row` in square metres: on the CRS ellipsoid for a geographic CRS (cells
  // shrink towards the poles); |dx * dy| in metres for a projected CRS (map-projection scale
  // distortion is not corrected). Throws InputError("grid", ...) if crs_wkt is not usable.
  double CellAreaM2(int row) const;
};

// Co-registered layers on `grid`; every vector has grid.width * grid.height entries, row-major
// (index = row * width + col), except soil_class which is empty when no soil raster was given.
struct TerrainLayers {
  Grid grid;
  std::vector<float> cone_index_kpa;  // NaN where no data
  std::vector<float> slope_percent;   // NaN where no data
  std::vector<int32_t> soil_class;    // empty when no soil raster; -1 where no data
  std::vector<uint8_t> valid;         // 1 where every supplied layer has data, else 0
};

// Opens, checks and co-registers the uploads. Throws InputError or LimitError (see the file
// comment).
TerrainLayers LoadTerrain(const TerrainInputs& inputs, const GeoLimits& limits);

}  // namespace gonogo::geo
