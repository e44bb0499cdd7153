#include "server/geo/plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "server/geo/quicklook.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

using internal::CapHeightPx;
using internal::Rgba;
using internal::TextWidthPx;

const char kField[] = "plot";

// Text (DejaVu Sans, em size in pixels): bold titles, shrunk to fit a panel down to the label
// size; tick labels a little smaller than axis labels and legend.
constexpr double kTitleFontPx = 15.0;
constexpr double kLabelFontPx = 12.0;
constexpr double kTickFontPx = 11.0;

// Panel decorations, relative to the panel's top-left corner (the plot area is in plot.h).
constexpr int kTitleTopPx = 8;
constexpr int kYLabelLeftPx = 6;
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
constexpr double kDashPx[] = {8.0, 5.0};                // on, off
constexpr double kQuarterTurnRad = 1.5707963267948966;  // pi / 2

constexpr Rgba kBackground{255, 255, 255, 255};
constexpr Rgba kTextColour{0, 0, 0, 255};
constexpr Rgba kAxisColour{64, 64, 64, 255};
constexpr Rgba kGridColour{230, 230, 230, 255};

Rgba Opaque(const std::array<uint8_t, 3>& rgb) { return {rgb[0], rgb[1], rgb[2], 255}; }

bool Finite(double v) { return std::isfinite(v); }

