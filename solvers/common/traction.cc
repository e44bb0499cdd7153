#include "solvers/common/traction.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <utility>

#include "solvers/common/errors.h"

namespace gonogo {

namespace {
bool PositiveFinite(double v) { return std::isfinite(v) && v > 0; }
}  // namespace

void TyreGeometry::Validate(const std::string& p) const {
  Require(PositiveFinite(diameter_m), p + "diameter_m", "must be a positive number of metres");
  Require(PositiveFinite(width_m), p + "width_m", "must be a positive number of metres");
  RequirePlausible(diameter_m, kPlausibleTyreDiameter, p + "diameter_m");
  RequirePlausible(width_m, kPlausibleTyreWidth, p + "width_m");
  Require(PositiveFinite(section_height_m), p + "section_height_m",
          "must be a positive number of metres");
  Require(section_height_m < 0.5 * diameter_m, p + "section_height_m",
          "must be less than half the diameter");
  Require(std::isfinite(deflection_m) && deflection_m >= 0, p + "deflection_m",
          "must be zero or a positive number of metres");
  Require(deflection_m < section_height_m, p + "deflection_m",
          "must be less than the section height");
  Require(std::isfinite(rolling_radius_m) && rolling_radius_m >= 0, p + "rolling_radius_m",
          "must be zero (derived) or a positive number of metres");
  Require(rolling_radius_m <= 0.5 * diameter_m, p + "rolling_radius_m",
          "must not exceed half the diameter");
  Require(std::isfinite(inflation_pressure_pa) && inflation_pressure_pa >= 0,
          p + "inflation_pressure_pa", "must be zero (not given) or a positive pressure in Pa");
}

void BekkerParameters::Validate(const std::string& p) const {
  Require(std::isfinite(n) && n > 0 && n <= 3, p + "n", "sinkage exponent must lie in (0, 3]");
  Require(std::isfinite(kc), p + "kc", "must be a finite modulus in N/m^(n+1)");
  Require(std::isfinite(kphi) && kphi >= 0, p + "kphi",
          "must be a non-negative modulus in N/m^(n+2)");
  Require(kc >= 0, p + "kc", "must not be negative");
  Require(kc > 0 || kphi > 0, p + "kphi", "kc and kphi cannot both be zero");
  Require(std::isfinite(cohesion_pa) && cohesion_pa >= 0, p + "cohesion_pa",
          "must be a non-negative stress in Pa");
  Require(std::isfinite(friction_angle_deg) && friction_angle_deg > 0 && friction_angle_deg < 90,
          p + "friction_angle_deg", "must lie in (0, 90) degrees");
  Require(std::isfinite(shear_deformation_m) && shear_deformation_m > 0,
          p + "shear_deformation_m", "must be a positive length in m");
}

SoilParameters BekkerParameters::ToSoilModel() const {
  return SoilParameters{"bekker",
                        {{"n", n},
                         {"kc", kc},
                         {"kphi", kphi},
                         {"cohesion_pa", cohesion_pa},
                         {"friction_angle_deg", friction_angle_deg},
                         {"shear_deformation_m", shear_deformation_m}}};
}

BekkerParameters BekkerParameters::FromSoilModel(const SoilParameters& p) {
  Require(p.model == "bekker", "parameters.model", "expected bekker parameters, got " + p.model);
  return BekkerParameters{p.Get("n"),           p.Get("kc"),
                          p.Get("kphi"),        p.Get("cohesion_pa"),
                          p.Get("friction_angle_deg"), p.Get("shear_deformation_m")};
}

void SoilState::Validate(const std::string& p) const {
  Require(std::isfinite(cone_index_pa), p + "cone_index_pa", "must be a finite number (got NaN or inf)");
  Require(cone_index_pa >= 0, p + "cone_index_pa", "must not be negative");
  RequirePlausible(cone_index_pa, kPlausibleConeIndex, p + "cone_index_pa");
  if (parameters) SoilModels().Validate(*parameters, p + "parameters");
}

void SurrogateGuard::Validate(const std::string& p) const {
  for (const auto& [value, name] : {std::pair{distance_threshold, "distance_threshold"},
                                    std::pair{spread_threshold, "spread_threshold"}}) {
    Require(!value || (std::isfinite(*value) && *value >= 0), p + name,
            "must be a number >= 0 (0: the model's own)");
  }
  Require(!pressure_floor_pa || (std::isfinite(*pressure_floor_pa) && *pressure_floor_pa >= 0),
          p + "pressure_floor_pa", "must be a number of pascals >= 0 (0: no floor)");
  Require(!return_after_steps || *return_after_steps >= 0, p + "return_after_steps",
          "must be >= 0 (0: never)");
  Require(!return_after_steps || *return_after_steps == 0 || fallback_enabled.value_or(true),
          p + "return_after_steps", "a point returns from its fallback, which this guard turns off");
}

void TractionRequest::Validate() const {
  soil.Validate("soil.");
  tyre.Validate("tyre.");
  Require(PositiveFinite(wheel_load_n), "wheel_load_n", "must be a positive number of newtons");
  RequirePlausible(wheel_load_n, kPlausibleWheelLoad, "wheel_load_n");
  Require(!slips.empty(), "slips", "must hold at least one slip value");
  for (double s : slips) Require(std::isfinite(s) && s >= 0 && s <= 1, "slips", "each slip must lie in [0, 1]");
  Require(surrogate_model.size() <= 64, "surrogate_model", "must be at most 64 characters");
  for (char c : surrogate_model) {
    Require(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.',
            "surrogate_model", "must be a model id: letters, digits, '-', '_' and '.'");
  }
  surrogate_guard.Validate("surrogate_guard.");
}

std::vector<double> TractionRequest::SlipSweep(double step) {
  Require(std::isfinite(step) && step > 0 && step <= 1, "slip_step", "must lie in (0, 1]");
  if (step < kMinSlipStep) {
    throw LimitError("slip_step", "a step below 0.001 (more than 1,001 slip points a curve) is "
                                  "beyond what the service computes or stores");
  }
  std::vector<double> slips;
  const int n = static_cast<int>(std::floor(1.0 / step + 1e-9));
  for (int i = 0; i <= n; ++i) slips.push_back(std::min(1.0, i * step));
  return slips;
}

double TractionCurve::DrawbarPullAt(double slip) const {
  if (points.empty()) return 0;
  if (slip <= points.front().slip) return points.front().drawbar_pull_n;
  for (size_t i = 1; i < points.size(); ++i) {
    if (slip <= points[i].slip) {
      const TractionPoint& a = points[i - 1];
      const TractionPoint& b = points[i];
      const double t = (slip - a.slip) / (b.slip - a.slip);
      return a.drawbar_pull_n + t * (b.drawbar_pull_n - a.drawbar_pull_n);
    }
  }
  return points.back().drawbar_pull_n;
}

}  // namespace gonogo
