// Warping an uploaded raster onto the output grid (internal).
#pragma once

#include <string>
#include <vector>

#include "server/geo/gdal_util.h"
#include "server/geo/terrain.h"

namespace gonogo::geo::internal {

// How continuous fields are resampled.
enum class ContinuousMethod {
  // Slope: GDAL's area-weighted average when the source cells are as small as the output cells or
  // smaller (the mean slope of each output cell); bilinear when they are coarser, where average
  // would copy the nearest source cell and leave steps.
  kAverage,
  // Elevation: bilinear interpolation at each output cell centre from the 2 x 2 source cells
  // around it, exact for a plane, so Horn's slope on the output grid carries no resampling noise.
  // (GDAL's average, and its bilinear with the kernel widened when shrinking, move the effective
  // sample point by a fraction of a source cell from cell to cell: about 1-2 % slope noise on a
  // plane.) From a DEM much finer than the grid this samples the terrain at cell centres rather
  // than smoothing it: the slope is the grade across output cells, and roughness finer than a cell
  // does not enter.
  kBilinear,
};

// Band 1 of `source` warped onto `grid` (grid.width * grid.height, row-major), NaN where the source
// has no data or does not reach. Source nodata (value, mask or NaN) is respected. Throws
// InputError(field, ...) when the CRSs cannot be related or GDAL fails.
std::vector<float> WarpContinuous(const OpenedRaster& source, const Grid& grid,
                                  ContinuousMethod method, const std::string& field);

// Categorical fields (soil classes): nearest neighbour, so codes are never mixed. Double keeps
// every int32 code exact and lets the caller reject non-integer values.
std::vector<double> WarpCategorical(const OpenedRaster& source, const Grid& grid,
                                    const std::string& field);

}  // namespace gonogo::geo::internal
