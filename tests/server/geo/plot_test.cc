// WritePlotPng: image size for one and three panels, data confined to the plot area, points at the
// pixels the documented layout gives, NaN breaks, dashes, bands, round ticks, legend, text set in
// an antialiased outline font, and argument checks.
//
// Data lines, markers and bands are drawn without antialiasing (plot.cc), so the tests find them by
// their exact colour and at exact pixels. Text is antialiased, so it is found by dark pixels rather
// than pure black.
//
// To look at a realistic plot: GONOGO_PLOT_SAMPLE=/tmp/plot.png
// build/tests/server/geo/geo_plot_test
#include "server/geo/plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "tests/server/geo/test_rasters.h"

namespace gonogo::geo {
namespace {

using fixtures::OpenForCheck;
using fixtures::TempDir;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::array<uint8_t, 3> kProbe{10, 200, 250};  // used by nothing the plot draws itself

// Height of an image whose legend takes one row: 2 + 18 + 8 px below the panels.
constexpr int kOneLegendRowHeightPx = kPlotPanelHeightPx + 28;

// The RGB pixels of a PNG written by WritePlotPng.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // (height x width x 3)

  bool Is(int x, int y, const std::array<uint8_t, 3>& c) const {
    const uint8_t* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
    return p[0] == c[0] && p[1] == c[1] && p[2] == c[2];
  }
  // Ink of black text: a grey no lighter than 96 (antialiased glyphs are black only at their core).
  bool IsDark(int x, int y) const {
    const uint8_t* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
    return p[0] == p[1] && p[1] == p[2] && p[0] < 96;
  }
  // An antialiased edge of black text: a grey between ink and the white background.
  bool IsGreyEdge(int x, int y) const {
    const uint8_t* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
    return p[0] == p[1] && p[1] == p[2] && p[0] >= 96 && p[0] < 224;
  }
};

RgbImage ReadPng(const std::string& path) {
  RgbImage image;
  auto ds = OpenForCheck(path);
  EXPECT_NE(ds, nullptr) << path;
  if (ds == nullptr) return image;
  EXPECT_STREQ(ds->GetDriver()->GetDescription(), "PNG");
  EXPECT_EQ(ds->GetRasterCount(), 3);
  image.width = ds->GetRasterXSize();
  image.height = ds->GetRasterYSize();
  image.rgb.resize(static_cast<size_t>(image.width) * image.height * 3);
  EXPECT_EQ(ds->RasterIO(GF_Read, 0, 0, image.width, image.height, image.rgb.data(), image.width,
                         image.height, GDT_Byte, 3, nullptr, 3, 3 * image.width, 1, nullptr),
            CE_None);
  return image;
}

// Plot area of panel `panel` in image pixels, [left, right) x [top, bottom).
struct Area {
  int left, top, right, bottom;
  bool Contains(int x, int y) const { return x >= left && x < right && y >= top && y < bottom; }
};

Area PlotArea(int panel) {
  const int left = panel * kPlotPanelWidthPx + kPlotAreaLeftPx;
  return {left, kPlotAreaTopPx, left + kPlotAreaWidthPx, kPlotAreaTopPx + kPlotAreaHeightPx};
}

// Expected pixel of data (x, y) on axes [x0, x1] x [y0, y1] in panel `panel`, per plot.h.
double ColOf(int panel, double x, double x0, double x1) {
  return PlotArea(panel).left + (x - x0) / (x1 - x0) * (kPlotAreaWidthPx - 1);
}
double RowOf(double y, double y0, double y1) {
  return kPlotAreaTopPx + (y1 - y) / (y1 - y0) * (kPlotAreaHeightPx - 1);
}

PlotPanel FixedPanel(double x0, double x1, double y0, double y1) {
  PlotPanel panel;
  panel.title = "Drawbar pull";
  panel.x_label = "slip";
  panel.y_label = "D/W";
  panel.x_min = x0;
  panel.x_max = x1;
  panel.y_min = y0;
  panel.y_max = y1;
  return panel;
}

PlotSeries Series(std::vector<double> x, std::vector<double> y, std::array<uint8_t, 3> rgb,
                  std::string label = "") {
  PlotSeries s;
  s.label = std::move(label);
  s.x = std::move(x);
  s.y = std::move(y);
  s.rgb = rgb;
  return s;
}

// Bounding box of the dark pixels in [x0, x1) x [y0, y1), and how many there are.
struct Ink {
  int count = 0, left = 1 << 30, top = 1 << 30, right = -1, bottom = -1;  // right, bottom inclusive
  int Width() const { return right - left + 1; }
  int Height() const { return bottom - top + 1; }
};

Ink InkIn(const RgbImage& image, int x0, int y0, int x1, int y1) {
  Ink ink;
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x) {
      if (!image.IsDark(x, y)) continue;
      ++ink.count;
      ink.left = std::min(ink.left, x);
      ink.right = std::max(ink.right, x);
      ink.top = std::min(ink.top, y);
      ink.bottom = std::max(ink.bottom, y);
    }
  }
  return ink;
}

