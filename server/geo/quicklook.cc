#include "server/geo/quicklook.h"

#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/geodesy.h"
#include "server/geo/products.h"

namespace gonogo::geo::internal {
namespace {

namespace fs = std::filesystem;

// Text (DejaVu Sans, em size in pixels); the title shrinks to fit the image, not below the minimum.
constexpr double kTitleFontPx = 18.0;
constexpr double kMinTitleFontPx = 10.0;
constexpr double kLegendFontPx = 14.0;
constexpr double kScaleFontPx = 12.0;
constexpr double kNorthFontPx = 16.0;

// Inside the panel column: legend label after its swatch; scale bar at most this long.
constexpr int kLegendTextGapPx = 8;
constexpr int kScaleBarMaxPx = kQuicklookPanelWidthPx - 24;
constexpr int kScaleBarThicknessPx = 8;
constexpr int kScaleBarSegments = 4;
constexpr int kNorthArrowWidthPx = 24;
constexpr int kNorthArrowLengthPx = 36;

constexpr Rgba kPageColour{255, 255, 255, 255};
constexpr Rgba kOutlineColour{64, 64, 64, 255};
constexpr Rgba kTextColour{0, 0, 0, 255};

struct LegendEntry {
  uint8_t go_class;
  const char* label;
};
constexpr LegendEntry kLegend[] = {
    {kClassGo, "GO"}, {kClassSlowGo, "SLOW-GO"}, {kClassNoGo, "NO-GO"}, {kClassNoData, "no data"}};
static_assert(sizeof(kLegend) / sizeof(kLegend[0]) == kQuicklookLegendRows);

// Colour of a class on the quicklook: the COG's colours, no data an opaque grey.
Rgba QuicklookColour(uint8_t go_class) {
  const Rgba c = ClassColour(go_class);
  return c.a == 0 ? kQuicklookNoDataColour : c;
}

void SetSource(cairo_t* cr, Rgba c) {
  cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, c.a / 255.0);
}

void FillRect(cairo_t* cr, int x, int y, int w, int h, Rgba c) {
  SetSource(cr, c);
  cairo_rectangle(cr, x, y, w, h);
  cairo_fill(cr);
}


// Size of the map for a width x height grid (see QuicklookLayout).
void MapSizePx(int width, int height, int* map_w, int* map_h) {
  const int long_side = std::max(width, height);
  if (long_side > kQuicklookMaxMapSidePx) {
    const double scale = static_cast<double>(kQuicklookMaxMapSidePx) / long_side;
    *map_w = std::max(1, static_cast<int>(width * scale + 0.5));
    *map_h = std::max(1, static_cast<int>(height * scale + 0.5));
    return;
  }
  const int factor = std::max(1, kQuicklookMaxMapSidePx / std::max(long_side, 1));
  *map_w = width * factor;
  *map_h = height * factor;
}

// Class per map pixel (map_w x map_h): each map pixel takes the minimum over the grid cells it
// covers, which is the most restrictive class (NO-GO 0 < SLOW-GO 1 < GO 2) and no data (255) only
// when every covered cell has none.
std::vector<uint8_t> ResampleClasses(int width, int height, const std::vector<uint8_t>& go_class,
                                     int map_w, int map_h) {
  std::vector<uint8_t> map(static_cast<size_t>(map_w) * map_h, kClassNoData);
  if (map_w >= width && map_h >= height) {
    // Enlarging by a whole factor: replicate each cell.
    const int factor = map_w / width;
    for (int y = 0; y < map_h; ++y) {
      const size_t src_row = static_cast<size_t>(y / factor) * width;
      for (int x = 0; x < map_w; ++x)
        map[static_cast<size_t>(y) * map_w + x] = go_class[src_row + x / factor];
    }
    return map;
  }
  std::vector<int> map_col(width);
  for (int col = 0; col < width; ++col) {
    map_col[col] = static_cast<int>(static_cast<int64_t>(col) * map_w / width);
  }
  for (int row = 0; row < height; ++row) {
    uint8_t* out = &map[static_cast<size_t>(static_cast<int64_t>(row) * map_h / height) * map_w];
    const uint8_t* in = &go_class[static_cast<size_t>(row) * width];
    for (int col = 0; col < width; ++col) out[map_col[col]] = std::min(out[map_col[col]], in[col]);
  }
  return map;
}

// Writes the classes straight into the surface's pixels at (x0, y0): one pixel per map cell, no
// resampling by cairo. Quicklook colours are opaque, so premultiplied equals straight.
void PutMap(cairo_surface_t* surface, const std::vector<uint8_t>& map, int x0, int y0, int map_w,
            int map_h) {
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < map_h; ++y) {
    auto* row = reinterpret_cast<uint32_t*>(data + static_cast<size_t>(y0 + y) * stride) + x0;
    for (int x = 0; x < map_w; ++x) {
      const Rgba c = QuicklookColour(map[static_cast<size_t>(y) * map_w + x]);
      // CAIRO_FORMAT_ARGB32: one native-endian 32-bit word per pixel, alpha in the top byte.
      row[x] = (uint32_t{c.a} << 24) | (uint32_t{c.r} << 16) | (uint32_t{c.g} << 8) | c.b;
    }
  }
  cairo_surface_mark_dirty(surface);
}

