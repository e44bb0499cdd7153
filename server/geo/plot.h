// PNG line plots, e.g. traction coefficients against slip for several tyre scales: panels side by
// side, each with axes, numeric ticks, a title and axis labels, and one legend below them.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace gonogo::geo {

// One curve. Points are joined in the given order by 2 px lines; a point with a NaN (or infinite)
// coordinate is skipped and breaks the line there. A point with no finite neighbour is drawn as a
// 2 px dot, so it does not vanish.
struct PlotSeries {
  std::string label;         // legend text, e.g. "scale 0.5"; empty: left out of the legend
  std::vector<double> x, y;  // same length
  std::array<uint8_t, 3> rgb{0, 0, 0};
  bool dashed = false;
  bool markers = false;  // 5 x 5 px squares at the points
};

// A filled band between `lower` and `upper`, linear between points (e.g. one standard deviation
// around a mean curve). Drawn under every series of its panel; not in the legend. A point with a
// NaN value breaks the band.
struct PlotBand {
  std::vector<double> x, lower, upper;  // same length
  std::array<uint8_t, 3> rgb{200, 200, 200};
};

struct PlotPanel {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<PlotBand> bands;
  // Axis ranges; NaN = automatic from the finite data of the series and bands (4 % margin on each
  // side). Ticks fall on multiples of 1, 2, 2.5 or 5 times a power of ten, about six per axis.
  double x_min = NAN, x_max = NAN, y_min = NAN, y_max = NAN;
};

// Layout of one panel in pixels, relative to its top-left corner; panel i starts at column
// i * kPlotPanelWidthPx. Data x_min..x_max maps linearly onto the columns kPlotAreaLeftPx ..
// kPlotAreaLeftPx + kPlotAreaWidthPx - 1, and y_max..y_min onto the rows kPlotAreaTopPx ..
// kPlotAreaTopPx + kPlotAreaHeightPx - 1 (nearest pixel). Lines, markers and bands never leave this
// area; the axes frame lies just outside it.
inline constexpr int kPlotPanelWidthPx = 420;
inline constexpr int kPlotPanelHeightPx = 320;
inline constexpr int kPlotAreaLeftPx = 68;
inline constexpr int kPlotAreaTopPx = 32;
inline constexpr int kPlotAreaWidthPx = 336;
inline constexpr int kPlotAreaHeightPx = 240;
inline constexpr int kPlotMaxPanels = 16;

// Writes an opaque RGB PNG at `path`: the panels side by side (kPlotPanelWidthPx x
// kPlotPanelHeightPx each) and, below them, a legend of the first panel's labelled series (rows of
// 18 px plus 10 px of padding, wrapped to the image width; no legend and no extra height when no
// series of the first panel has a label). Drawn with cairo; text in DejaVu Sans: bold 15 px titles
// (shrunk to fit a panel, not below 12 px), 12 px axis labels and legend, 11 px tick labels, which
// are plain decimals. Lines, markers and bands are not antialiased: their pixels have exactly the
// series or band colour.
//
// The file appears complete or not at all (written under a temporary name, then renamed); the
// directory must exist. Throws InputError("plot", ...) for bad arguments: no panels or more than
// kPlotMaxPanels, x/y (or x/lower/upper) lengths that differ, an infinite axis bound,
// x_min >= x_max or y_min >= y_max, data too wide for a finite axis range, an empty path. Throws
// std::runtime_error when the file cannot be written.
void WritePlotPng(const std::vector<PlotPanel>& panels, const std::string& path);

}  // namespace gonogo::geo
