// PNG quicklook of a go/no-go class map with a legend (internal).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gonogo::geo::internal {

struct Rgba {
  uint8_t r, g, b, a;
};

// Display colour of a class value (kClassNoGo red, kClassSlowGo amber, kClassGo green, anything
// else transparent). Shared by the COG colour table and the quicklook so they always agree.
Rgba ClassColour(uint8_t go_class);

// An RGBA image, row-major, 4 bytes per pixel.
struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // (height x width x 4)

  void Fill(int x, int y, int w, int h, Rgba colour);  // clipped to the image
};

// Size of the map part of the quicklook for a width x height grid: grids with a long side over
// 1024 cells are shrunk to 1024 px; grids under 256 cells are enlarged by a whole factor so that
// the legend stays readable beside them.
void QuicklookMapSize(int width, int height, int* map_width_px, int* map_height_px);

// The class map (shrunk by keeping the most restrictive class of each block, so no NO-GO cell
// vanishes from the overview; enlarged by pixel replication) with a legend panel on its right.
RgbaImage RenderQuicklook(int width, int height, const std::vector<uint8_t>& go_class);

// Writes `image` as a PNG file at `path`: RGBA, or RGB when `with_alpha` is false (opaque images
// such as plots then need no alpha channel). Throws std::runtime_error on failure.
void WritePng(const RgbaImage& image, const std::string& path, bool with_alpha = true);

}  // namespace gonogo::geo::internal
