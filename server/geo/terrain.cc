// LoadTerrain: open the uploads, check them, and bring every layer onto the cone-index grid.
#include "server/geo/terrain.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "server/geo/gdal_util.h"
#include "server/geo/geodesy.h"
#include "server/geo/slope.h"
#include "server/geo/warp.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

using internal::OpenedRaster;

// "row R col C" for a row-major index, 0-based like GDAL pixel/line offsets.
std::string CellName(size_t index, int width) {
  return "row " + std::to_string(index / width) + " col " + std::to_string(index % width) +
         " (0-based)";
}

std::string FormatValue(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

void CheckInputChoice(const TerrainInputs& inputs) {
  Require(inputs.slope.has_value() || inputs.elevation.has_value(), "slope",
          "one of slope (percent) or elevation (metres) is required");
  Require(!(inputs.slope.has_value() && inputs.elevation.has_value()), "elevation",
          "give slope or elevation, not both");
}

// The output grid: the cone-index raster's own grid and CRS.
Grid GridOf(const OpenedRaster& cone, const GeoLimits& limits) {
  Grid grid;
  grid.width = cone.width;
  grid.height = cone.height;
  if (grid.CellCount() > limits.max_output_cells) {
    throw LimitError("cone_index", "output grid of " + std::to_string(grid.CellCount()) +
                                       " cells exceeds the limit of " +
                                       std::to_string(limits.max_output_cells) + " cells");
  }
  cone.dataset->GetGeoTransform(grid.geotransform.data());
  Require(grid.geotransform[2] == 0.0 && grid.geotransform[4] == 0.0, "cone_index",
          "rotated geotransform is not supported; warp the cone-index raster to a north-up grid");
  // WKT2 keeps every detail of the CRS (datum ensembles, axis order) that WKT1 may drop.
  const char* const wkt_options[] = {"FORMAT=WKT2_2019", nullptr};
  char* wkt = nullptr;
  cone.dataset->GetSpatialRef()->exportToWkt(&wkt, wkt_options);
  grid.crs_wkt = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  internal::CrsMetricsFromWkt(grid.crs_wkt, "cone_index");  // projected or geographic only
  return grid;
}

// Cone index must be finite and non-negative wherever it has data, and have data somewhere.
void CheckConeIndex(const std::vector<float>& cone_kpa, int width) {
  bool any_valid = false;
  for (size_t i = 0; i < cone_kpa.size(); ++i) {
    const float v = cone_kpa[i];
    if (std::isnan(v)) continue;
    any_valid = true;
    // Per-cell checks build their message only on failure (Require would build it every time).
    if (!std::isfinite(v)) {
      throw InputError("cone_index", "infinite value at " + CellName(i, width) +
                                         "; mark missing cells as nodata");
    }
    if (v < 0.0f) {
      throw InputError("cone_index",
                       "negative value " + FormatValue(v) + " kPa at " + CellName(i, width) +
                           "; cone index must be >= 0 (mark missing cells as nodata)");
    }
  }
  Require(any_valid, "cone_index", "all cells are nodata (or NaN)");
}

// An optional layer must share at least one valid cell with the cone index. When it shares none,
// tells an all-nodata upload apart from one that does not overlap (reading the source again only on
// this error path).
template <typename T>
void CheckOverlap(const std::vector<T>& layer, const std::vector<float>& cone_kpa,
                  const OpenedRaster& source, const std::string& field) {
  for (size_t i = 0; i < layer.size(); ++i) {
    if (!std::isnan(layer[i]) && !std::isnan(cone_kpa[i])) return;
  }
  Require(internal::HasAnyValidCell(source), field, "all cells are nodata (or NaN)");
  throw InputError(field,
                   "does not overlap the cone-index grid: after warping onto it no cell has data "
                   "in both rasters (check the extent and CRS)");
}

std::vector<float> LoadSlope(const RasterInput& input, const Grid& grid,
                             const std::vector<float>& cone_kpa, const GeoLimits& limits) {
  const OpenedRaster source = internal::OpenUpload(input, "slope", limits.max_input_cells);
  std::vector<float> slope =
      internal::WarpContinuous(source, grid, internal::ContinuousMethod::kAverage, "slope");
  CheckOverlap(slope, cone_kpa, source, "slope");
  for (size_t i = 0; i < slope.size(); ++i) {
    if (std::isnan(slope[i])) continue;
    if (!std::isfinite(slope[i]) || slope[i] < 0.0f) {
      throw InputError("slope",
                       "value " + FormatValue(slope[i]) + " % at " + CellName(i, grid.width) +
                           " of the cone-index grid; slope must be finite and >= 0 percent");
    }
  }
  return slope;
}

std::vector<float> LoadSlopeFromElevation(const RasterInput& input, const Grid& grid,
                                          const std::vector<float>& cone_kpa,
                                          const GeoLimits& limits) {
  const OpenedRaster source = internal::OpenUpload(input, "elevation", limits.max_input_cells);
  const std::vector<float> elevation_m =
      internal::WarpContinuous(source, grid, internal::ContinuousMethod::kBilinear, "elevation");
  CheckOverlap(elevation_m, cone_kpa, source, "elevation");
  for (size_t i = 0; i < elevation_m.size(); ++i) {
    if (std::isinf(elevation_m[i])) {
      throw InputError("elevation",
                       "infinite value at " + CellName(i, grid.width) + " of the cone-index grid");
    }
  }
  return HornSlopePercent(grid, elevation_m);
}

std::vector<int32_t> LoadSoilClass(const RasterInput& input, const Grid& grid,
                                   const std::vector<float>& cone_kpa, const GeoLimits& limits) {
  const OpenedRaster source = internal::OpenUpload(input, "soil_class", limits.max_input_cells);
  const std::vector<double> codes = internal::WarpCategorical(source, grid, "soil_class");
  CheckOverlap(codes, cone_kpa, source, "soil_class");
  std::vector<int32_t> soil(codes.size(), -1);
  for (size_t i = 0; i < codes.size(); ++i) {
    const double code = codes[i];
    if (std::isnan(code)) continue;
    if (!(code >= 0.0 && code <= std::numeric_limits<int32_t>::max() && code == std::floor(code))) {
      throw InputError("soil_class", "class code " + FormatValue(code) + " at " +
                                         CellName(i, grid.width) +
                                         " of the cone-index grid is not an integer >= 0");
    }
    soil[i] = static_cast<int32_t>(code);
  }
  return soil;
}

}  // namespace