int CountGreyEdges(const RgbImage& image, int x0, int y0, int x1, int y1) {
  int count = 0;
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x) {
      count += image.IsGreyEdge(x, y);
    }
  }
  return count;
}

int CountColour(const RgbImage& image, const std::array<uint8_t, 3>& c, int x0, int y0, int x1,
                int y1) {
  int count = 0;
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x) count += image.Is(x, y, c);
  }
  return count;
}

TEST(WritePlotPng, SizeForOneAndThreePanels) {
  TempDir dir("geo_plot");
  PlotPanel panel = FixedPanel(0, 1, 0, 1);
  panel.series.push_back(Series({0, 1}, {0, 1}, {0, 0, 255}, "scale 1.0"));
  for (int n : {1, 3}) {
    const std::string path = dir.path() + "/plot" + std::to_string(n) + ".png";
    WritePlotPng(std::vector<PlotPanel>(n, panel), path);
    const RgbImage image = ReadPng(path);
    EXPECT_EQ(image.width, n * kPlotPanelWidthPx);
    EXPECT_EQ(image.height, kOneLegendRowHeightPx);
    EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  }
  // No labelled series in the first panel: no legend, no extra height.
  panel.series[0].label.clear();
  const std::string path = dir.path() + "/bare.png";
  WritePlotPng({panel}, path);
  EXPECT_EQ(ReadPng(path).height, kPlotPanelHeightPx);
}

TEST(WritePlotPng, SeriesStaysInsideItsPlotArea) {
  TempDir dir("geo_plot");
  // The middle panel's curve runs far beyond its axes on every side; markers at every point.
  std::vector<PlotPanel> panels(3, FixedPanel(0, 1, 0, 1));
  std::vector<double> x, y;
  for (int i = -40; i <= 80; ++i) {
    x.push_back(i / 40.0);
    y.push_back(3.0 * std::sin(i / 5.0));
  }
  panels[1].series.push_back(Series(x, y, kProbe));
  panels[1].series.back().markers = true;
  panels[1].series.push_back(Series({-1e9, 1e9}, {-1e9, 1e9}, kProbe));  // the diagonal
  // Ends beyond any pixel coordinate: clipped in data space, so nothing overflows.
  panels[1].series.push_back(Series({-1e300, 1e300}, {1e300, -1e300}, kProbe));
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng(panels, path);
  const RgbImage image = ReadPng(path);
  const Area area = PlotArea(1);
  int inside = 0, outside = 0;
  for (int py = 0; py < image.height; ++py) {
    for (int px = 0; px < image.width; ++px) {
      if (image.Is(px, py, kProbe)) ++(area.Contains(px, py) ? inside : outside);
    }
  }
  EXPECT_GT(inside, 500);
  EXPECT_EQ(outside, 0);
  // The long diagonal crosses the area from corner to corner.
  EXPECT_TRUE(image.Is(area.left, area.bottom - 1, kProbe));
  EXPECT_TRUE(image.Is(area.right - 1, area.top, kProbe));
}

