#include "server/geo/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "server/geo/bitmap_font.h"
#include "server/geo/gdal_util.h"
#include "server/geo/quicklook.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

namespace fs = std::filesystem;
using internal::Rgba;
using internal::RgbaImage;

const char kField[] = "plot";

// Text: titles at twice the font size, everything else at its own size.
constexpr int kTitleScale = 2;
constexpr int kTextScale = 1;
constexpr int kTextHeightPx = internal::kGlyphHeight * kTextScale;

// Panel decorations, relative to the panel's top-left corner (the plot area is in plot.h).
constexpr int kTitleTopPx = 8;
constexpr int kYLabelLeftPx = 8;
constexpr int kTickLengthPx = 4;
constexpr int kTickLabelGapPx = 3;  // between a tick mark's end and its label
constexpr int kXLabelGapPx = 8;     // between the x tick labels and the x-axis label
constexpr int kXTickTarget = 6;     // about this many ticks per axis
constexpr int kYTickTarget = 5;
constexpr int kMaxTicks = 50;
constexpr int kMinTickLabelGapPx = 10;  // between neighbouring x tick labels
constexpr double kAutoMarginFraction = 0.04;

// Legend below the panels: entries left to right, wrapped to the image width.
constexpr int kLegendPadTopPx = 2;
constexpr int kLegendPadBottomPx = 8;
constexpr int kLegendRowPx = 18;
constexpr int kLegendSamplePx = 28;  // length of the line sample before each label
constexpr int kLegendTextGapPx = 6;
constexpr int kLegendEntryGapPx = 24;
constexpr int kLegendRightMarginPx = 16;

// Line style.
constexpr int kLineWidthPx = 2;
constexpr int kMarkerPx = 5;
constexpr double kDashOnPx = 8.0;
constexpr double kDashOffPx = 5.0;

constexpr Rgba kBackground{255, 255, 255, 255};
constexpr Rgba kTextColour{0, 0, 0, 255};
constexpr Rgba kAxisColour{64, 64, 64, 255};
constexpr Rgba kGridColour{230, 230, 230, 255};

Rgba Opaque(const std::array<uint8_t, 3>& rgb) { return {rgb[0], rgb[1], rgb[2], 255}; }

bool Finite(double v) { return std::isfinite(v); }

// A pixel rectangle, [left, left + width) x [top, top + height).
struct PixelRect {
  int left = 0, top = 0, width = 0, height = 0;
};

// Fills a rectangle clipped to `clip`, so data drawn with it never spills onto axes or labels.
void FillClipped(RgbaImage& image, const PixelRect& clip, int x, int y, int w, int h, Rgba c) {
  const int x0 = std::max(x, clip.left), y0 = std::max(y, clip.top);
  const int x1 = std::min(x + w, clip.left + clip.width);
  const int y1 = std::min(y + h, clip.top + clip.height);
  if (x1 > x0 && y1 > y0) image.Fill(x0, y0, x1 - x0, y1 - y0, c);
}

// One axis: its range, tick values and the decimals their labels need.
struct Axis {
  double min = 0.0, max = 1.0;
  std::vector<double> ticks;
  double step = 1.0;  // between ticks
  int decimals = 0;
};

