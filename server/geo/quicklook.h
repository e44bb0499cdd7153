// PNG quicklook of a go/no-go class map with a legend, and the cairo plumbing the line plots
// (plot.cc) share with it: owning handles, the font, the atomic PNG write (internal).
#pragma once

#include <cairo.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace gonogo::geo::internal {

struct Rgba {
  uint8_t r, g, b, a;
};

// Display colour of a class value (kClassNoGo red, kClassSlowGo amber, kClassGo green, anything
// else transparent). Shared by the COG colour table and the quicklook so they always agree.
Rgba ClassColour(uint8_t go_class);

// Owning handles for cairo objects.
struct CairoDeleter {
  void operator()(cairo_surface_t* surface) const { cairo_surface_destroy(surface); }
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using CairoSurface = std::unique_ptr<cairo_surface_t, CairoDeleter>;
using CairoContext = std::unique_ptr<cairo_t, CairoDeleter>;

// A width x height image surface, every pixel zero (transparent for CAIRO_FORMAT_ARGB32, black for
// CAIRO_FORMAT_RGB24), and a drawing context on it. Throw std::runtime_error when cairo cannot
// allocate them.
CairoSurface NewImageSurface(cairo_format_t format, int width, int height);
CairoContext NewContext(cairo_surface_t* surface);

// Every PNG writes its text in DejaVu Sans (Debian package fonts-dejavu-core, found through
// fontconfig) with greyscale antialiasing; `size_px` is the em size in pixels.
inline constexpr char kFontFamily[] = "DejaVu Sans";
void SelectFont(cairo_t* cr, double size_px, bool bold = false);

// Size of the map part of the quicklook for a width x height grid: grids with a long side over
// 1024 cells are shrunk to 1024 px; grids under 256 cells are enlarged by a whole factor so that
// the legend stays readable beside them.
void QuicklookMapSize(int width, int height, int* map_width_px, int* map_height_px);

// Size of the legend panel to the right of the map. The quicklook is (map width +
// kQuicklookLegendWidthPx) x max(map height, kQuicklookLegendHeightPx) px.
inline constexpr int kQuicklookLegendWidthPx = 122;
inline constexpr int kQuicklookLegendHeightPx = 104;

// The class map (shrunk by keeping the most restrictive class of each block, so no NO-GO cell
// vanishes from the overview; enlarged by pixel replication) with a legend panel on its right,
// as an ARGB32 surface (no data transparent).
CairoSurface RenderQuicklook(int width, int height, const std::vector<uint8_t>& go_class);

// Writes `surface` as a PNG file at `path`: RGB for a CAIRO_FORMAT_RGB24 surface (written by
// cairo), RGBA for CAIRO_FORMAT_ARGB32 (written by GDAL, because cairo's writer drops the alpha
// channel of an image that happens to be opaque, and the quicklook promises RGBA). The file
// appears complete or not at all: it is written as `path`.partial and renamed; on failure nothing
// is left. Throws std::runtime_error on failure.
void WritePngAtomically(cairo_surface_t* surface, const std::string& path);

}  // namespace gonogo::geo::internal