TEST(WritePlotPng, PointsLandAtTheirPixels) {
  TempDir dir("geo_plot");
  // Two panels with different fixed ranges; one marker each at known data coordinates.
  std::vector<PlotPanel> panels = {FixedPanel(0, 10, -1, 1), FixedPanel(-0.5, 0.25, 100, 400)};
  panels[0].series.push_back(Series({2.5}, {0.5}, kProbe));
  panels[1].series.push_back(Series({0.1}, {130}, kProbe));
  for (PlotPanel& p : panels) p.series[0].markers = true;
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng(panels, path);
  const RgbImage image = ReadPng(path);

  const double expected_col[] = {ColOf(0, 2.5, 0, 10), ColOf(1, 0.1, -0.5, 0.25)};
  const double expected_row[] = {RowOf(0.5, -1, 1), RowOf(130, 100, 400)};
  for (int panel = 0; panel < 2; ++panel) {
    const Area area = PlotArea(panel);
    double sum_x = 0, sum_y = 0;
    int n = 0;
    for (int py = area.top; py < area.bottom; ++py) {
      for (int px = area.left; px < area.right; ++px) {
        if (!image.Is(px, py, kProbe)) continue;
        sum_x += px;
        sum_y += py;
        ++n;
      }
    }
    ASSERT_EQ(n, 25) << "a 5 x 5 marker in panel " << panel;
    EXPECT_NEAR(sum_x / n, expected_col[panel], 2.0) << "panel " << panel;
    EXPECT_NEAR(sum_y / n, expected_row[panel], 2.0) << "panel " << panel;
  }
}

TEST(WritePlotPng, LineEndsAtItsDataCorners) {
  TempDir dir("geo_plot");
  PlotPanel panel = FixedPanel(0, 2, 0, 4);
  panel.series.push_back(Series({0.5, 1.5}, {1, 3}, kProbe));
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng({panel}, path);
  const RgbImage image = ReadPng(path);
  const int c0 = std::lround(ColOf(0, 0.5, 0, 2)), r0 = std::lround(RowOf(1, 0, 4));
  const int c1 = std::lround(ColOf(0, 1.5, 0, 2)), r1 = std::lround(RowOf(3, 0, 4));
  EXPECT_TRUE(image.Is(c0, r0, kProbe));
  EXPECT_TRUE(image.Is(c1, r1, kProbe));
  // Nothing beyond the end points.
  EXPECT_EQ(CountColour(image, kProbe, 0, 0, c0 - 2, image.height), 0);
  EXPECT_EQ(CountColour(image, kProbe, c1 + 3, 0, image.width, image.height), 0);
}

TEST(WritePlotPng, NanPointsBreakTheLine) {
  TempDir dir("geo_plot");
  // y = 0.5 at x = 0..10, with y NaN at x = 5 in one series and x NaN at x = 5 in the other.
  std::vector<PlotPanel> panels(2, FixedPanel(0, 10, 0, 1));
  std::vector<double> x, y;
  for (int i = 0; i <= 10; ++i) {
    x.push_back(i);
    y.push_back(0.5);
  }
  std::vector<double> y_gap = y, x_gap = x;
  y_gap[5] = kNaN;
  x_gap[5] = kNaN;
  panels[0].series.push_back(Series(x, y_gap, kProbe));
  panels[1].series.push_back(Series(x_gap, y, kProbe));
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng(panels, path);
  const RgbImage image = ReadPng(path);
  for (int panel = 0; panel < 2; ++panel) {
    const Area area = PlotArea(panel);
    // Between x = 4 and x = 6 the line is absent (a 2 px pen may reach one pixel past a point).
    const int gap_begin = std::lround(ColOf(panel, 4, 0, 10)) + 3;
    const int gap_end = std::lround(ColOf(panel, 6, 0, 10)) - 2;
    EXPECT_EQ(CountColour(image, kProbe, gap_begin, area.top, gap_end, area.bottom), 0)
        << "panel " << panel;
    // Elsewhere it is there: both neighbouring pieces are drawn.
    const int row = std::lround(RowOf(0.5, 0, 1));
    EXPECT_TRUE(image.Is(std::lround(ColOf(panel, 2, 0, 10)), row, kProbe)) << "panel " << panel;
    EXPECT_TRUE(image.Is(std::lround(ColOf(panel, 8, 0, 10)), row, kProbe)) << "panel " << panel;
  }
}

