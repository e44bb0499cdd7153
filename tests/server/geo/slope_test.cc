// Slope from elevation (Horn 1981) and cell areas, against closed forms: a plane has the same slope
// everywhere, including edges and holes, in metre, foot and degree CRSs.
#include "server/geo/slope.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "server/geo/terrain.h"
#include "solvers/common/errors.h"
#include "tests/server/geo/test_rasters.h"

namespace gonogo::geo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
// WGS84 ellipsoid (NIMA TR8350.2).
constexpr double kWgs84A = 6378137.0;
constexpr double kWgs84F = 1.0 / 298.257223563;
constexpr double kWgs84E2 = kWgs84F * (2.0 - kWgs84F);
constexpr double kUsSurveyFootM = 1200.0 / 3937.0;

double MeridianRadius(double lat_rad) {
  const double w = 1.0 - kWgs84E2 * std::sin(lat_rad) * std::sin(lat_rad);
  return kWgs84A * (1.0 - kWgs84E2) / std::pow(w, 1.5);
}

double PrimeVerticalRadius(double lat_rad) {
  return kWgs84A / std::sqrt(1.0 - kWgs84E2 * std::sin(lat_rad) * std::sin(lat_rad));
}

// Composite Simpson rule with n (even) intervals.
double Simpson(const std::function<double(double)>& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 == 1 ? 4.0 : 2.0);
  return sum * h / 3.0;
}

Grid MakeGrid(int epsg, std::array<double, 6> geotransform, int width = 20, int height = 20) {
  Grid grid;
  grid.width = width;
  grid.height = height;
  grid.geotransform = geotransform;
  grid.crs_wkt = fixtures::WktOfEpsg(epsg);
  return grid;
}

// Elevation f(x, y) at the cell centres of `grid`, in CRS units.
std::vector<float> Sample(const Grid& grid, const std::function<double(double, double)>& f) {
  std::vector<float> z(static_cast<size_t>(grid.CellCount()));
  const auto& gt = grid.geotransform;
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      z[row * grid.width + col] =
          static_cast<float>(f(gt[0] + (col + 0.5) * gt[1], gt[3] + (row + 0.5) * gt[5]));
    }
  }
  return z;
}

const std::array<double, 6> kUtmGeotransform{500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0};

TEST(HornSlope, PlaneHasItsSlopeEverywhereIncludingEdgesAndCorners) {
  const Grid grid = MakeGrid(32617, kUtmGeotransform);
  // dz/dx = 0.03, dz/dy = 0.04: a 5 % plane at 53.13 degrees from east.
  const auto z = Sample(grid, [](double x, double y) {
    return 100.0 + 0.03 * (x - 500000.0) + 0.04 * (y - 4000000.0);
  });
  const auto slope = HornSlopePercent(grid, z);
  for (size_t i = 0; i < slope.size(); ++i) EXPECT_NEAR(slope[i], 5.0, 1e-3) << i;
}

TEST(HornSlope, HolesStayNodataAndDoNotBiasNeighbours) {
  const Grid grid = MakeGrid(32617, kUtmGeotransform);
  auto z = Sample(grid, [](double x, double) { return 0.05 * (x - 500000.0); });
  for (int i : {0, 21, 105, 106, 107, 210, 399}) z[i] = std::nanf("");
  const auto slope = HornSlopePercent(grid, z);
  for (size_t i = 0; i < slope.size(); ++i) {
    if (std::isnan(z[i])) {
      EXPECT_TRUE(std::isnan(slope[i])) << i;
    } else {
      EXPECT_NEAR(slope[i], 5.0, 1e-3) << i;
    }
  }
}

TEST(HornSlope, QuadraticSurfaceMatchesCentralDifference) {
  // z = x^2 / 1000 (x in metres from the grid's west edge): Horn's x-difference spans two cells and
  // is exact for a quadratic, dz/dx = 2 x / 1000.
  const Grid grid = MakeGrid(32617, kUtmGeotransform);
  const auto z = Sample(grid, [](double x, double) {
    const double u = x - 500000.0;
    return u * u / 1000.0;
  });
  const auto slope = HornSlopePercent(grid, z);
  for (int row = 1; row < 19; ++row) {
    for (int col = 1; col < 19; ++col) {
      const double u = 10.0 * col + 5.0;
      EXPECT_NEAR(slope[row * 20 + col], 100.0 * 2.0 * u / 1000.0, 1e-3) << row << "," << col;
    }
  }
}

TEST(HornSlope, FootCrsConvertsCellSizeToMetres) {
  // NAD83 / North Carolina (ftUS), 30 ft cells; elevation stays in metres.
  const Grid grid = MakeGrid(2264, {2000000.0, 30.0, 0.0, 700000.0, 0.0, -30.0});
  const auto z =
      Sample(grid, [](double x, double) { return 0.05 * (x - 2000000.0) * kUsSurveyFootM; });
  const auto slope = HornSlopePercent(grid, z);
  for (size_t i = 0; i < slope.size(); ++i) EXPECT_NEAR(slope[i], 5.0, 1e-3) << i;
}

TEST(HornSlope, GeographicNorthRampUsesMeridianRadius) {
  // 0.0001 degree cells centred on 45 N; z = 0.05 * meridian arc length from the centre, with the
  // arc integrated numerically from M(phi).
  const Grid grid = MakeGrid(4326, {10.0, 1e-4, 0.0, 45.001, 0.0, -1e-4});
  const double lat0 = 45.0 * kDegToRad;
  const auto z = Sample(grid, [&](double, double lat_deg) {
    return 0.05 * Simpson(MeridianRadius, lat0, lat_deg * kDegToRad, 20);
  });
  const auto slope = HornSlopePercent(grid, z);
  // Tolerance: float elevations (about 1e-7 relative) over 11 m cells.
  for (size_t i = 0; i < slope.size(); ++i) EXPECT_NEAR(slope[i], 5.0, 2e-3) << i;
}

