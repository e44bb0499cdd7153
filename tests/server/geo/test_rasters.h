// Test fixtures for server/geo: real GeoTIFF files built with GDAL, and helpers to inspect output.
#pragma once

#include <gdal_priv.h>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo::fixtures {

// A single-band raster to encode as GeoTIFF bytes.
struct RasterSpec {
  int width = 20;
  int height = 20;
  // UTM 17N near 36.1 N 81 W, 10 m cells.
  std::array<double, 6> geotransform{500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0};
  bool georeferenced = true;  // false: no geotransform written
  int epsg = 32617;           // 0: no CRS written
  GDALDataType type = GDT_Float32;
  std::optional<double> nodata;
  std::vector<double> values;  // width * height row-major; empty: every cell is `fill`
  double fill = 0.0;
  bool mask_left_half = false;  // add an internal mask that hides columns < width / 2
};

// The bytes of a GeoTIFF file holding `spec`.
std::string MakeGeoTiff(const RasterSpec& spec);

// `spec` written with another GDAL driver (e.g. "HFA" for ERDAS Imagine), as file bytes.
std::string MakeRasterFile(const RasterSpec& spec, const char* driver);

// Fills spec.values from f(x, y) evaluated at cell centres in CRS units.
void FillFromCentres(RasterSpec& spec, const std::function<double(double x, double y)>& f);

// WKT of an EPSG code, GIS axis order (x = easting or longitude).
std::string WktOfEpsg(int epsg);

// Transforms (x, y) from one EPSG CRS to another, GIS axis order.
std::array<double, 2> Transform(int from_epsg, int to_epsg, double x, double y);

// A fresh empty directory under the system temp directory, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& stem);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Runs a shell command; returns its exit status and puts stdout+stderr in *output.
int RunCommand(const std::string& command, std::string* output);

// A GeoPackage holding two raster tables: GDAL opens it as a container of sub-datasets with no
// bands of its own.
std::string MakeTwoTableGeoPackage();

// Opens a file written by the module for inspection (read-only, GDAL registered).
GDALDatasetUniquePtr OpenForCheck(const std::string& path);

}  // namespace gonogo::geo::fixtures
