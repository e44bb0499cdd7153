// The class map as a KMZ for Google Earth (internal): a KML super-overlay written by GDAL's
// KMLSUPEROVERLAY driver, with the legend as a screen overlay.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo::internal {

// Writes `path` (a .kmz; complete or not at all): the classes in their palette colours (no data
// transparent) reprojected to WGS 84 longitude / latitude with nearest-neighbour resampling, so
// class codes never mix, tiled into PNG tiles with their regions, and `legend.png`
// (RenderLegendPanel(title)) shown as a screen overlay in the top-left corner of the view.
// Throws std::runtime_error when GDAL cannot reproject or write.
void WriteClassKmz(const Grid& grid, const std::vector<uint8_t>& go_class, const std::string& title,
                   const std::string& path);

// The ScreenOverlay element that WriteClassKmz adds to doc.kml.
inline constexpr char kKmzLegendName[] = "legend.png";

}  // namespace gonogo::geo::internal