// Ticks on multiples of a 1-2-2.5-5 step near span / target_count, so labels are round numbers.
void SetNiceTicks(Axis& axis, int target_count) {
  const double raw_step = (axis.max - axis.min) / target_count;
  const int exponent = static_cast<int>(std::floor(std::log10(raw_step)));
  const double magnitude = std::pow(10.0, exponent);
  const double fraction = raw_step / magnitude;
  if (!Finite(fraction) || magnitude <= 0.0) {  // subnormal spans: label the ends only
    axis.ticks = {axis.min, axis.max};
    axis.step = axis.max - axis.min;
    axis.decimals = 6;
    return;
  }
  double nice = 10.0;
  if (fraction < 1.5) {
    nice = 1.0;
  } else if (fraction < 2.25) {
    nice = 2.0;
  } else if (fraction < 3.5) {
    nice = 2.5;
  } else if (fraction < 7.5) {
    nice = 5.0;
  }
  const double step = nice * magnitude;
  axis.step = step;
  // Digits after the point: those of the power of ten, one more for 2.5 (0.25), one less for 10.
  const int decimals = -exponent + (nice == 2.5 ? 1 : 0) - (nice == 10.0 ? 1 : 0);
  axis.decimals = std::clamp(decimals, 0, 12);
  axis.ticks.clear();
  // The tolerance keeps a tick that sits on a bound despite rounding (0.1 * 3 vs 0.3).
  for (double k = std::ceil(axis.min / step - 1e-9);
       k <= std::floor(axis.max / step + 1e-9) &&
       axis.ticks.size() < static_cast<size_t>(kMaxTicks);
       k += 1.0) {
    const double value = k * step;
    axis.ticks.push_back(std::abs(value) < 1e-9 * step ? 0.0 : value);  // no "-0.0"
  }
}

std::string FormatTick(double value, int decimals) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

int WidestTickLabelPx(const Axis& axis) {
  int widest = 0;
  for (double v : axis.ticks) {
    widest = std::max(widest, internal::TextWidthPx(FormatTick(v, axis.decimals), kTextScale));
  }
  return widest;
}

// Fewer x ticks while neighbouring labels would touch: labels such as "-0.0025" need more room than
// the default tick count leaves them.
void FitXTickLabels(Axis& axis) {
  const double px_per_unit = (kPlotAreaWidthPx - 1) / (axis.max - axis.min);
  for (int target = kXTickTarget - 1;
       target >= 2 && WidestTickLabelPx(axis) + kMinTickLabelGapPx > axis.step * px_per_unit;
       --target) {
    SetNiceTicks(axis, target);
  }
}