TerrainLayers LoadTerrain(const TerrainInputs& inputs, const GeoLimits& limits) {
  internal::EnsureGdalRegistered();
  internal::GdalErrorScope gdal_errors;
  CheckInputChoice(inputs);

  TerrainLayers layers;
  {
    const OpenedRaster cone =
        internal::OpenUpload(inputs.cone_index, "cone_index", limits.max_input_cells);
    layers.grid = GridOf(cone, limits);
    layers.cone_index_kpa = internal::ReadBand1AsFloat(cone, "cone_index");
  }
  CheckConeIndex(layers.cone_index_kpa, layers.grid.width);

  if (inputs.slope.has_value()) {
    layers.slope_percent = LoadSlope(*inputs.slope, layers.grid, layers.cone_index_kpa, limits);
  } else {
    layers.slope_percent =
        LoadSlopeFromElevation(*inputs.elevation, layers.grid, layers.cone_index_kpa, limits);
  }
  if (inputs.soil_class.has_value()) {
    layers.soil_class =
        LoadSoilClass(*inputs.soil_class, layers.grid, layers.cone_index_kpa, limits);
  }

  // Valid where every supplied layer has data.
  layers.valid.assign(layers.cone_index_kpa.size(), 0);
  bool any_valid = false;
  for (size_t i = 0; i < layers.valid.size(); ++i) {
    const bool ok = !std::isnan(layers.cone_index_kpa[i]) && !std::isnan(layers.slope_percent[i]) &&
                    (layers.soil_class.empty() || layers.soil_class[i] >= 0);
    layers.valid[i] = ok ? 1 : 0;
    any_valid = any_valid || ok;
  }
  const char* last_field = inputs.soil_class.has_value()
                               ? "soil_class"
                               : (inputs.slope.has_value() ? "slope" : "elevation");
  Require(any_valid, last_field,
          "no cell where every supplied layer has data (each overlaps the cone-index raster, but "
          "not all of them in the same place)");
  return layers;
}

}  // namespace gonogo::geo
