// QGIS layer styles (.qml) for the map products (internal). QGIS applies `NAME.qml` on its own when
// it opens `NAME.tif` from the same folder, so gonogo.qml and speed.qml sit beside the rasters.
// The format is the one QGIS 3.22 writes with Layer Properties > Style > Save as QGIS Layer Style
// File; later QGIS versions read it unchanged.
#pragma once

#include <string>

namespace gonogo::geo::internal {

// Paletted renderer of band 1 with three classes, labelled and coloured as the COG's palette:
// 2 "GO", 1 "SLOW-GO", 0 "NO-GO" (legend in that order); nodata (255) and every other value are
// not drawn. Nearest-neighbour resampling, so class edges stay crisp.
std::string ClassStyleQml();

// Single-band pseudocolour renderer of band 1: a colour ramp from red at 0 km/h through yellow to
// green at `max_kmh`, five stops labelled "0 km/h" ... "<max_kmh> km/h"; speeds above max_kmh
// take the last colour; NaN (nodata) is not drawn. `max_kmh` > 0.
std::string SpeedStyleQml(double max_kmh);

// The top of the speed ramp for speeds up to `highest_kmh`: the next multiple of 5 km/h at or
// above it, at least 5 km/h (NaN or no data: 5 km/h).
double SpeedRampMaxKmh(double highest_kmh);

}  // namespace gonogo::geo::internal