// Smallest and largest finite value seen; empty while lo > hi.
struct Extent {
  double lo = INFINITY, hi = -INFINITY;
  void Add(double v) {
    if (!Finite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
};

// The axis range: fixed bounds as given, automatic ones from the data with a margin.
Axis ResolveAxis(double fixed_min, double fixed_max, const Extent& data, int tick_target,
                 const std::string& what) {
  double lo = 0.0, hi = 1.0;  // no data at all
  if (data.lo < data.hi) {
    const double margin = kAutoMarginFraction * (data.hi - data.lo);
    lo = data.lo - margin;
    hi = data.hi + margin;
  } else if (data.lo == data.hi) {  // a single value: centre it
    const double half = data.lo == 0.0 ? 0.5 : 0.1 * std::abs(data.lo);
    lo = data.lo - half;
    hi = data.hi + half;
  }
  const double auto_span = hi - lo;
  Axis axis;
  axis.min = std::isnan(fixed_min) ? lo : fixed_min;
  axis.max = std::isnan(fixed_max) ? hi : fixed_max;
  // One fixed bound beyond the data: keep the automatic span on the free side.
  if (axis.min >= axis.max && std::isnan(fixed_max)) axis.max = axis.min + auto_span;
  if (axis.min >= axis.max && std::isnan(fixed_min)) axis.min = axis.max - auto_span;
  Require(axis.min < axis.max && Finite(axis.max - axis.min), kField,
          what + " range [" + Number(axis.min) + ", " + Number(axis.max) +
              "] is not a finite, non-empty interval");
  SetNiceTicks(axis, tick_target);
  return axis;
}

// Maps one panel's data coordinates to image pixels.
struct Frame {
  PixelRect area;  // the plot area in image pixels
  Axis x, y;

  double Col(double v) const {
    return area.left + (v - x.min) / (x.max - x.min) * (area.width - 1);
  }
  double Row(double v) const {
    return area.top + (y.max - v) / (y.max - y.min) * (area.height - 1);
  }
  // The data x at the centre of image column `col`.
  double XAt(int col) const {
    return x.min + (col - area.left) * (x.max - x.min) / (area.width - 1);
  }
  bool Contains(double vx, double vy) const {
    return vx >= x.min && vx <= x.max && vy >= y.min && vy <= y.max;
  }
};

Frame MakeFrame(const PlotPanel& panel, int panel_index) {
  Extent xs, ys;
  for (const PlotSeries& s : panel.series) {
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (Finite(s.x[i]) && Finite(s.y[i])) {
        xs.Add(s.x[i]);
        ys.Add(s.y[i]);
      }
    }
  }
  for (const PlotBand& b : panel.bands) {
    for (size_t i = 0; i < b.x.size(); ++i) {
      if (Finite(b.x[i]) && Finite(b.lower[i]) && Finite(b.upper[i])) {
        xs.Add(b.x[i]);
        ys.Add(b.lower[i]);
        ys.Add(b.upper[i]);
      }
    }
  }
  const std::string where = "panel " + std::to_string(panel_index);
  Frame frame;
  frame.area = {panel_index * kPlotPanelWidthPx + kPlotAreaLeftPx, kPlotAreaTopPx, kPlotAreaWidthPx,
                kPlotAreaHeightPx};
  frame.x = ResolveAxis(panel.x_min, panel.x_max, xs, kXTickTarget, where + " x axis");
  FitXTickLabels(frame.x);
  frame.y = ResolveAxis(panel.y_min, panel.y_max, ys, kYTickTarget, where + " y axis");
  return frame;
}

// Clips the segment (x0, y0)-(x1, y1) to the axis ranges in data space (Liang-Barsky), before any
// pixel conversion, so far-away points cost nothing and never overflow an int. False when nothing
// is left.
bool ClipSegment(const Frame& f, double& x0, double& y0, double& x1, double& y1) {
  const double dx = x1 - x0, dy = y1 - y0;
  if (!Finite(dx) || !Finite(dy)) return false;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {x0 - f.x.min, f.x.max - x0, y0 - f.y.min, f.y.max - y0};
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;  // parallel to this edge and outside it
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
  }
  if (t0 > t1) return false;
  // Clamped because rounding can leave the ends a hair outside (or, for a segment millions of times
  // longer than the axes, far outside); pixel coordinates then always fit an int.
  x1 = std::clamp(x0 + t1 * dx, f.x.min, f.x.max);
  y1 = std::clamp(y0 + t1 * dy, f.y.min, f.y.max);
  x0 = std::clamp(x0 + t0 * dx, f.x.min, f.x.max);
  y0 = std::clamp(y0 + t0 * dy, f.y.min, f.y.max);
  return true;
}

// Draws data lines and markers on the image, clipped to one rectangle.
class Pen {
 public:
  Pen(RgbaImage& image, const PixelRect& clip, Rgba colour)
      : image_(image), clip_(clip), colour_(colour) {}

  // A size x size square centred on (col, row) (the extra pixel of an even size goes right/down).
  void Square(int col, int row, int size) {
    const int offset = (size - 1) / 2;
    FillClipped(image_, clip_, col - offset, row - offset, size, size, colour_);
  }

  // Bresenham from (c0, r0) to (c1, r1), a line-width square at each step. For dashed lines
  // `dash_phase_px` is the length drawn so far along the polyline, so dashes run on across joints.
  void Segment(int c0, int r0, int c1, int r1, bool dashed, double* dash_phase_px) {
    const int dc = std::abs(c1 - c0), dr = -std::abs(r1 - r0);
    const int step_c = c0 < c1 ? 1 : -1, step_r = r0 < r1 ? 1 : -1;
    const int steps = std::max(dc, -dr);
    const double step_length = steps == 0 ? 0.0 : std::hypot(dc, dr) / steps;
    int error = dc + dr;
    for (int c = c0, r = r0;;) {
      if (!dashed || std::fmod(*dash_phase_px, kDashOnPx + kDashOffPx) < kDashOnPx) {
        Square(c, r, kLineWidthPx);
      }
      if (c == c1 && r == r1) break;
      *dash_phase_px += step_length;
      const int doubled = 2 * error;
      if (doubled >= dr) {
        error += dr;
        c += step_c;
      }
      if (doubled <= dc) {
        error += dc;
        r += step_r;
      }
    }
  }