TEST(WritePlotPng, DashedLineHasGapsSolidLineNone) {
  TempDir dir("geo_plot");
  std::vector<PlotPanel> panels(2, FixedPanel(0, 1, 0, 1));
  panels[0].series.push_back(Series({0, 1}, {0.5, 0.5}, kProbe));
  panels[1].series.push_back(Series({0, 1}, {0.5, 0.5}, kProbe));
  panels[1].series[0].dashed = true;
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng(panels, path);
  const RgbImage image = ReadPng(path);
  const int row = std::lround(RowOf(0.5, 0, 1));
  for (int panel = 0; panel < 2; ++panel) {
    const Area area = PlotArea(panel);
    int drawn = 0;
    for (int px = area.left; px < area.right; ++px) drawn += image.Is(px, row, kProbe);
    const double fraction = static_cast<double>(drawn) / kPlotAreaWidthPx;
    if (panel == 0) {
      EXPECT_EQ(drawn, kPlotAreaWidthPx);
    } else {
      // 8 px on, 5 px off, widened by one pixel by the 2 px pen: about 9 / 13 of the length.
      EXPECT_GT(fraction, 0.55);
      EXPECT_LT(fraction, 0.8);
    }
  }
}

TEST(WritePlotPng, BandLiesUnderTheLines) {
  TempDir dir("geo_plot");
  const std::array<uint8_t, 3> band_rgb{250, 220, 10};
  PlotPanel panel = FixedPanel(0, 1, 0, 1);
  PlotBand band;
  band.x = {0, 0.5, 1};
  band.lower = {0.25, 0.25, 0.25};
  band.upper = {0.75, 0.75, 0.75};
  band.rgb = band_rgb;
  panel.bands.push_back(band);
  panel.series.push_back(Series({0, 1}, {0.5, 0.5}, kProbe));
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng({panel}, path);
  const RgbImage image = ReadPng(path);
  const int col = std::lround(ColOf(0, 0.3, 0, 1));
  EXPECT_TRUE(image.Is(col, std::lround(RowOf(0.3, 0, 1)), band_rgb));
  EXPECT_TRUE(image.Is(col, std::lround(RowOf(0.7, 0, 1)), band_rgb));
  EXPECT_TRUE(image.Is(col, std::lround(RowOf(0.5, 0, 1)), kProbe));  // the line wins
  EXPECT_FALSE(image.Is(col, std::lround(RowOf(0.9, 0, 1)), band_rgb));
  EXPECT_FALSE(image.Is(col, std::lround(RowOf(0.1, 0, 1)), band_rgb));
  // Filled from edge to edge of the area, and nowhere outside it.
  const int row = std::lround(RowOf(0.3, 0, 1));
  EXPECT_TRUE(image.Is(kPlotAreaLeftPx, row, band_rgb));
  EXPECT_TRUE(image.Is(kPlotAreaLeftPx + kPlotAreaWidthPx - 1, row, band_rgb));
  const Area area = PlotArea(0);
  EXPECT_EQ(CountColour(image, band_rgb, 0, 0, image.width, image.height),
            CountColour(image, band_rgb, area.left, area.top, area.right, area.bottom));
}

TEST(WritePlotPng, AutomaticRangesShowAllDataWithAMargin) {
  TempDir dir("geo_plot");
  PlotPanel panel;  // every bound NaN
  panel.series.push_back(Series({0, 0.2, 0.6, 1}, {0.1, 0.45, 0.7, 0.8}, kProbe));
  panel.series[0].markers = true;
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng({panel}, path);
  const RgbImage image = ReadPng(path);
  const Area area = PlotArea(0);
  int min_x = image.width, max_x = -1, min_y = image.height, max_y = -1;
  for (int py = 0; py < image.height; ++py) {
    for (int px = 0; px < image.width; ++px) {
      if (!image.Is(px, py, kProbe)) continue;
      min_x = std::min(min_x, px);
      max_x = std::max(max_x, px);
      min_y = std::min(min_y, py);
      max_y = std::max(max_y, py);
    }
  }
  // Markers at the extreme points are whole (2 px half-width) and a few pixels off the frame.
  EXPECT_GT(min_x, area.left + 5);
  EXPECT_LT(max_x, area.right - 6);
  EXPECT_GT(min_y, area.top + 5);
  EXPECT_LT(max_y, area.bottom - 6);
}