// One line of bold text at (x, baseline), shrunk to `room_px` if needed.
void DrawTitle(cairo_t* cr, const std::string& title, double x, double baseline, double room_px) {
  SelectFont(cr, kTitleFontPx, /*bold=*/true);
  const double width_px = TextWidthPx(cr, title);
  if (width_px > room_px) {
    SelectFont(cr, std::max(kMinTitleFontPx, kTitleFontPx * room_px / width_px), true);
  }
  SetSource(cr, kTextColour);
  cairo_move_to(cr, x, baseline);
  cairo_show_text(cr, title.c_str());
}

// Four rows of a swatch (outlined) and its label, the first swatch's top-left at (x0, y0).
void DrawLegendRows(cairo_t* cr, int x0, int y0) {
  SelectFont(cr, kLegendFontPx);
  const double cap_px = CapHeightPx(cr);
  for (int i = 0; i < kQuicklookLegendRows; ++i) {
    const int y = y0 + i * kQuicklookLegendRowPitchPx;
    FillRect(cr, x0, y, kQuicklookLegendSwatchPx, kQuicklookLegendSwatchPx, kOutlineColour);
    FillRect(cr, x0 + 1, y + 1, kQuicklookLegendSwatchPx - 2, kQuicklookLegendSwatchPx - 2,
             QuicklookColour(kLegend[i].go_class));
    SetSource(cr, kTextColour);
    cairo_move_to(cr, x0 + kQuicklookLegendSwatchPx + kLegendTextGapPx,
                  y + kQuicklookLegendSwatchPx / 2.0 + cap_px / 2.0);
    cairo_show_text(cr, kLegend[i].label);
  }
}

// An arrow pointing up (grid north; the grids are north-up) with an "N" under it, centred in its
// box at (x0, y0) of kQuicklookPanelWidthPx x kQuicklookNorthArrowHeightPx.
void DrawNorthArrow(cairo_t* cr, int x0, int y0) {
  const double centre_x = x0 + kNorthArrowWidthPx / 2.0;
  const double tip_y = y0 + 4.0;
  const double base_y = tip_y + kNorthArrowLengthPx;
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_GRAY);
  // Left half filled, right half outlined: the usual look, readable at a glance.
  cairo_move_to(cr, centre_x, tip_y);
  cairo_line_to(cr, centre_x - kNorthArrowWidthPx / 2.0, base_y);
  cairo_line_to(cr, centre_x, base_y - kNorthArrowLengthPx / 4.0);
  cairo_close_path(cr);
  SetSource(cr, kTextColour);
  cairo_fill(cr);
  cairo_move_to(cr, centre_x, tip_y);
  cairo_line_to(cr, centre_x + kNorthArrowWidthPx / 2.0, base_y);
  cairo_line_to(cr, centre_x, base_y - kNorthArrowLengthPx / 4.0);
  cairo_close_path(cr);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
  SelectFont(cr, kNorthFontPx, /*bold=*/true);
  const double n_width_px = TextWidthPx(cr, "N");
  cairo_move_to(cr, centre_x - n_width_px / 2.0, base_y + 4.0 + CapHeightPx(cr));
  cairo_show_text(cr, "N");
}

