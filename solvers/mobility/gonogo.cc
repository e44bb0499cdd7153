#include "solvers/mobility/gonogo.h"

#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::mobility {

namespace {

// Linear interpolation of y(x) on an ascending table.
double Interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  const size_t i = std::upper_bound(x.begin(), x.end(), at) - x.begin();
  const double t = (at - x[i - 1]) / (x[i] - x[i - 1]);
  return y[i - 1] + t * (y[i] - y[i - 1]);
}

// Smallest slip in [0, max_slip] at which the total drawbar pull reaches `required_n`, or -1.
double BalancingSlip(const VehicleTraction& t, double required_n, double max_slip) {
  if (t.drawbar_pull_n.front() >= required_n) return t.slip.front();
  for (size_t i = 1; i < t.slip.size() && t.slip[i - 1] < max_slip; ++i) {
    const double d0 = t.drawbar_pull_n[i - 1] - required_n;
    const double d1 = t.drawbar_pull_n[i] - required_n;
    if (d1 >= 0) {
      const double s = t.slip[i - 1] + (t.slip[i] - t.slip[i - 1]) * (-d0) / (d1 - d0);
      return s <= max_slip ? s : -1;
    }
  }
  return -1;
}

}  // namespace

void Criteria::Validate() const {
  Require(std::isfinite(design_slip) && design_slip > 0 && design_slip < 1, "criteria.design_slip",
          "must lie in (0, 1)");
  Require(std::isfinite(max_slip) && max_slip >= design_slip && max_slip <= 1, "criteria.max_slip",
          "must lie in [design_slip, 1]");
  Require(std::isfinite(go_margin) && go_margin >= 0 && go_margin < 1, "criteria.go_margin",
          "must lie in [0, 1)");
  Require(passes == 1 || passes == 50, "criteria.passes", "must be 1 or 50");
  Require(std::isfinite(slip_step) && slip_step >= 0.001 && slip_step <= 0.25,
          "criteria.slip_step", "must lie in [0.001, 0.25]");
}

VehicleTraction CombineAxles(const VehicleSpec& v, const std::vector<const TractionCurve*>& curves) {
  Require(curves.size() == v.axles.size(), "curves", "one traction curve per axle is needed");
  VehicleTraction t;
  for (const TractionCurve* c : curves) {
    if (!c->immobile_reason.empty()) {
      t.immobile_reason = c->immobile_reason;
      return t;
    }
  }
  for (const TractionPoint& p : curves[0]->points) t.slip.push_back(p.slip);
  t.drawbar_pull_n.assign(t.slip.size(), 0.0);
  t.gross_traction_n.assign(t.slip.size(), 0.0);
  for (size_t a = 0; a < v.axles.size(); ++a) {
    const TractionCurve& c = *curves[a];
    Require(c.points.size() == t.slip.size(), "curves", "axle curves must share one slip sweep");
    const double wheels = v.axles[a].wheels;
    for (size_t i = 0; i < t.slip.size(); ++i) {
      if (v.axles[a].driven) {
        t.drawbar_pull_n[i] += wheels * c.points[i].drawbar_pull_n;
        t.gross_traction_n[i] += wheels * c.points[i].gross_traction_n;
      } else {
        t.drawbar_pull_n[i] += wheels * c.points[0].drawbar_pull_n;
      }
    }
  }
  return t;
}

CellVerdict EvaluateCell(const VehicleSpec& v, const Criteria& c, const VehicleTraction& t,
                         double slope_percent) {
  if (!std::isfinite(slope_percent)) return {GoClass::kNoData, 0.0f};
  if (!t.immobile_reason.empty()) return {GoClass::kNoGo, 0.0f, NoGoReason::kCannotCarry};
  if (t.slip.empty()) return {GoClass::kNoData, 0.0f};
  if (!t.soft_soil_ok) return {GoClass::kNoGo, 0.0f, NoGoReason::kSoftSoil};
  const double weight_n = v.WeightN();
  const double grade_sin = std::sin(std::atan(std::abs(slope_percent) / 100.0));
  const double required_n = weight_n * grade_sin;

  const double s_star = BalancingSlip(t, required_n, c.max_slip);
  if (s_star < 0) return {GoClass::kNoGo, 0.0f, NoGoReason::kTraction};

  const double margin_at_design =
      Interpolate(t.slip, t.drawbar_pull_n, c.design_slip) / weight_n - grade_sin;
  const GoClass go_class = margin_at_design >= c.go_margin ? GoClass::kGo : GoClass::kSlowGo;

  // Power-limited speed at the balancing slip.
  const double max_speed_mps = v.max_speed_kmh / 3.6;
  const double gross_n = Interpolate(t.slip, t.gross_traction_n, s_star);
  double speed_mps = max_speed_mps;
  if (gross_n > 0) {
    speed_mps = std::min(max_speed_mps,
                         v.drive_power_w * v.driveline_efficiency * (1.0 - s_star) / gross_n);
  }
  return {go_class, static_cast<float>(speed_mps * 3.6)};
}

}  // namespace gonogo::mobility
