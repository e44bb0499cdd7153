// A tiny 5x7 bitmap font for the quicklook legend (internal). GDAL renders no text, and the legend
// needs only a handful of characters: "GO", "SLOW-GO", "NO-GO", "no data".
#pragma once

#include <string>

#include "server/geo/quicklook.h"

namespace gonogo::geo::internal {

inline constexpr int kGlyphWidth = 5;   // pixels at scale 1
inline constexpr int kGlyphHeight = 7;  // pixels at scale 1
inline constexpr int kGlyphAdvance = kGlyphWidth + 1;

// Width in pixels of `text` drawn at `scale` (no trailing gap).
int TextWidthPx(const std::string& text, int scale);

// Draws `text` with its top-left corner at (x, y), each font pixel a scale x scale square. Glyphs
// exist for G L N O S W - space and a d n o t; any other character draws as a hollow box.
void DrawText(RgbaImage& image, int x, int y, const std::string& text, int scale, Rgba colour);

}  // namespace gonogo::geo::internal