void SetColour(cairo_t* cr, Rgba c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

// A filled rectangle on whole pixels, so its colour is exact whatever the antialiasing.
void FillRect(cairo_t* cr, int x, int y, int w, int h, Rgba c) {
  SetColour(cr, c);
  cairo_rectangle(cr, x, y, w, h);
  cairo_fill(cr);
}


// Draws `text` in kTextColour with the left end of its baseline at (x, baseline).
void DrawText(cairo_t* cr, double x, double baseline, const std::string& text) {
  SetColour(cr, kTextColour);
  cairo_move_to(cr, x, baseline);
  cairo_show_text(cr, text.c_str());
}

// A pixel rectangle, [left, left + width) x [top, top + height).
struct PixelRect {
  int left = 0, top = 0, width = 0, height = 0;
};

// Restricts drawing to `r` until the next cairo_restore (the caller saves first).
void ClipTo(cairo_t* cr, const PixelRect& r) {
  cairo_rectangle(cr, r.left, r.top, r.width, r.height);
  cairo_clip(cr);
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

// `cr` carries the tick-label font.
double WidestTickLabelPx(cairo_t* cr, const Axis& axis) {
  double widest = 0.0;
  for (double v : axis.ticks)
    widest = std::max(widest, TextWidthPx(cr, FormatTick(v, axis.decimals)));
  return widest;
}

// Fewer x ticks while neighbouring labels would touch: labels such as "-0.0025" need more room than
// the default tick count leaves them.
void FitXTickLabels(cairo_t* cr, Axis& axis) {
  const double px_per_unit = (kPlotAreaWidthPx - 1) / (axis.max - axis.min);
  for (int target = kXTickTarget - 1;
       target >= 2 && WidestTickLabelPx(cr, axis) + kMinTickLabelGapPx > axis.step * px_per_unit;
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

// `cr` is only measured with (tick-label widths).
Frame MakeFrame(cairo_t* cr, const PlotPanel& panel, int panel_index) {
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
  internal::SelectFont(cr, kTickFontPx);
  FitXTickLabels(cr, frame.x);
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

// Data lines, markers and bands are drawn without antialiasing, on whole pixels: every pixel of a
// series then has exactly the series colour (the tests find points by colour, and bands and lines
// never blend into each other), and the geometry matches the documented layout to the pixel.
// Text keeps cairo's greyscale antialiasing.

int Pixel(double v) { return static_cast<int>(std::lround(v)); }

// Where a polyline vertex goes: the corner between the point's pixel and its right and lower
// neighbours, so the 2 px line covers the point's pixel and one more each way, with no sample on
// the stroke's edge (unambiguous without antialiasing).
double LineX(const Frame& f, double x) { return Pixel(f.Col(x)) + 1.0; }
double LineY(const Frame& f, double y) { return Pixel(f.Row(y)) + 1.0; }

// A size x size square centred on pixel (col, row) (the extra pixel of an even size goes
// right/down), added to the current path.
void AddSquare(cairo_t* cr, int col, int row, int size) {
  const int offset = (size - 1) / 2;
  cairo_rectangle(cr, col - offset, row - offset, size, size);
}

// The stroke of a series: 2 px, round caps and joins when solid, 8 on / 5 off butt-ended dashes
// (continued across joints) when dashed.
void SetLineStyle(cairo_t* cr, const PlotSeries& s) {
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
  cairo_set_line_width(cr, kLineWidthPx);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, s.dashed ? CAIRO_LINE_CAP_BUTT : CAIRO_LINE_CAP_ROUND);
  if (s.dashed) cairo_set_dash(cr, kDashPx, 2, 0.0);
  SetColour(cr, Opaque(s.rgb));
}

void DrawSeries(cairo_t* cr, const Frame& f, const PlotSeries& s) {
  cairo_save(cr);
  ClipTo(cr, f.area);
  SetLineStyle(cr, s);
  const size_t n = s.x.size();
  auto usable = [&](size_t i) { return i < n && Finite(s.x[i]) && Finite(s.y[i]); };
  // One path for the whole series: a NaN point or a clipped end starts a new sub-path (and a new
  // dash pattern); otherwise the line runs on through the joint.
  bool joined = false;  // the current sub-path ends at point i - 1
  for (size_t i = 0; i < n; ++i) {
    if (!usable(i) || i == 0 || !usable(i - 1)) {
      joined = false;
      continue;
    }
    double x0 = s.x[i - 1], y0 = s.y[i - 1], x1 = s.x[i], y1 = s.y[i];
    if (!ClipSegment(f, x0, y0, x1, y1)) {
      joined = false;
      continue;
    }
    if (!joined || x0 != s.x[i - 1] || y0 != s.y[i - 1]) {
      cairo_move_to(cr, LineX(f, x0), LineY(f, y0));
    }
    cairo_line_to(cr, LineX(f, x1), LineY(f, y1));
    joined = x1 == s.x[i] && y1 == s.y[i];
  }
  cairo_stroke(cr);
  // Markers, and a 2 px dot for a point with no finite neighbour so it does not vanish.
  for (size_t i = 0; i < n; ++i) {
    if (!usable(i)) continue;
    const bool isolated = !(i > 0 && usable(i - 1)) && !usable(i + 1);
    if ((s.markers || isolated) && f.Contains(s.x[i], s.y[i])) {
      AddSquare(cr, Pixel(f.Col(s.x[i])), Pixel(f.Row(s.y[i])),
                s.markers ? kMarkerPx : kLineWidthPx);
    }
  }
  cairo_fill(cr);
  cairo_restore(cr);
}

// Fills each image column between consecutive band points from the interpolated lower to upper
// value; the column's data x is interpolated in data space, so no pixel coordinate overflows.
void DrawBand(cairo_t* cr, const Frame& f, const PlotBand& b) {
  const PixelRect& a = f.area;
  cairo_save(cr);
  ClipTo(cr, a);
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
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
      // Clamped just outside the area before the conversion to int; the clip trims the rest.
      const double row_lo = a.top - 1.0, row_hi = a.top + a.height;
      const int top = Pixel(std::clamp(f.Row(std::max(lower, upper)), row_lo, row_hi));
      const int bottom = Pixel(std::clamp(f.Row(std::min(lower, upper)), row_lo, row_hi));
      cairo_rectangle(cr, col, top, 1, bottom - top + 1);
    }
  }
  SetColour(cr, Opaque(b.rgb));
  cairo_fill(cr);
  cairo_restore(cr);
}

// Light grid lines at the ticks, drawn first so bands and lines cover them.
void DrawGrid(cairo_t* cr, const Frame& f) {
  const PixelRect& a = f.area;
  cairo_save(cr);
  ClipTo(cr, a);
  for (double v : f.x.ticks) FillRect(cr, Pixel(f.Col(v)), a.top, 1, a.height, kGridColour);
  for (double v : f.y.ticks) FillRect(cr, a.left, Pixel(f.Row(v)), a.width, 1, kGridColour);
  cairo_restore(cr);
}

// The frame just outside the plot area, outward tick marks with their labels, the title and the
// axis labels; all clipped to the panel.
void DrawAxes(cairo_t* cr, const Frame& f, const PlotPanel& panel, int panel_left) {
  const PixelRect& a = f.area;
  cairo_save(cr);
  ClipTo(cr, {panel_left, 0, kPlotPanelWidthPx, kPlotPanelHeightPx});
  const int right = a.left + a.width;   // the frame's right column
  const int bottom = a.top + a.height;  // the frame's bottom row
  FillRect(cr, a.left - 1, a.top - 1, a.width + 2, 1, kAxisColour);
  FillRect(cr, a.left - 1, bottom, a.width + 2, 1, kAxisColour);
  FillRect(cr, a.left - 1, a.top - 1, 1, a.height + 2, kAxisColour);
  FillRect(cr, right, a.top - 1, 1, a.height + 2, kAxisColour);

  internal::SelectFont(cr, kTickFontPx);
  const double tick_cap_px = CapHeightPx(cr);
  const int x_label_top = bottom + 1 + kTickLengthPx + kTickLabelGapPx;
  for (double v : f.x.ticks) {
    const int col = Pixel(f.Col(v));
    FillRect(cr, col, bottom + 1, 1, kTickLengthPx, kAxisColour);
    const std::string label = FormatTick(v, f.x.decimals);
    DrawText(cr, col + 0.5 - TextWidthPx(cr, label) / 2, x_label_top + tick_cap_px, label);
  }
  const int y_label_right = a.left - 1 - kTickLengthPx - kTickLabelGapPx;
  for (double v : f.y.ticks) {
    const int row = Pixel(f.Row(v));
    FillRect(cr, a.left - 1 - kTickLengthPx, row, kTickLengthPx, 1, kAxisColour);
    const std::string label = FormatTick(v, f.y.decimals);
    DrawText(cr, y_label_right - TextWidthPx(cr, label), row + 0.5 + tick_cap_px / 2, label);
  }

  // The title, shrunk (not below the label size) when it is wider than the panel.
  const double centre_x = a.left + a.width / 2.0;
  internal::SelectFont(cr, kTitleFontPx, /*bold=*/true);
  const double room_px = kPlotPanelWidthPx - 8;
  const double title_px = TextWidthPx(cr, panel.title);
  if (title_px > room_px) {
    internal::SelectFont(cr, std::max(kLabelFontPx, kTitleFontPx * room_px / title_px), true);
  }
  DrawText(cr, centre_x - TextWidthPx(cr, panel.title) / 2, kTitleTopPx + CapHeightPx(cr),
           panel.title);

  internal::SelectFont(cr, kLabelFontPx);
  const double label_cap_px = CapHeightPx(cr);
  DrawText(cr, centre_x - TextWidthPx(cr, panel.x_label) / 2,
           x_label_top + tick_cap_px + kXLabelGapPx + label_cap_px, panel.x_label);
  // The y label reads bottom to top: its baseline is a vertical line, the capitals to its left.
  cairo_move_to(cr, panel_left + kYLabelLeftPx + label_cap_px,
                a.top + (a.height + TextWidthPx(cr, panel.y_label)) / 2);
  cairo_rotate(cr, -kQuarterTurnRad);
  SetColour(cr, kTextColour);
  cairo_show_text(cr, panel.y_label.c_str());
  cairo_restore(cr);
}

// Where each legend entry goes: its top-left corner in the image.
struct LegendEntry {
  const PlotSeries* series;
  int x, y;
};

// `cr` is only measured with.
std::vector<LegendEntry> LayoutLegend(cairo_t* cr, const PlotPanel& first, int image_width,
                                      int* rows) {
  internal::SelectFont(cr, kLabelFontPx);
  std::vector<LegendEntry> entries;
  const int start_x = kPlotAreaLeftPx;
  int x = start_x, row = 0;
  for (const PlotSeries& s : first.series) {
    if (s.label.empty()) continue;
    const int width =
        kLegendSamplePx + kLegendTextGapPx + static_cast<int>(std::ceil(TextWidthPx(cr, s.label)));
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

// Each entry: a short sample of the line (with its marker) and the label.
void DrawLegend(cairo_t* cr, const std::vector<LegendEntry>& entries) {
  internal::SelectFont(cr, kLabelFontPx);
  const double cap_px = CapHeightPx(cr);
  for (const LegendEntry& e : entries) {
    const PlotSeries& s = *e.series;
    const int mid = e.y + kLegendRowPx / 2;
    cairo_save(cr);
    ClipTo(cr, {e.x, e.y, kLegendSamplePx, kLegendRowPx});
    SetLineStyle(cr, s);
    cairo_move_to(cr, e.x + 1, mid);
    cairo_line_to(cr, e.x + kLegendSamplePx - 1, mid);
    cairo_stroke(cr);
    if (s.markers) {
      AddSquare(cr, e.x + kLegendSamplePx / 2, mid - 1, kMarkerPx);
      cairo_fill(cr);
    }
    cairo_restore(cr);
    DrawText(cr, e.x + kLegendSamplePx + kLegendTextGapPx, mid + cap_px / 2, s.label);
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

internal::CairoSurface RenderPlot(const std::vector<PlotPanel>& panels) {
  // Every axis is resolved (and checked) and the legend laid out before anything is drawn; text is
  // measured on a scratch surface because the image height depends on the legend.
  const internal::CairoSurface scratch = internal::NewImageSurface(CAIRO_FORMAT_RGB24, 1, 1);
  const internal::CairoContext measure = internal::NewContext(scratch.get());
  std::vector<Frame> frames;
  for (size_t i = 0; i < panels.size(); ++i) {
    frames.push_back(MakeFrame(measure.get(), panels[i], static_cast<int>(i)));
  }
  const int width = kPlotPanelWidthPx * static_cast<int>(panels.size());
  int legend_rows = 0;
  const std::vector<LegendEntry> legend =
      LayoutLegend(measure.get(), panels[0], width, &legend_rows);
  int height = kPlotPanelHeightPx;
  if (legend_rows > 0) height += kLegendPadTopPx + legend_rows * kLegendRowPx + kLegendPadBottomPx;

  internal::CairoSurface surface = internal::NewImageSurface(CAIRO_FORMAT_RGB24, width, height);
  const internal::CairoContext context = internal::NewContext(surface.get());
  cairo_t* cr = context.get();
  FillRect(cr, 0, 0, width, height, kBackground);
  for (size_t i = 0; i < panels.size(); ++i) {
    const Frame& f = frames[i];
    DrawGrid(cr, f);
    for (const PlotBand& b : panels[i].bands) DrawBand(cr, f, b);
    for (const PlotSeries& s : panels[i].series) DrawSeries(cr, f, s);
    DrawAxes(cr, f, panels[i], static_cast<int>(i) * kPlotPanelWidthPx);
  }
  DrawLegend(cr, legend);
  const cairo_status_t status = cairo_status(cr);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cannot draw the plot: ") +
                             cairo_status_to_string(status));
  }
  return surface;
}

}  // namespace

void WritePlotPng(const std::vector<PlotPanel>& panels, const std::string& path) {
  CheckArguments(panels, path);
  // RGB24: cairo writes an opaque RGB PNG, under a temporary name that is then renamed.
  internal::WritePngAtomically(RenderPlot(panels).get(), path);
}

}  // namespace gonogo::geo