TEST(HornSlope, GeographicEastRampShrinksWithCosLatitude) {
  // At 60 N a degree of longitude is half as long as at the equator: z = 0.05 * east distance must
  // read 5 %, not 10 %.
  const Grid grid = MakeGrid(4326, {10.0, 1e-4, 0.0, 60.001, 0.0, -1e-4});
  const double lat0 = 60.0 * kDegToRad;
  const double metres_per_rad = PrimeVerticalRadius(lat0) * std::cos(lat0);
  const auto z = Sample(grid, [&](double lon_deg, double) {
    return 0.05 * (lon_deg - 10.0) * kDegToRad * metres_per_rad;
  });
  const auto slope = HornSlopePercent(grid, z);
  for (size_t i = 0; i < slope.size(); ++i) EXPECT_NEAR(slope[i], 5.0, 2e-3) << i;
}

TEST(HornSlope, ElevationWarpedOntoGeographicGrid) {
  // Cone-index grid in EPSG:4326 near 36.1 N 81 W; elevation a 5 % northward plane in UTM 17N with
  // 5 m cells. UTM distances are k = 0.9996 times ground distances on the central meridian (81 W),
  // so the ground slope is 5 * 0.9996 %.
  fixtures::RasterSpec cone;
  cone.epsg = 4326;
  cone.width = cone.height = 40;
  cone.geotransform = {-81.002, 1e-4, 0.0, 36.102, 0.0, -1e-4};
  cone.fill = 800.0;
  const auto nw = fixtures::Transform(4326, 32617, -81.002, 36.102);
  const auto se = fixtures::Transform(4326, 32617, -80.998, 36.098);
  fixtures::RasterSpec elevation;
  elevation.geotransform = {std::min(nw[0], se[0]) - 100.0, 5.0, 0.0,
                            std::max(nw[1], se[1]) + 100.0, 0.0, -5.0};
  elevation.width = static_cast<int>(std::abs(se[0] - nw[0]) / 5.0) + 40;
  elevation.height = static_cast<int>(std::abs(nw[1] - se[1]) / 5.0) + 40;
  fixtures::FillFromCentres(elevation, [&](double, double y) { return 0.05 * (y - se[1]); });
  TerrainInputs inputs;
  inputs.cone_index.bytes = fixtures::MakeGeoTiff(cone);
  inputs.elevation = RasterInput{fixtures::MakeGeoTiff(elevation)};
  const TerrainLayers t = LoadTerrain(inputs, {});
  ASSERT_EQ(t.slope_percent.size(), 1600u);
  for (size_t i = 0; i < t.slope_percent.size(); ++i) {
    EXPECT_NEAR(t.slope_percent[i], 5.0 * 0.9996, 0.01) << i;
  }
}

TEST(CellArea, ProjectedCellIsDxTimesDyInMetres) {
  EXPECT_DOUBLE_EQ(MakeGrid(32617, kUtmGeotransform).CellAreaM2(7), 100.0);
  const Grid feet = MakeGrid(2264, {2000000.0, 30.0, 0.0, 700000.0, 0.0, -30.0});
  EXPECT_NEAR(feet.CellAreaM2(0), 900.0 * kUsSurveyFootM * kUsSurveyFootM, 1e-9);
}

TEST(CellArea, GeographicCellMatchesNumericIntegral) {
  // Area element on the ellipsoid: M(phi) N(phi) cos(phi) dphi dlambda.
  const Grid grid = MakeGrid(4326, {0.0, 1.0, 0.0, 61.0, 0.0, -1.0}, 1, 61);
  for (int row : {0, 30, 60}) {
    const double top = (61.0 - row) * kDegToRad, bottom = (60.0 - row) * kDegToRad;
    const double expected =
        kDegToRad * Simpson(
                        [](double phi) {
                          return MeridianRadius(phi) * PrimeVerticalRadius(phi) * std::cos(phi);
                        },
                        bottom, top, 200);
    EXPECT_NEAR(grid.CellAreaM2(row) / expected, 1.0, 1e-10) << row;
  }
}

TEST(CellArea, GlobalGeographicGridSumsToEllipsoidArea) {
  // A 1 degree global grid covers the WGS84 ellipsoid, 510 065 621.724 km^2 (the closed form
  // 2 pi a^2 (1 + (1 - e^2) atanh(e) / e)).
  const Grid grid = MakeGrid(4326, {-180.0, 1.0, 0.0, 90.0, 0.0, -1.0}, 360, 180);
  double total_m2 = 0.0;
  for (int row = 0; row < 180; ++row) total_m2 += 360.0 * grid.CellAreaM2(row);
  const double e = std::sqrt(kWgs84E2);
  const double closed_form_m2 =
      2.0 * kPi * kWgs84A * kWgs84A * (1.0 + (1.0 - kWgs84E2) * std::atanh(e) / e);
  EXPECT_NEAR(total_m2 / closed_form_m2, 1.0, 1e-12);
  EXPECT_NEAR(total_m2 / 510065621.724e6, 1.0, 1e-11);
}

TEST(CellArea, RejectsNonGeographicNonProjectedCrs) {
  const Grid geocentric = MakeGrid(4978, {0.0, 1.0, 0.0, 0.0, 0.0, -1.0});
  try {
    geocentric.CellAreaM2(0);
    FAIL() << "geocentric CRS accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "grid");
  }
}

}  // namespace
}  // namespace gonogo::geo