 private:
  RgbaImage& image_;
  PixelRect clip_;
  Rgba colour_;
};

int Pixel(double v) { return static_cast<int>(std::lround(v)); }

void DrawSeries(RgbaImage& image, const Frame& f, const PlotSeries& s) {
  Pen pen(image, f.area, Opaque(s.rgb));
  const size_t n = s.x.size();
  auto usable = [&](size_t i) { return i < n && Finite(s.x[i]) && Finite(s.y[i]); };
  double dash_phase_px = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (!usable(i)) {
      dash_phase_px = 0.0;  // a new piece of line starts a new dash pattern
      continue;
    }
    const bool joined_before = i > 0 && usable(i - 1);
    if (joined_before) {
      double x0 = s.x[i - 1], y0 = s.y[i - 1], x1 = s.x[i], y1 = s.y[i];
      if (ClipSegment(f, x0, y0, x1, y1)) {
        pen.Segment(Pixel(f.Col(x0)), Pixel(f.Row(y0)), Pixel(f.Col(x1)), Pixel(f.Row(y1)),
                    s.dashed, &dash_phase_px);
      }
    }
    const bool isolated = !joined_before && !usable(i + 1);
    if ((s.markers || isolated) && f.Contains(s.x[i], s.y[i])) {
      pen.Square(Pixel(f.Col(s.x[i])), Pixel(f.Row(s.y[i])), s.markers ? kMarkerPx : kLineWidthPx);
    }
  }
}

// Fills each image column between consecutive band points from the interpolated lower to upper
// value; the column's data x is interpolated in data space, so no pixel coordinate overflows.
void DrawBand(RgbaImage& image, const Frame& f, const PlotBand& b) {
  const Rgba colour = Opaque(b.rgb);
  const PixelRect& a = f.area;
  for (size_t i = 0; i + 1 < b.x.size(); ++i) {
    size_t p = i, q = i + 1;
    if (b.x[p] > b.x[q]) std::swap(p, q);
    const double xa = b.x[p], xb = b.x[q];
    if (!Finite(xa) || !Finite(xb) || !Finite(b.lower[p]) || !Finite(b.lower[q]) ||
        !Finite(b.upper[p]) || !Finite(b.upper[q])) {
      continue;
    }
    const double lo = std::max(xa, f.x.min), hi = std::min(xb, f.x.max);
    if (lo > hi) continue;
    for (int col = Pixel(f.Col(lo)); col <= Pixel(f.Col(hi)); ++col) {
      const double x = std::clamp(f.XAt(col), xa, xb);
      const double t = xb > xa ? (x - xa) / (xb - xa) : 0.0;
      const double lower = b.lower[p] + t * (b.lower[q] - b.lower[p]);
      const double upper = b.upper[p] + t * (b.upper[q] - b.upper[p]);
      // Clamped just outside the area before the conversion to int; FillClipped trims the rest.
      const double row_lo = a.top - 1.0, row_hi = a.top + a.height;
      const int top = Pixel(std::clamp(f.Row(std::max(lower, upper)), row_lo, row_hi));
      const int bottom = Pixel(std::clamp(f.Row(std::min(lower, upper)), row_lo, row_hi));
      FillClipped(image, a, col, top, 1, bottom - top + 1, colour);
    }
  }
}

void DrawCentredText(RgbaImage& image, int centre_x, int y, const std::string& text, int scale) {
  internal::DrawText(image, centre_x - internal::TextWidthPx(text, scale) / 2, y, text, scale,
                     kTextColour);
}

