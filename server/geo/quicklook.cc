#include "server/geo/quicklook.h"

#include <gdal_priv.h>

#include <algorithm>
#include <stdexcept>

#include "server/geo/bitmap_font.h"
#include "server/geo/gdal_util.h"
#include "server/geo/products.h"

namespace gonogo::geo::internal {
namespace {

constexpr int kMaxMapSidePx = 1024;
constexpr int kMinMapSidePx = 256;

// Legend layout in pixels: text at twice the font size, one row per class.
constexpr int kLegendScale = 2;
constexpr int kLegendMarginPx = 8;
constexpr int kLegendBoxPx = 16;
constexpr int kLegendRowPitchPx = 24;

constexpr Rgba kTransparent{0, 0, 0, 0};
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

int LegendWidthPx() {
  int text_px = 0;
  for (const LegendEntry& entry : kLegend) {
    text_px = std::max(text_px, TextWidthPx(entry.label, kLegendScale));
  }
  return kLegendMarginPx + kLegendBoxPx + kLegendMarginPx + text_px + kLegendMarginPx;
}

int LegendHeightPx() { return kLegendMarginPx + kLegendRows * kLegendRowPitchPx; }

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

void DrawLegend(RgbaImage& image, int x0) {
  image.Fill(x0, 0, image.width - x0, image.height, kPanelColour);
  for (int i = 0; i < kLegendRows; ++i) {
    const int y = kLegendMarginPx + i * kLegendRowPitchPx;
    const int box_x = x0 + kLegendMarginPx;
    image.Fill(box_x, y, kLegendBoxPx, kLegendBoxPx, kOutlineColour);
    // No data is transparent on the map; over the white panel its swatch is white in an outline.
    const Rgba swatch =
        kLegend[i].go_class == kClassNoData ? kPanelColour : ClassColour(kLegend[i].go_class);
    image.Fill(box_x + 1, y + 1, kLegendBoxPx - 2, kLegendBoxPx - 2, swatch);
    const int text_y = y + (kLegendBoxPx - kGlyphHeight * kLegendScale) / 2;
    DrawText(image, box_x + kLegendBoxPx + kLegendMarginPx, text_y, kLegend[i].label, kLegendScale,
             kTextColour);
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
      return kTransparent;
  }
}

void RgbaImage::Fill(int x, int y, int w, int h, Rgba colour) {
  const int x_end = std::min(width, x + w), y_end = std::min(height, y + h);
  for (int row = std::max(0, y); row < y_end; ++row) {
    for (int col = std::max(0, x); col < x_end; ++col) {
      uint8_t* p = &pixels[(static_cast<size_t>(row) * width + col) * 4];
      p[0] = colour.r;
      p[1] = colour.g;
      p[2] = colour.b;
      p[3] = colour.a;
    }
  }
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

RgbaImage RenderQuicklook(int width, int height, const std::vector<uint8_t>& go_class) {
  int map_w = 0, map_h = 0;
  QuicklookMapSize(width, height, &map_w, &map_h);
  RgbaImage image;
  image.width = map_w + LegendWidthPx();
  image.height = std::max(map_h, LegendHeightPx());
  image.pixels.assign(static_cast<size_t>(image.width) * image.height * 4, 0);  // transparent

  const std::vector<uint8_t> map = ResampleClasses(width, height, go_class, map_w, map_h);
  for (int y = 0; y < map_h; ++y) {
    for (int x = 0; x < map_w; ++x) {
      const Rgba c = ClassColour(map[static_cast<size_t>(y) * map_w + x]);
      uint8_t* p = &image.pixels[(static_cast<size_t>(y) * image.width + x) * 4];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
      p[3] = c.a;
    }
  }
  DrawLegend(image, map_w);
  return image;
}

void WritePng(const RgbaImage& image, const std::string& path, bool with_alpha) {
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* png = GetGDALDriverManager()->GetDriverByName("PNG");
  if (mem == nullptr || png == nullptr) throw std::runtime_error("GDAL MEM or PNG driver missing");
  const int bands = with_alpha ? 4 : 3;
  GDALDatasetUniquePtr pixels(mem->Create("", image.width, image.height, bands, GDT_Byte, nullptr));
  if (pixels == nullptr) throw std::runtime_error("cannot create the PNG image in memory");
  // One call for all bands of the pixel-interleaved buffer (RGB takes the first three bytes of
  // each pixel's four).
  const CPLErr written = pixels->RasterIO(GF_Write, 0, 0, image.width, image.height,
                                          const_cast<uint8_t*>(image.pixels.data()), image.width,
                                          image.height, GDT_Byte, bands, nullptr, 4,
                                          4 * static_cast<GSpacing>(image.width), 1, nullptr);
  if (written != CE_None) throw std::runtime_error("cannot fill the PNG image in memory");
  if (with_alpha) pixels->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand);
  const char* const options[] = {"ZLEVEL=6", nullptr};
  GDALDatasetUniquePtr out(png->CreateCopy(path.c_str(), pixels.get(), FALSE,
                                           const_cast<char**>(options), nullptr, nullptr));
  if (out == nullptr) {
    throw std::runtime_error("cannot write " + path + ": " + GdalErrorScope::LastMessage());
  }
}

}  // namespace gonogo::geo::internal