// The longest round distance (1, 2 or 5 times a power of ten metres) that fits in max_px.
double RoundScaleLengthM(double metres_per_px, int max_px) {
  const double max_m = metres_per_px * max_px;
  double step = std::pow(10.0, std::floor(std::log10(max_m)));
  for (const double factor : {5.0, 2.0, 1.0}) {
    if (factor * step <= max_m) return factor * step;
  }
  return step;
}

std::string DistanceLabel(double metres) {
  char text[32];
  if (metres >= 1000.0) {
    std::snprintf(text, sizeof text, "%g km", metres / 1000.0);
  } else {
    std::snprintf(text, sizeof text, "%g m", metres);
  }
  return text;
}

// A bar of alternating black and white segments, "0" under its left end and its length under the
// right end, in its box at (x0, y0).
void DrawScaleBar(cairo_t* cr, int x0, int y0, double metres_per_px) {
  const double length_m = RoundScaleLengthM(metres_per_px, kScaleBarMaxPx);
  const int length_px =
      std::max(kScaleBarSegments, static_cast<int>(length_m / metres_per_px + 0.5));
  const int bar_y = y0 + 8;
  FillRect(cr, x0, bar_y, length_px, kScaleBarThicknessPx, kTextColour);
  for (int i = 1; i < kScaleBarSegments; i += 2) {
    const int left = x0 + 1 + i * (length_px - 2) / kScaleBarSegments;
    const int right = x0 + 1 + (i + 1) * (length_px - 2) / kScaleBarSegments;
    FillRect(cr, left, bar_y + 1, right - left, kScaleBarThicknessPx - 2, kPageColour);
  }
  SelectFont(cr, kScaleFontPx);
  const double baseline = bar_y + kScaleBarThicknessPx + 4 + CapHeightPx(cr);
  SetSource(cr, kTextColour);
  cairo_move_to(cr, x0, baseline);
  cairo_show_text(cr, "0");
  const std::string label = DistanceLabel(length_m);
  cairo_move_to(cr, x0 + length_px - TextWidthPx(cr, label), baseline);
  cairo_show_text(cr, label.c_str());
}

// The straight (not premultiplied) RGBA bytes of an ARGB32 surface, row-major.
std::vector<uint8_t> StraightRgba(cairo_surface_t* surface, int width, int height) {
  cairo_surface_flush(surface);
  const unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  std::vector<uint8_t> rgba(static_cast<size_t>(width) * height * 4);
  for (int y = 0; y < height; ++y) {
    const auto* row = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < width; ++x) {
      const uint32_t p = row[x];
      const uint32_t a = p >> 24;
      uint8_t* out = &rgba[(static_cast<size_t>(y) * width + x) * 4];
      for (int channel = 0; channel < 3; ++channel) {
        const uint32_t premultiplied = (p >> (16 - 8 * channel)) & 0xff;
        out[channel] = a == 0 ? 0 : static_cast<uint8_t>((premultiplied * 255 + a / 2) / a);
      }
      out[3] = static_cast<uint8_t>(a);
    }
  }
  return rgba;
}

