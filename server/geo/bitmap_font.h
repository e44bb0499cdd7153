// A tiny 5x7 bitmap font for the quicklook legend and the line plots (internal). GDAL renders no
// text, and the products need only plain labels: letters, digits and a little punctuation.
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
// exist for A-Z, a-z, 0-9, space and . , - + = / ( ) % : _ '; any other character draws as a
// hollow box, so a missing glyph is visible rather than silently blank.
void DrawText(RgbaImage& image, int x, int y, const std::string& text, int scale, Rgba colour);

// Draws `text` turned 90 degrees counter-clockwise (reading bottom to top, as a y-axis label), in
// the box with top-left corner (x, y), kGlyphHeight * scale wide and TextWidthPx(text, scale) tall.
void DrawTextUp(RgbaImage& image, int x, int y, const std::string& text, int scale, Rgba colour);

}  // namespace gonogo::geo::internal