TEST(WritePlotPng, TicksFallOnRoundValues) {
  TempDir dir("geo_plot");
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng({FixedPanel(0, 1, 0, 80)}, path);
  const RgbImage image = ReadPng(path);
  const std::array<uint8_t, 3> axis{64, 64, 64};
  const Area area = PlotArea(0);
  // Outward tick marks: x below the frame every 0.2, y left of it every 20; none half-way.
  const auto x_tick = [&](double x) {
    return image.Is(std::lround(ColOf(0, x, 0, 1)), area.bottom + 2, axis);
  };
  const auto y_tick = [&](double y) {
    return image.Is(area.left - 3, std::lround(RowOf(y, 0, 80)), axis);
  };
  for (double x : {0.0, 0.2, 0.4, 0.6, 0.8, 1.0}) EXPECT_TRUE(x_tick(x)) << x;
  for (double x : {0.1, 0.5, 0.9}) EXPECT_FALSE(x_tick(x)) << x;
  for (double y : {0.0, 20.0, 40.0, 60.0, 80.0}) EXPECT_TRUE(y_tick(y)) << y;
  for (double y : {10.0, 50.0}) EXPECT_FALSE(y_tick(y)) << y;
}

TEST(WritePlotPng, LegendListsLabelledSeriesOfTheFirstPanel) {
  TempDir dir("geo_plot");
  const std::array<uint8_t, 3> unlabelled{250, 10, 200};
  const std::array<uint8_t, 3> second_panel{10, 250, 10};
  std::vector<PlotPanel> panels(2, FixedPanel(0, 1, 0, 1));
  panels[0].series.push_back(Series({0, 1}, {0, 1}, kProbe, "scale 0.5"));
  panels[0].series.push_back(Series({0, 1}, {1, 0}, unlabelled));
  panels[1].series.push_back(Series({0, 1}, {0, 1}, second_panel, "other"));
  const std::string path = dir.path() + "/plot.png";
  WritePlotPng(panels, path);
  const RgbImage image = ReadPng(path);
  ASSERT_EQ(image.height, kOneLegendRowHeightPx);
  const auto in_legend = [&](const std::array<uint8_t, 3>& c) {
    return CountColour(image, c, 0, kPlotPanelHeightPx, image.width, image.height);
  };
  EXPECT_GT(in_legend(kProbe), 20);
  EXPECT_EQ(in_legend(unlabelled), 0);
  EXPECT_EQ(in_legend(second_panel), 0);
  // The label text is drawn (dark, antialiased) to the right of the sample line.
  EXPECT_GT(
      InkIn(image, kPlotAreaLeftPx + 30, kPlotPanelHeightPx, kPlotAreaLeftPx + 90, image.height)
          .count,
      20);
}

// The README's sample: three panels of traction against slip for three tyre scales.
std::vector<PlotPanel> TractionPanels() {
  const std::array<std::array<uint8_t, 3>, 3> colours = {
      {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}}};
  const char* const titles[] = {"Drawbar pull", "Gross traction", "Tractive efficiency"};
  const char* const y_labels[] = {"D/W", "T/(rW)", "efficiency (%)"};
  const char* const labels[] = {"scale 0.25", "scale 0.5", "scale 1"};
  std::vector<PlotPanel> panels(3);
  for (int p = 0; p < 3; ++p) {
    PlotPanel& panel = panels[p];
    panel.title = titles[p];
    panel.x_label = "slip s (-)";
    panel.y_label = y_labels[p];
    panel.x_min = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double scale = 0.25 * (1 << k);
      std::vector<double> x, y;
      for (int i = 0; i <= 14; ++i) {
        const double slip = 0.05 * i;
        const double pull = (0.6 - 0.05 * k) * (1 - std::exp(-slip / (0.06 * scale + 0.04)));
        x.push_back(slip);
        y.push_back(p == 0 ? pull - 0.05 : p == 1 ? pull + 0.1 : 100 * pull * (1 - slip));
      }
      panel.series.push_back(Series(x, y, colours[k], labels[k]));
      if (k == 2) {
        panel.series.back().markers = true;
        PlotBand band;
        band.x = x;
        for (double v : y) {
          band.lower.push_back(v * 0.9);
          band.upper.push_back(v * 1.1);
        }
        band.rgb = {200, 235, 200};
        panel.bands.push_back(band);
      }
    }
  }
  PlotSeries dashed = Series({0.0, 0.7}, {0.3, 0.3}, {44, 160, 44}, "1 sigma band (full scale)");
  dashed.dashed = true;
  panels[0].series.push_back(dashed);
  return panels;
}

