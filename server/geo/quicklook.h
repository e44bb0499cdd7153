// PNG quicklook of a go/no-go class map (title, legend, north arrow, scale bar), and the cairo
// plumbing the line plots (plot.cc) share with it: owning handles, the font, the atomic PNG write
// (internal).
#pragma once

#include <cairo.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

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
// Advance width of `text` in pixels at the current font.
double TextWidthPx(cairo_t* cr, const std::string& text);
// Height of a capital above the baseline at the current font: text is placed by its capitals, so
// labels with and without descenders line up.
double CapHeightPx(cairo_t* cr);

// Layout of the quicklook in pixels, from the top-left corner of the image:
//
//   +--------------------------------------------------+
//   | title (bold, one line)                           |
//   | +--------------------------+  legend (4 rows)    |
//   | | map                      |  north arrow        |
//   | |                          |  scale bar          |
//   | +--------------------------+                     |
//   +--------------------------------------------------+
//
// The map keeps the grid's shape: a grid with a long side over kQuicklookMaxMapSidePx cells is
// shrunk to that many pixels; a smaller one is enlarged by the largest whole factor that keeps it
// within that size, so even a 10 x 5 grid is drawn about 1000 px wide.
struct QuicklookLayout {
  int image_width_px = 0, image_height_px = 0;
  int map_x_px = 0, map_y_px = 0, map_width_px = 0, map_height_px = 0;
  int panel_x_px = 0;        // left edge of the legend, north arrow and scale bar column
  int legend_y_px = 0;       // top of the first legend row
  int north_arrow_y_px = 0;  // top of the north arrow's box (kQuicklookNorthArrowHeightPx tall)
  int scale_bar_y_px = 0;    // top of the scale bar's box (kQuicklookScaleBarHeightPx tall)
};
inline constexpr int kQuicklookMaxMapSidePx = 1024;
inline constexpr int kQuicklookMarginPx = 12;
inline constexpr int kQuicklookTitleBandPx = 40;  // the title line above the map
inline constexpr int kQuicklookPanelWidthPx = 168;
inline constexpr int kQuicklookLegendSwatchPx = 16;  // at panel_x, legend_y + row * pitch
inline constexpr int kQuicklookLegendRowPitchPx = 24;
inline constexpr int kQuicklookNorthArrowHeightPx = 64;
inline constexpr int kQuicklookScaleBarHeightPx = 44;
QuicklookLayout QuicklookLayoutFor(int grid_width, int grid_height);

// Legend rows top to bottom: GO, SLOW-GO, NO-GO, no data. On the quicklook no data is drawn in
// kQuicklookNoDataColour (an opaque light grey), so the picture reads the same on any background.
inline constexpr int kQuicklookLegendRows = 4;
inline constexpr Rgba kQuicklookNoDataColour{224, 224, 224, 255};

// The quicklook of a class map on `grid` (layout above), opaque: a white page, the title, the
// classes (shrunk by keeping the most restrictive class of each block, so no NO-GO cell vanishes;
// enlarged by pixel replication), the legend, a north arrow (grid north: up) and a scale bar whose
// length is a round number of metres or kilometres measured along the middle row of the grid.
CairoSurface RenderQuicklook(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::string& title);

// The legend alone (title above the four rows) on a white panel, for the KMZ's screen overlay.
CairoSurface RenderLegendPanel(const std::string& title);

// The PNG bytes of an image surface, as cairo encodes them (RGB or RGBA).
std::string EncodePng(cairo_surface_t* surface);

// Writes `surface` as a PNG file at `path`: RGB for a CAIRO_FORMAT_RGB24 surface (written by
// cairo), RGBA for CAIRO_FORMAT_ARGB32 (written by GDAL, because cairo's writer drops the alpha
// channel of an image that happens to be opaque, and the quicklook promises RGBA). The file
// appears complete or not at all: it is written as `path`.partial and renamed; on failure nothing
// is left. Throws std::runtime_error on failure.
void WritePngAtomically(cairo_surface_t* surface, const std::string& path);

}  // namespace gonogo::geo::internal