// RGBA PNG through GDAL's PNG driver, which always keeps the alpha band.
void WriteRgbaPng(cairo_surface_t* surface, const std::string& path) {
  EnsureGdalRegistered();
  GdalErrorScope gdal_errors;
  const int width = cairo_image_surface_get_width(surface);
  const int height = cairo_image_surface_get_height(surface);
  std::vector<uint8_t> rgba = StraightRgba(surface, width, height);
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* png = GetGDALDriverManager()->GetDriverByName("PNG");
  if (mem == nullptr || png == nullptr) throw std::runtime_error("GDAL MEM or PNG driver missing");
  GDALDatasetUniquePtr pixels(mem->Create("", width, height, 4, GDT_Byte, nullptr));
  if (pixels == nullptr) throw std::runtime_error("cannot create the PNG image in memory");
  const CPLErr written =
      pixels->RasterIO(GF_Write, 0, 0, width, height, rgba.data(), width, height, GDT_Byte, 4,
                       nullptr, 4, 4 * static_cast<GSpacing>(width), 1, nullptr);
  if (written != CE_None) throw std::runtime_error("cannot fill the PNG image in memory");
  pixels->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand);
  const char* const options[] = {"ZLEVEL=6", nullptr};
  GDALDatasetUniquePtr out(png->CreateCopy(path.c_str(), pixels.get(), FALSE,
                                           const_cast<char**>(options), nullptr, nullptr));
  if (out == nullptr) {
    throw std::runtime_error("cannot write " + path + ": " + GdalErrorScope::LastMessage());
  }
}

void WritePng(cairo_surface_t* surface, const std::string& path) {
  if (cairo_image_surface_get_format(surface) == CAIRO_FORMAT_ARGB32) {
    WriteRgbaPng(surface, path);
    return;
  }
  const cairo_status_t status = cairo_surface_write_to_png(surface, path.c_str());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("cannot write " + path + ": " + cairo_status_to_string(status));
  }
}

}  // namespace

double TextWidthPx(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

double CapHeightPx(cairo_t* cr) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, "H", &extents);
  return -extents.y_bearing;
}

Rgba ClassColour(uint8_t go_class) {
  switch (go_class) {
    case kClassNoGo:
      return {215, 25, 28, 255};  // red
    case kClassSlowGo:
      return {255, 176, 0, 255};  // amber
    case kClassGo:
      return {26, 150, 65, 255};  // green
    default:
      return {0, 0, 0, 0};  // transparent
  }
}

CairoSurface NewImageSurface(cairo_format_t format, int width, int height) {
  CairoSurface surface(cairo_image_surface_create(format, width, height));
  const cairo_status_t status = cairo_surface_status(surface.get());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("cannot create a " + std::to_string(width) + " x " +
                             std::to_string(height) +
                             " px image: " + cairo_status_to_string(status));
  }
  return surface;
}

CairoContext NewContext(cairo_surface_t* surface) {
  CairoContext cr(cairo_create(surface));
  const cairo_status_t status = cairo_status(cr.get());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cannot draw: ") + cairo_status_to_string(status));
  }
  return cr;
}

void SelectFont(cairo_t* cr, double size_px, bool bold) {
  cairo_select_font_face(cr, kFontFamily, CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size_px);
  // Greyscale antialiasing (no colour fringes from subpixel rendering) and slight hinting, so
  // small text is sharp but keeps its shapes, whatever the machine's fontconfig says.
  cairo_font_options_t* options = cairo_font_options_create();
  cairo_font_options_set_antialias(options, CAIRO_ANTIALIAS_GRAY);
  cairo_font_options_set_hint_style(options, CAIRO_HINT_STYLE_SLIGHT);
  cairo_font_options_set_hint_metrics(options, CAIRO_HINT_METRICS_ON);
  cairo_set_font_options(cr, options);
  cairo_font_options_destroy(options);
}

QuicklookLayout QuicklookLayoutFor(int grid_width, int grid_height) {
  QuicklookLayout l;
  MapSizePx(grid_width, grid_height, &l.map_width_px, &l.map_height_px);
  l.map_x_px = kQuicklookMarginPx;
  l.map_y_px = kQuicklookTitleBandPx;
  l.panel_x_px = l.map_x_px + l.map_width_px + kQuicklookMarginPx;
  l.legend_y_px = l.map_y_px;
  l.north_arrow_y_px = l.legend_y_px + kQuicklookLegendRows * kQuicklookLegendRowPitchPx + 12;
  l.scale_bar_y_px = l.north_arrow_y_px + kQuicklookNorthArrowHeightPx;
  const int panel_bottom_px = l.scale_bar_y_px + kQuicklookScaleBarHeightPx;
  l.image_width_px = l.panel_x_px + kQuicklookPanelWidthPx;
  l.image_height_px = std::max(l.map_y_px + l.map_height_px, panel_bottom_px) + kQuicklookMarginPx;
  return l;
}

