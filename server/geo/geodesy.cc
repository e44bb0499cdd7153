#include "server/geo/geodesy.h"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace internal {
namespace {

constexpr double kHalfPiRad = 1.57079632679489661923;

// Latitude of a grid y coordinate, in radians, clamped to the poles.
double LatitudeRad(const CrsMetrics& crs, double y_units) {
  return std::clamp(y_units * crs.radians_per_unit, -kHalfPiRad, kHalfPiRad);
}

}  // namespace

CrsMetrics CrsMetricsFromWkt(const std::string& wkt, const std::string& field) {
  OGRSpatialReference srs;
  Require(!wkt.empty() && srs.importFromWkt(wkt.c_str()) == OGRERR_NONE, field,
          "CRS is missing or not a valid WKT definition");
  CrsMetrics metrics;
  if (srs.IsProjected()) {
    metrics.metres_per_unit = srs.GetLinearUnits(nullptr);
  } else if (srs.IsGeographic()) {
    metrics.geographic = true;
    metrics.radians_per_unit = srs.GetAngularUnits(nullptr);
  } else {
    throw InputError(field,
                     "CRS must be projected or geographic (got a geocentric, local or "
                     "engineering CRS)");
  }
  OGRErr err = OGRERR_NONE;
  metrics.semi_major_m = srs.GetSemiMajor(&err);
  const double semi_minor_m = srs.GetSemiMinor(&err);
  Require(err == OGRERR_NONE && metrics.semi_major_m > 0.0 && semi_minor_m > 0.0, field,
          "CRS has no usable ellipsoid");
  metrics.eccentricity_sq =
      1.0 - (semi_minor_m * semi_minor_m) / (metrics.semi_major_m * metrics.semi_major_m);
  Require(metrics.metres_per_unit > 0.0 && (!metrics.geographic || metrics.radians_per_unit > 0.0),
          field, "CRS has no usable units");
  return metrics;
}

const CrsMetrics& CachedCrsMetrics(const std::string& wkt) {
  // Grid::CellAreaM2 is called per row; a per-thread cache avoids re-parsing the same WKT and
  // needs no locking.
  thread_local std::string cached_wkt;
  thread_local CrsMetrics cached;
  thread_local bool has_cached = false;
  if (!has_cached || wkt != cached_wkt) {
    cached = CrsMetricsFromWkt(wkt, "grid");
    cached_wkt = wkt;
    has_cached = true;
  }
  return cached;
}

double MeridianRadiusM(const CrsMetrics& crs, double lat_rad) {
  const double s = std::sin(lat_rad);
  const double w = 1.0 - crs.eccentricity_sq * s * s;
  return crs.semi_major_m * (1.0 - crs.eccentricity_sq) / (w * std::sqrt(w));
}

double PrimeVerticalRadiusM(const CrsMetrics& crs, double lat_rad) {
  const double s = std::sin(lat_rad);
  return crs.semi_major_m / std::sqrt(1.0 - crs.eccentricity_sq * s * s);
}

double ZoneAreaPerRadianM2(const CrsMetrics& crs, double lat_rad) {
  // Snyder (1987) eq. 3-12: q = (1 - e^2) [sin phi / (1 - e^2 sin^2 phi) + atanh(e sin phi) / e],
  // written with atanh instead of the log form; q -> 2 sin phi on a sphere.
  const double s = std::sin(lat_rad);
  const double e2 = crs.eccentricity_sq;
  double q = 2.0 * s;
  if (e2 > 1e-15) {
    const double e = std::sqrt(e2);
    q = (1.0 - e2) * (s / (1.0 - e2 * s * s) + std::atanh(e * s) / e);
  }
  return 0.5 * crs.semi_major_m * crs.semi_major_m * q;
}

CellSizeM CellSizeAtRow(const Grid& grid, int row) {
  const CrsMetrics& crs = CachedCrsMetrics(grid.crs_wkt);
  const auto& gt = grid.geotransform;
  if (!crs.geographic) {
    return {std::hypot(gt[1], gt[4]) * crs.metres_per_unit,
            std::hypot(gt[2], gt[5]) * crs.metres_per_unit};
  }
  const double lat_rad = LatitudeRad(crs, gt[3] + (row + 0.5) * gt[5] + 0.5 * grid.width * gt[4]);
  const double east_m_per_unit =
      crs.radians_per_unit * PrimeVerticalRadiusM(crs, lat_rad) * std::cos(lat_rad);
  const double north_m_per_unit = crs.radians_per_unit * MeridianRadiusM(crs, lat_rad);
  return {std::hypot(gt[1] * east_m_per_unit, gt[4] * north_m_per_unit),
          std::hypot(gt[2] * east_m_per_unit, gt[5] * north_m_per_unit)};
}

}  // namespace internal

double Grid::CellAreaM2(int row) const {
  const internal::CrsMetrics& crs = internal::CachedCrsMetrics(crs_wkt);
  const auto& gt = geotransform;
  const double det_units2 = std::abs(gt[1] * gt[5] - gt[2] * gt[4]);
  if (!crs.geographic) return det_units2 * crs.metres_per_unit * crs.metres_per_unit;
  if (gt[2] != 0.0 || gt[4] != 0.0) {
    // Rotated geographic grid: the local metric at the row centre, accurate for cells far smaller
    // than the Earth.
    const double lat_rad =
        internal::LatitudeRad(crs, gt[3] + (row + 0.5) * gt[5] + 0.5 * width * gt[4]);
    return det_units2 * crs.radians_per_unit * crs.radians_per_unit *
           internal::MeridianRadiusM(crs, lat_rad) * internal::PrimeVerticalRadiusM(crs, lat_rad) *
           std::cos(lat_rad);
  }
  // North-up: the exact ellipsoidal area of the band between the row's edges, times the cell's
  // share of longitude.
  const double lat_a_rad = internal::LatitudeRad(crs, gt[3] + row * gt[5]);
  const double lat_b_rad = internal::LatitudeRad(crs, gt[3] + (row + 1) * gt[5]);
  const double dlon_rad = std::abs(gt[1]) * crs.radians_per_unit;
  return dlon_rad * std::abs(internal::ZoneAreaPerRadianM2(crs, lat_b_rad) -
                             internal::ZoneAreaPerRadianM2(crs, lat_a_rad));
}

}  // namespace gonogo::geo
