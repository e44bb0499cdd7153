// Map products of a finished go/no-go run, ready for a GIS user without any setting: two
// Cloud-Optimized GeoTIFFs with their QGIS styles, the class names for GIS software, a KMZ for
// Google Earth and a PNG quicklook; and a STAC item describing them.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo {

// Values of the go/no-go class raster.
inline constexpr uint8_t kClassNoGo = 0;
inline constexpr uint8_t kClassSlowGo = 1;
inline constexpr uint8_t kClassGo = 2;
inline constexpr uint8_t kClassNoData = 255;

// What the products say about the map beyond its cells.
struct MapDescription {
  // One line on the quicklook and the KMZ legend, e.g. "sample terrain - FED Alpha, empirical
  // tier"; empty: "Go / no-go map".
  std::string title;
  // Into both GeoTIFFs' dataset metadata (LEGEND and UNITS are set by WriteMapProducts and win).
  std::map<std::string, std::string> metadata;
};

// One product file as a catalogue (the STAC item) describes it.
struct ProductFile {
  std::string name;                // file name in the output directory
  std::string media_type;          // IANA media type, e.g. "image/png"
  std::vector<std::string> roles;  // STAC asset roles: "data", "overview", "visual", "metadata"
  std::string title;
};

// Paths of the files written, and every file in download order.
struct MapProducts {
  std::string gonogo_tif;      // Byte COG: classes above, nodata 255, colour table, LEGEND metadata
  std::string gonogo_aux_xml;  // GDAL sidecar of gonogo.tif: category names and attribute table
  std::string gonogo_qml;      // QGIS style of gonogo.tif: three labelled classes
  std::string speed_tif;       // Float32 COG: speed in km/h, nodata NaN
  std::string speed_qml;       // QGIS style of speed.tif: colour ramp in km/h
  std::string kmz;             // gonogo.kmz: the classes as a KML super-overlay with a legend
  std::string quicklook_png;   // RGBA PNG: title, classes, legend, north arrow, scale bar
  std::vector<ProductFile> files;
};

// Writes into out_dir (created if needed; each file appears complete or not at all):
// gonogo.tif, gonogo.tif.aux.xml, gonogo.qml, speed.tif, speed.qml, gonogo.kmz, quicklook.png.
// `go_class` and `speed_kmh` have grid.width * grid.height entries, row-major; speed NaN means no
// data. Throws InputError for inconsistent arguments ("grid", "go_class", "speed_kmh",
// "metadata", "out_dir") and std::runtime_error when a file cannot be written.
MapProducts WriteMapProducts(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::vector<float>& speed_kmh, const MapDescription& description,
                             const std::string& out_dir);

// A STAC item (STAC 1.0.0 with the projection extension) describing a map's products.
struct StacItemInfo {
  std::string id;               // item id, e.g. the job id; non-empty
  std::string datetime_utc;     // RFC 3339 in UTC, e.g. "2024-05-01T12:00:00Z"
  std::string title;            // properties.title
  std::string properties_json;  // a JSON object merged into properties (provenance); may be ""
};

// Writes the item describing `assets` (hrefs relative to the item's folder) at `path`: bbox and
// footprint in WGS 84 longitude / latitude, the grid's native CRS, shape and transform
// (proj:wkt2, proj:epsg when the CRS has an EPSG code, proj:shape, proj:transform, proj:bbox).
// Throws InputError("stac", ...) for an empty id or datetime or properties_json that is not a JSON
// object, InputError("grid", ...) for an unusable grid, std::runtime_error when it cannot write.
void WriteStacItem(const Grid& grid, const StacItemInfo& info,
                   const std::vector<ProductFile>& assets, const std::string& path);

}  // namespace gonogo::geo