// Light grid lines at the ticks, drawn first so bands and lines cover them.
void DrawGrid(RgbaImage& image, const Frame& f) {
  const PixelRect& a = f.area;
  for (double v : f.x.ticks) {
    FillClipped(image, a, Pixel(f.Col(v)), a.top, 1, a.height, kGridColour);
  }
  for (double v : f.y.ticks) {
    FillClipped(image, a, a.left, Pixel(f.Row(v)), a.width, 1, kGridColour);
  }
}

// The frame just outside the plot area, outward tick marks with their labels, the title and the
// axis labels.
void DrawAxes(RgbaImage& image, const Frame& f, const PlotPanel& panel, int panel_left) {
  const PixelRect& a = f.area;
  const int right = a.left + a.width;   // the frame's right column
  const int bottom = a.top + a.height;  // the frame's bottom row
  image.Fill(a.left - 1, a.top - 1, a.width + 2, 1, kAxisColour);
  image.Fill(a.left - 1, bottom, a.width + 2, 1, kAxisColour);
  image.Fill(a.left - 1, a.top - 1, 1, a.height + 2, kAxisColour);
  image.Fill(right, a.top - 1, 1, a.height + 2, kAxisColour);

  const int x_label_top = bottom + 1 + kTickLengthPx + kTickLabelGapPx;
  for (double v : f.x.ticks) {
    const int col = Pixel(f.Col(v));
    image.Fill(col, bottom + 1, 1, kTickLengthPx, kAxisColour);
    DrawCentredText(image, col, x_label_top, FormatTick(v, f.x.decimals), kTextScale);
  }
  const int y_label_right = a.left - 1 - kTickLengthPx - kTickLabelGapPx;
  for (double v : f.y.ticks) {
    const int row = Pixel(f.Row(v));
    image.Fill(a.left - 1 - kTickLengthPx, row, kTickLengthPx, 1, kAxisColour);
    const std::string label = FormatTick(v, f.y.decimals);
    internal::DrawText(image, y_label_right - internal::TextWidthPx(label, kTextScale),
                       row - kTextHeightPx / 2, label, kTextScale, kTextColour);
  }

  const int centre_x = a.left + a.width / 2;
  const int title_scale =
      internal::TextWidthPx(panel.title, kTitleScale) <= kPlotPanelWidthPx - 8 ? kTitleScale : 1;
  DrawCentredText(image, centre_x, kTitleTopPx, panel.title, title_scale);
  DrawCentredText(image, centre_x, x_label_top + kTextHeightPx + kXLabelGapPx, panel.x_label,
                  kTextScale);
  internal::DrawTextUp(image, panel_left + kYLabelLeftPx,
                       a.top + (a.height - internal::TextWidthPx(panel.y_label, kTextScale)) / 2,
                       panel.y_label, kTextScale, kTextColour);
}

// Where each legend entry goes: its top-left corner in the image.
struct LegendEntry {
  const PlotSeries* series;
  int x, y;
};

std::vector<LegendEntry> LayoutLegend(const PlotPanel& first, int image_width, int* rows) {
  std::vector<LegendEntry> entries;
  const int start_x = kPlotAreaLeftPx;
  int x = start_x, row = 0;
  for (const PlotSeries& s : first.series) {
    if (s.label.empty()) continue;
    const int width =
        kLegendSamplePx + kLegendTextGapPx + internal::TextWidthPx(s.label, kTextScale);
    if (x > start_x && x + width > image_width - kLegendRightMarginPx) {
      x = start_x;
      ++row;
    }
    entries.push_back({&s, x, kPlotPanelHeightPx + kLegendPadTopPx + row * kLegendRowPx});
    x += width + kLegendEntryGapPx;
  }
  *rows = entries.empty() ? 0 : row + 1;
  return entries;
}

