// Ground distances and areas for a grid in a projected or geographic CRS (internal).
//
// Geographic CRS: distances use the radii of curvature of the CRS ellipsoid (Snyder 1987, "Map
// Projections: A Working Manual", USGS Prof. Paper 1395, ch. 3-4):
//   M(phi) = a (1 - e^2) / (1 - e^2 sin^2 phi)^(3/2)   metres per radian of latitude (meridian)
//   N(phi) = a / (1 - e^2 sin^2 phi)^(1/2)             prime vertical; N cos(phi) metres per radian
//                                                      of longitude
// and areas the authalic function q (Snyder eq. 3-12): the ellipsoid area between the equator and
// latitude phi is a^2 q(phi) / 2 per radian of longitude.
// Projected CRS: one CRS unit is the CRS's linear unit in metres everywhere; the projection's scale
// factor (e.g. 0.9996 to 1.0004 across a UTM zone) is ignored.
#pragma once

#include <string>

#include "server/geo/terrain.h"

namespace gonogo::geo::internal {

struct CrsMetrics {
  bool geographic = false;
  double metres_per_unit = 1.0;   // projected: the CRS linear unit in metres
  double radians_per_unit = 0.0;  // geographic: the CRS angular unit in radians
  double semi_major_m = 0.0;      // ellipsoid a
  double eccentricity_sq = 0.0;   // ellipsoid e^2 = 1 - b^2 / a^2
};

// Parses `wkt`; throws InputError(field, ...) unless it is a projected or geographic CRS.
CrsMetrics CrsMetricsFromWkt(const std::string& wkt, const std::string& field);

// CrsMetricsFromWkt with a per-thread cache of the last WKT seen (parsing costs ~0.1 ms).
const CrsMetrics& CachedCrsMetrics(const std::string& wkt);

double MeridianRadiusM(const CrsMetrics& crs, double lat_rad);       // M(phi)
double PrimeVerticalRadiusM(const CrsMetrics& crs, double lat_rad);  // N(phi)
double ZoneAreaPerRadianM2(const CrsMetrics& crs, double lat_rad);   // a^2 q(phi) / 2

// Ground size of one cell of `row` along the grid axes, in metres. For a geographic CRS it is taken
// at the latitude of the row centre.
struct CellSizeM {
  double dx_m = 0.0;
  double dy_m = 0.0;
};
CellSizeM CellSizeAtRow(const Grid& grid, int row);

}  // namespace gonogo::geo::internal
