// Slope from elevation on a grid.
#pragma once

#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo {

// Slope in percent (100 * tan of the slope angle) of `elevation_m` (grid.width * grid.height,
// row-major, NaN = no data) by Horn's (1981) 3x3 finite differences, with cell sizes in ground
// metres (geographic CRS: metres per degree from the ellipsoid at each row's latitude).
//
// Horn's gradient is the 1-2-1 weighted mean of the central differences of the three rows (for x)
// and columns (for y) of the window. At edges, corners and beside holes a row or column missing one
// end uses the one-sided difference to its middle cell, and one missing more is dropped with the
// weights renormalised, so a plane keeps its exact slope everywhere; an axis with no usable line
// (a grid one cell wide) contributes no gradient.
// Cells whose own elevation is NaN get NaN. Throws InputError("elevation", ...) on a size mismatch.
std::vector<float> HornSlopePercent(const Grid& grid, const std::vector<float>& elevation_m);

}  // namespace gonogo::geo
