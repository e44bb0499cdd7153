// WriteStacItem: the catalogue entry of a map's products (STAC 1.0.0 item, projection extension
// 1.1.0; https://github.com/radiantearth/stac-spec/blob/v1.0.0/item-spec/item-spec.md).
#include <ogr_spatialref.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/products.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;  // keys in the order STAC documents them

constexpr char kStacVersion[] = "1.0.0";
constexpr char kProjectionExtension[] =
    "https://stac-extensions.github.io/projection/v1.1.0/schema.json";
// Points per edge when a bbox is reprojected: edges of a projected grid curve in longitude /
// latitude, so the corners alone can miss part of the extent.
constexpr int kDensifyPoints = 21;

struct NativeBounds {
  double min_x, min_y, max_x, max_y;
};

NativeBounds BoundsOf(const Grid& grid) {
  const auto& gt = grid.geotransform;
  const double x0 = gt[0], x1 = gt[0] + grid.width * gt[1];
  const double y0 = gt[3], y1 = gt[3] + grid.height * gt[5];
  return {std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1)};
}

struct Wgs84Extent {
  std::array<double, 4> bbox;                    // west, south, east, north
  std::vector<std::array<double, 2>> footprint;  // closed ring, counter-clockwise
};

Wgs84Extent ExtentInWgs84(const Grid& grid, const OGRSpatialReference& native) {
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  // Longitude first, as GeoJSON and STAC want it.
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84(
      OGRCreateCoordinateTransformation(&native, &wgs84));
  Require(to_wgs84 != nullptr, "grid", "its CRS cannot be transformed to WGS 84");
  const NativeBounds b = BoundsOf(grid);
  Wgs84Extent extent;
  auto& [west, south, east, north] = extent.bbox;
  Require(to_wgs84->TransformBounds(b.min_x, b.min_y, b.max_x, b.max_y, &west, &south, &east,
                                    &north, kDensifyPoints) != 0,
          "grid", "its extent cannot be transformed to WGS 84");
  // The footprint: the grid's outline with its edges densified, so it follows their curvature.
  std::vector<std::array<double, 2>> outline;
  const std::array<std::array<double, 2>, 4> corners = {
      {{b.min_x, b.min_y}, {b.max_x, b.min_y}, {b.max_x, b.max_y}, {b.min_x, b.max_y}}};
  for (int edge = 0; edge < 4; ++edge) {
    const auto& from = corners[edge];
    const auto& to = corners[(edge + 1) % 4];
    for (int i = 0; i < kDensifyPoints - 1; ++i) {
      const double t = static_cast<double>(i) / (kDensifyPoints - 1);
      outline.push_back({from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])});
    }
  }
  for (auto& point : outline) {
    double x = point[0], y = point[1];
    Require(to_wgs84->Transform(1, &x, &y) != 0, "grid",
            "a corner of its extent cannot be transformed to WGS 84");
    point = {x, y};
  }
  outline.push_back(outline.front());
  extent.footprint = std::move(outline);
  return extent;
}

json ProjectionProperties(const Grid& grid, OGRSpatialReference& native) {
  const auto& gt = grid.geotransform;
  const NativeBounds b = BoundsOf(grid);
  json epsg = nullptr;
  if (native.AutoIdentifyEPSG() == OGRERR_NONE || native.GetAuthorityCode(nullptr) != nullptr) {
    const char* authority = native.GetAuthorityName(nullptr);
    const char* code = native.GetAuthorityCode(nullptr);
    if (authority != nullptr && code != nullptr && std::string(authority) == "EPSG") {
      epsg = std::stoi(code);
    }
  }
  return {{"proj:epsg", epsg},
          {"proj:wkt2", grid.crs_wkt},
          {"proj:shape", {grid.height, grid.width}},
          // The affine transform in the order of the Python affine package: a, b, c, d, e, f.
          {"proj:transform", {gt[1], gt[2], gt[0], gt[4], gt[5], gt[3]}},
          {"proj:bbox", {b.min_x, b.min_y, b.max_x, b.max_y}}};
}

json AssetsJson(const std::vector<ProductFile>& assets) {
  json out = json::object();
  for (const ProductFile& file : assets) {
    json asset = {{"href", "./" + file.name}, {"type", file.media_type}, {"roles", file.roles}};
    if (!file.title.empty()) asset["title"] = file.title;
    out[file.name] = asset;
  }
  return out;
}

}  // namespace

void WriteStacItem(const Grid& grid, const StacItemInfo& info,
                   const std::vector<ProductFile>& assets, const std::string& path) {
  internal::EnsureGdalRegistered();
  internal::GdalErrorScope gdal_errors;
  Require(!info.id.empty(), "stac", "item id is empty");
  Require(!info.datetime_utc.empty(), "stac", "datetime is empty");
  json properties = json::object();
  if (!info.properties_json.empty()) {
    properties = json::parse(info.properties_json, nullptr, /*allow_exceptions=*/false);
    Require(properties.is_object(), "stac", "properties_json is not a JSON object");
  }
  Require(grid.width > 0 && grid.height > 0, "grid", "zero-size grid");
  OGRSpatialReference native;
  Require(native.importFromWkt(grid.crs_wkt.c_str()) == OGRERR_NONE, "grid",
          "grid CRS is not a valid WKT definition");
  native.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);

  const Wgs84Extent extent = ExtentInWgs84(grid, native);
  properties["datetime"] = info.datetime_utc;
  if (!info.title.empty()) properties["title"] = info.title;
  properties.update(ProjectionProperties(grid, native));
  const json item = {
      {"type", "Feature"},
      {"stac_version", kStacVersion},
      {"stac_extensions", {kProjectionExtension}},
      {"id", info.id},
      {"bbox", extent.bbox},
      {"geometry", {{"type", "Polygon"}, {"coordinates", {extent.footprint}}}},
      {"properties", properties},
      {"links", json::array()},
      {"assets", AssetsJson(assets)},
  };

  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    out << item.dump(2) << "\n";
    if (!out.flush()) {
      std::error_code ignored;
      fs::remove(partial, ignored);
      throw std::runtime_error("cannot write " + path);
    }
  }
  fs::rename(partial, path);
}

}  // namespace gonogo::geo