TEST(WritePlotPng, TextIsSetInAnAntialiasedOutlineFont) {
  TempDir dir("geo_plot");
  const std::string path = dir.path() + "/traction.png";
  WritePlotPng(TractionPanels(), path);
  if (const char* keep = std::getenv("GONOGO_PLOT_SAMPLE")) {
    std::filesystem::copy_file(path, keep, std::filesystem::copy_options::overwrite_existing);
  }
  const RgbImage image = ReadPng(path);
  ASSERT_EQ(image.width, 3 * kPlotPanelWidthPx);
  for (int panel = 0; panel < 3; ++panel) {
    const int left = panel * kPlotPanelWidthPx;
    const Area area = PlotArea(panel);
    // Title, above the frame: a line of 15 px bold type (capitals about 11 px, "p" and "y" reach
    // below), far wider than tall, centred over the plot area. Antialiased glyph edges leave grey
    // pixels, which a bitmap font would not.
    const Ink title = InkIn(image, left, 0, left + kPlotPanelWidthPx, kPlotAreaTopPx - 1);
    EXPECT_GT(title.count, 150) << "panel " << panel;
    EXPECT_GE(title.Height(), 10) << "panel " << panel;
    EXPECT_LE(title.Height(), 20) << "panel " << panel;
    EXPECT_GT(title.Width(), 80) << "panel " << panel;
    EXPECT_NEAR((title.left + title.right) / 2.0, (area.left + area.right) / 2.0, 4.0);
    EXPECT_GT(CountGreyEdges(image, left, 0, left + kPlotPanelWidthPx, kPlotAreaTopPx - 1), 40);
    // x tick labels and the x-axis label, below the frame: two lines of text, at least 11 px type.
    const Ink below =
        InkIn(image, area.left - 20, area.bottom + 6, area.right + 10, kPlotPanelHeightPx);
    EXPECT_GE(below.Height(), 2 * 8) << "panel " << panel;
    // The y label reads upwards: its ink, left of the tick labels, is taller than wide.
    const Ink y_label = InkIn(image, left, area.top, left + 24, area.bottom);
    EXPECT_GT(y_label.Height(), y_label.Width()) << "panel " << panel;
    EXPECT_GE(y_label.Width(), 8) << "panel " << panel;
  }
  // Legend: one row of labels across most of the image width.
  const Ink legend = InkIn(image, 0, kPlotPanelHeightPx, image.width, image.height);
  EXPECT_GE(legend.Height(), 8);
  EXPECT_GT(legend.Width(), 400);
}

TEST(WritePlotPng, RejectsBadArguments) {
  TempDir dir("geo_plot");
  const std::string path = dir.path() + "/plot.png";
  const PlotPanel good = FixedPanel(0, 1, 0, 1);
  const auto expect_plot_error = [&](const std::vector<PlotPanel>& panels, const std::string& out,
                                     const std::string& fragment) {
    try {
      WritePlotPng(panels, out);
      ADD_FAILURE() << "no error; expected one mentioning " << fragment;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "plot");
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_plot_error({}, path, "no panels");
  expect_plot_error(std::vector<PlotPanel>(kPlotMaxPanels + 1, good), path, "limit");
  expect_plot_error({good}, "", "path is empty");

  PlotPanel bad = good;
  bad.series.push_back(Series({0, 1, 2}, {0, 1}, kProbe, "short y"));
  expect_plot_error({good, bad}, path, "panel 1 series 0 (\"short y\"): x has 3 points, y has 2");

  bad = good;
  PlotBand band;
  band.x = {0, 1};
  band.lower = {0, 1};
  band.upper = {1};
  bad.bands.push_back(band);
  expect_plot_error({bad}, path, "band 0");

  bad = good;
  bad.x_min = 2;  // above x_max = 1
  expect_plot_error({bad}, path, "x axis range [2, 1]");
  bad = good;
  bad.y_max = bad.y_min;
  expect_plot_error({bad}, path, "y axis range");
  bad = good;
  bad.y_max = INFINITY;
  expect_plot_error({bad}, path, "finite");
  bad = PlotPanel();  // automatic range over data too wide for a finite span
  bad.series.push_back(Series({-1.7e308, 1.7e308}, {0, 1}, kProbe));
  expect_plot_error({bad}, path, "x axis range");

  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(WritePlotPng, UnwritablePathThrowsAndLeavesNothing) {
  TempDir dir("geo_plot");
  const std::string path = dir.path() + "/missing/plot.png";
  PlotPanel panel = FixedPanel(0, 1, 0, 1);
  EXPECT_THROW(WritePlotPng({panel}, path), std::runtime_error);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace gonogo::geo