void DrawLegend(RgbaImage& image, const std::vector<LegendEntry>& entries) {
  for (const LegendEntry& e : entries) {
    const PlotSeries& s = *e.series;
    const int mid = e.y + kLegendRowPx / 2;
    const PixelRect sample{e.x, e.y, kLegendSamplePx, kLegendRowPx};
    Pen pen(image, sample, Opaque(s.rgb));
    double dash_phase_px = 0.0;
    pen.Segment(e.x, mid, e.x + kLegendSamplePx - 2, mid, s.dashed, &dash_phase_px);
    if (s.markers) pen.Square(e.x + kLegendSamplePx / 2, mid, kMarkerPx);
    internal::DrawText(image, e.x + kLegendSamplePx + kLegendTextGapPx, mid - kTextHeightPx / 2,
                       s.label, kTextScale, kTextColour);
  }
}

void CheckArguments(const std::vector<PlotPanel>& panels, const std::string& path) {
  Require(!panels.empty(), kField, "no panels to draw");
  Require(panels.size() <= static_cast<size_t>(kPlotMaxPanels), kField,
          std::to_string(panels.size()) + " panels exceed the limit of " +
              std::to_string(kPlotMaxPanels));
  Require(!path.empty(), kField, "output path is empty");
  for (size_t i = 0; i < panels.size(); ++i) {
    const PlotPanel& p = panels[i];
    const std::string where = "panel " + std::to_string(i);
    for (size_t j = 0; j < p.series.size(); ++j) {
      const PlotSeries& s = p.series[j];
      Require(s.x.size() == s.y.size(), kField,
              where + " series " + std::to_string(j) + " (\"" + s.label + "\"): x has " +
                  std::to_string(s.x.size()) + " points, y has " + std::to_string(s.y.size()));
    }
    for (size_t j = 0; j < p.bands.size(); ++j) {
      const PlotBand& b = p.bands[j];
      Require(b.lower.size() == b.x.size() && b.upper.size() == b.x.size(), kField,
              where + " band " + std::to_string(j) + ": x has " + std::to_string(b.x.size()) +
                  " points, lower " + std::to_string(b.lower.size()) + ", upper " +
                  std::to_string(b.upper.size()));
    }
    for (double bound : {p.x_min, p.x_max, p.y_min, p.y_max}) {
      Require(!std::isinf(bound), kField, where + ": axis bounds must be finite (NaN = automatic)");
    }
  }
}

RgbaImage RenderPlot(const std::vector<PlotPanel>& panels) {
  // Every axis is resolved (and checked) before anything is drawn.
  std::vector<Frame> frames;
  for (size_t i = 0; i < panels.size(); ++i) {
    frames.push_back(MakeFrame(panels[i], static_cast<int>(i)));
  }
  RgbaImage image;
  image.width = kPlotPanelWidthPx * static_cast<int>(panels.size());
  int legend_rows = 0;
  const std::vector<LegendEntry> legend = LayoutLegend(panels[0], image.width, &legend_rows);
  image.height = kPlotPanelHeightPx;
  if (legend_rows > 0) {
    image.height += kLegendPadTopPx + legend_rows * kLegendRowPx + kLegendPadBottomPx;
  }
  image.pixels.resize(static_cast<size_t>(image.width) * image.height * 4);
  image.Fill(0, 0, image.width, image.height, kBackground);

  for (size_t i = 0; i < panels.size(); ++i) {
    const Frame& f = frames[i];
    DrawGrid(image, f);
    for (const PlotBand& b : panels[i].bands) DrawBand(image, f, b);
    for (const PlotSeries& s : panels[i].series) DrawSeries(image, f, s);
    DrawAxes(image, f, panels[i], static_cast<int>(i) * kPlotPanelWidthPx);
  }
  DrawLegend(image, legend);
  return image;
}

}  // namespace

void WritePlotPng(const std::vector<PlotPanel>& panels, const std::string& path) {
  CheckArguments(panels, path);
  const RgbaImage image = RenderPlot(panels);
  internal::EnsureGdalRegistered();
  internal::GdalErrorScope gdal_errors;
  // A temporary name and a rename, so a reader never sees a partial file.
  const std::string partial = path + ".partial";
  try {
    internal::WritePng(image, partial, /*with_alpha=*/false);
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

}  // namespace gonogo::geo