CairoSurface RenderQuicklook(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::string& title) {
  const QuicklookLayout l = QuicklookLayoutFor(grid.width, grid.height);
  CairoSurface surface = NewImageSurface(CAIRO_FORMAT_ARGB32, l.image_width_px, l.image_height_px);
  CairoContext cr = NewContext(surface.get());
  FillRect(cr.get(), 0, 0, l.image_width_px, l.image_height_px, kPageColour);
  cairo_surface_flush(surface.get());
  PutMap(surface.get(),
         ResampleClasses(grid.width, grid.height, go_class, l.map_width_px, l.map_height_px),
         l.map_x_px, l.map_y_px, l.map_width_px, l.map_height_px);
  DrawTitle(cr.get(), title, kQuicklookMarginPx, kQuicklookTitleBandPx - 14,
            l.image_width_px - 2 * kQuicklookMarginPx);
  DrawLegendRows(cr.get(), l.panel_x_px, l.legend_y_px);
  DrawNorthArrow(cr.get(), l.panel_x_px, l.north_arrow_y_px);
  // Ground metres per map pixel along the middle row (a geographic grid's cells narrow towards
  // the poles; the middle row is the fair average for a map that is not continental).
  const double metres_per_px =
      CellSizeAtRow(grid, grid.height / 2).dx_m * grid.width / l.map_width_px;
  DrawScaleBar(cr.get(), l.panel_x_px, l.scale_bar_y_px, metres_per_px);
  return surface;
}

CairoSurface RenderLegendPanel(const std::string& title) {
  constexpr int kWidthPx = 220;
  constexpr int kTitleBandPx = 34;
  const int height_px =
      kTitleBandPx + kQuicklookLegendRows * kQuicklookLegendRowPitchPx + kQuicklookMarginPx / 2;
  CairoSurface surface = NewImageSurface(CAIRO_FORMAT_RGB24, kWidthPx, height_px);
  CairoContext cr = NewContext(surface.get());
  FillRect(cr.get(), 0, 0, kWidthPx, height_px, kPageColour);
  FillRect(cr.get(), 0, 0, kWidthPx, 1, kOutlineColour);
  FillRect(cr.get(), 0, height_px - 1, kWidthPx, 1, kOutlineColour);
  FillRect(cr.get(), 0, 0, 1, height_px, kOutlineColour);
  FillRect(cr.get(), kWidthPx - 1, 0, 1, height_px, kOutlineColour);
  DrawTitle(cr.get(), title, kQuicklookMarginPx, kTitleBandPx - 12,
            kWidthPx - 2 * kQuicklookMarginPx);
  DrawLegendRows(cr.get(), kQuicklookMarginPx, kTitleBandPx);
  return surface;
}

std::string EncodePng(cairo_surface_t* surface) {
  std::string bytes;
  const cairo_status_t status = cairo_surface_write_to_png_stream(
      surface,
      [](void* closure, const unsigned char* data, unsigned int length) {
        static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
        return CAIRO_STATUS_SUCCESS;
      },
      &bytes);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cannot encode a PNG: ") + cairo_status_to_string(status));
  }
  return bytes;
}

void WritePngAtomically(cairo_surface_t* surface, const std::string& path) {
  const std::string partial = path + ".partial";
  try {
    WritePng(surface, partial);
  } catch (...) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw;
  }
  std::error_code renamed;
  fs::rename(partial, path, renamed);
  if (renamed) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw std::runtime_error("cannot write " + path + ": " + renamed.message());
  }
}

}  // namespace gonogo::geo::internal
