#include "server/geo/slope.h"

#include <cmath>
#include <limits>

#include "server/geo/geodesy.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

// Change of elevation per cell along one axis, from the three lines (-1, 0, +1) across it with
// Horn's weights 1-2-1. z(line, step) is the elevation at `step` cells along the axis on `line`,
// NaN where missing. Returns 0 when no line has two cells.
template <typename ElevationAt>
double WeightedDifference(const ElevationAt& z) {
  double sum = 0.0, weight_sum = 0.0;
  for (int line = -1; line <= 1; ++line) {
    const double before = z(line, -1), middle = z(line, 0), after = z(line, 1);
    double per_cell = 0.0;
    if (!std::isnan(before) && !std::isnan(after)) {
      per_cell = 0.5 * (after - before);
    } else if (!std::isnan(after) && !std::isnan(middle)) {
      per_cell = after - middle;
    } else if (!std::isnan(before) && !std::isnan(middle)) {
      per_cell = middle - before;
    } else {
      continue;
    }
    const double weight = line == 0 ? 2.0 : 1.0;
    sum += weight * per_cell;
    weight_sum += weight;
  }
  return weight_sum > 0.0 ? sum / weight_sum : 0.0;
}

}  // namespace

std::vector<float> HornSlopePercent(const Grid& grid, const std::vector<float>& elevation_m) {
  const int w = grid.width, h = grid.height;
  Require(w > 0 && h > 0 && elevation_m.size() == static_cast<size_t>(w) * h, "elevation",
          "elevation has " + std::to_string(elevation_m.size()) + " cells, grid needs " +
              std::to_string(grid.CellCount()));
  std::vector<float> slope_percent(elevation_m.size(), std::numeric_limits<float>::quiet_NaN());
  // Elevation at (row, col), NaN outside the grid.
  auto z_at = [&](int row, int col) -> double {
    if (row < 0 || row >= h || col < 0 || col >= w) return std::nan("");
    return elevation_m[static_cast<size_t>(row) * w + col];
  };
  for (int row = 0; row < h; ++row) {
    const internal::CellSizeM cell = internal::CellSizeAtRow(grid, row);
    for (int col = 0; col < w; ++col) {
      if (std::isnan(z_at(row, col))) continue;
      // Horn (1981), "Hill shading and the reflectance map", Proc. IEEE 69(1): 14-47 (also
      // gdaldem's default): with the window rows a b c / d e f / g h i from top to bottom,
      //   dz/dx = ((c + 2f + i) - (a + 2d + g)) / (8 dx),  dz/dy = ((g + 2h + i) - (a + 2b + c)) /
      //   (8 dy),
      // i.e. the 1-2-1 weighted mean of the three rows' (columns') central differences. A line
      // missing one end uses its one-sided difference to its middle cell; a line missing more is
      // left out and the weights renormalised. On a full window this is Horn's formula exactly.
      const double dz_dx_per_cell =
          WeightedDifference([&](int line, int step) { return z_at(row + line, col + step); });
      const double dz_dy_per_cell =
          WeightedDifference([&](int line, int step) { return z_at(row + step, col + line); });
      const double dz_dx = dz_dx_per_cell / cell.dx_m;
      const double dz_dy = dz_dy_per_cell / cell.dy_m;
      const double percent = 100.0 * std::sqrt(dz_dx * dz_dx + dz_dy * dz_dy);
      if (std::isfinite(percent)) {
        slope_percent[static_cast<size_t>(row) * w + col] = static_cast<float>(percent);
      }
    }
  }
  return slope_percent;
}

}  // namespace gonogo::geo
