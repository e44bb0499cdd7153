#include "server/geo/quicklook.h"

#include <gdal_priv.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/products.h"

namespace gonogo::geo::internal {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxMapSidePx = 1024;
constexpr int kMinMapSidePx = 256;

// Legend layout in pixels: one row per class, a swatch and its label.
constexpr int kLegendMarginPx = 8;
constexpr int kLegendBoxPx = 16;
constexpr int kLegendRowPitchPx = 24;
constexpr double kLegendFontPx = 14.0;  // shrunk only if a label would not fit the panel

constexpr Rgba kPanelColour{255, 255, 255, 255};
constexpr Rgba kOutlineColour{64, 64, 64, 255};
constexpr Rgba kTextColour{0, 0, 0, 255};

struct LegendEntry {
  uint8_t go_class;
  const char* label;
};
constexpr LegendEntry kLegend[] = {
    {kClassGo, "GO"}, {kClassSlowGo, "SLOW-GO"}, {kClassNoGo, "NO-GO"}, {kClassNoData, "no data"}};
constexpr int kLegendRows = sizeof(kLegend) / sizeof(kLegend[0]);
static_assert(kLegendMarginPx + kLegendRows * kLegendRowPitchPx == kQuicklookLegendHeightPx);

void SetSource(cairo_t* cr, Rgba c) {
  cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, c.a / 255.0);
}

void FillRect(cairo_t* cr, int x, int y, int w, int h, Rgba c) {
  SetSource(cr, c);
  cairo_rectangle(cr, x, y, w, h);
  cairo_fill(cr);
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

// Writes the classes straight into the surface's pixels: one pixel per map cell, no resampling
// by cairo. Class colours are opaque or fully transparent, so premultiplied equals straight.
void PutMap(cairo_surface_t* surface, const std::vector<uint8_t>& map, int map_w, int map_h) {
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < map_h; ++y) {
    auto* row = reinterpret_cast<uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < map_w; ++x) {
      const Rgba c = ClassColour(map[static_cast<size_t>(y) * map_w + x]);
      // CAIRO_FORMAT_ARGB32: one native-endian 32-bit word per pixel, alpha in the top byte.
      row[x] = (uint32_t{c.a} << 24) | (uint32_t{c.r} << 16) | (uint32_t{c.g} << 8) | c.b;
    }
  }
  cairo_surface_mark_dirty(surface);
}

// The white legend panel over the strip right of the map: a swatch and a label per class.
void DrawLegend(cairo_t* cr, int x0, int image_width, int image_height) {
  FillRect(cr, x0, 0, image_width - x0, image_height, kPanelColour);
  const int text_x = x0 + kLegendMarginPx + kLegendBoxPx + kLegendMarginPx;
  const double room_px = kQuicklookLegendWidthPx - (text_x - x0) - kLegendMarginPx;
  SelectFont(cr, kLegendFontPx);
  double widest_px = 0.0;
  for (const LegendEntry& entry : kLegend) {
    cairo_text_extents_t extents;
    cairo_text_extents(cr, entry.label, &extents);
    widest_px = std::max(widest_px, extents.x_advance);
  }
  if (widest_px > room_px) SelectFont(cr, kLegendFontPx * room_px / widest_px);
  cairo_text_extents_t capital;
  cairo_text_extents(cr, "H", &capital);  // centres the capitals on their swatch
  for (int i = 0; i < kLegendRows; ++i) {
    const int y = kLegendMarginPx + i * kLegendRowPitchPx;
    const int box_x = x0 + kLegendMarginPx;
    FillRect(cr, box_x, y, kLegendBoxPx, kLegendBoxPx, kOutlineColour);
    // No data is transparent on the map; over the white panel its swatch is white in an outline.
    const Rgba swatch =
        kLegend[i].go_class == kClassNoData ? kPanelColour : ClassColour(kLegend[i].go_class);
    FillRect(cr, box_x + 1, y + 1, kLegendBoxPx - 2, kLegendBoxPx - 2, swatch);
    SetSource(cr, kTextColour);
    cairo_move_to(cr, text_x, y + kLegendBoxPx / 2.0 + capital.height / 2.0);
    cairo_show_text(cr, kLegend[i].label);
  }
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

void QuicklookMapSize(int width, int height, int* map_width_px, int* map_height_px) {
  const int long_side = std::max(width, height);
  if (long_side > kMaxMapSidePx) {
    const double scale = static_cast<double>(kMaxMapSidePx) / long_side;
    *map_width_px = std::max(1, static_cast<int>(width * scale + 0.5));
    *map_height_px = std::max(1, static_cast<int>(height * scale + 0.5));
    return;
  }
  const int factor = std::max(1, kMinMapSidePx / std::max(long_side, 1));
  *map_width_px = width * factor;
  *map_height_px = height * factor;
}

CairoSurface RenderQuicklook(int width, int height, const std::vector<uint8_t>& go_class) {
  int map_w = 0, map_h = 0;
  QuicklookMapSize(width, height, &map_w, &map_h);
  const int image_w = map_w + kQuicklookLegendWidthPx;
  const int image_h = std::max(map_h, kQuicklookLegendHeightPx);
  CairoSurface surface = NewImageSurface(CAIRO_FORMAT_ARGB32, image_w, image_h);  // transparent
  PutMap(surface.get(), ResampleClasses(width, height, go_class, map_w, map_h), map_w, map_h);
  CairoContext cr = NewContext(surface.get());
  DrawLegend(cr.get(), map_w, image_w, image_h);
  return surface;
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
