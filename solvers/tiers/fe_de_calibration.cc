#include "solvers/tiers/fe_de_calibration.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::tiers {
namespace {

using dem::rve::Matrix3;

// Compression-positive axial strain, volumetric strain and deviator of an RVE snapshot (the RVE
// reports tension-positive quantities; axis z is the axial one).
void AppendRow(const dem::rve::RveSnapshot& snapshot, TriaxialCurve* curve) {
  const Matrix3 stress = -snapshot.stress_pa;
  const Matrix3 strain = -snapshot.strain;
  curve->axial_strain.push_back(strain(2, 2));
  curve->volumetric_strain.push_back(strain.trace());
  const double lateral_pa = 0.5 * (stress(0, 0) + stress(1, 1));
  curve->deviator_pa.push_back(stress(2, 2) - lateral_pa);
  curve->lateral_stress_pa.push_back(lateral_pa);
}

// Linear interpolation of x where y first reaches `level` going up from index 0 (y[0] < level).
double FirstCrossing(const std::vector<double>& x, const std::vector<double>& y, double level,
                     size_t* after) {
  for (size_t k = 1; k < y.size(); ++k) {
    if (y[k] >= level) {
      *after = k;
      const double t = (level - y[k - 1]) / (y[k] - y[k - 1]);
      return x[k - 1] + t * (x[k] - x[k - 1]);
    }
  }
  *after = y.size() - 1;
  return x.back();
}

TriaxialCurveFit FitCurve(const TriaxialCurve& curve, double dilatancy_window) {
  const std::vector<double>& ea = curve.axial_strain;
  const std::vector<double>& ev = curve.volumetric_strain;
  const std::vector<double>& q = curve.deviator_pa;
  Require(ea.size() == ev.size() && ea.size() == q.size() && ea.size() >= 3, "triaxial",
          "a curve needs at least 3 rows of equal length");
  TriaxialCurveFit fit;
  const size_t peak =
      static_cast<size_t>(std::max_element(q.begin(), q.end()) - q.begin());
  fit.peak_deviator_pa = q[peak];
  fit.lateral_stress_at_peak_pa =
      curve.lateral_stress_pa.empty() ? curve.confining_pa : curve.lateral_stress_pa.at(peak);
  fit.axial_strain_at_peak = ea[peak];
  Require(peak > 0 && q[peak] > q[0] && ea[peak] > ea[0], "triaxial",
          "the curve at " + std::to_string(curve.confining_pa) + " Pa has no loading");
  // Secant at half the peak, from the curve's start.
  size_t after = 0;
  const double half = q[0] + 0.5 * (q[peak] - q[0]);
  const double ea50 = FirstCrossing(ea, q, half, &after) - ea[0];
  const double t = (ea50 + ea[0] - ea[after - 1]) / (ea[after] - ea[after - 1]);
  const double ev50 = ev[after - 1] + t * (ev[after] - ev[after - 1]) - ev[0];
  fit.secant_young_pa = (half - q[0]) / ea50;
  fit.secant_poisson = (ea50 - ev50) / (2 * ea50);
  // Dilatancy just past the peak: least-squares slope of eps_v against eps_a over the window.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  for (size_t k = peak; k < ea.size() && ea[k] <= ea[peak] + dilatancy_window; ++k) {
    sx += ea[k];
    sy += ev[k];
    sxx += ea[k] * ea[k];
    sxy += ea[k] * ev[k];
    ++count;
  }
  const double denominator = count * sxx - sx * sx;
  fit.dilatancy_at_peak = count >= 2 && denominator > 0 ? (count * sxy - sx * sy) / denominator : 0;
  const double d = fit.dilatancy_at_peak;
  fit.dilation_angle_deg = units::RadiansToDegrees(std::asin(std::clamp(-d / (2 - d), 0.0, 1.0)));
  return fit;
}

// The RVE's rate at `inertial_number`: StableRate1S is its own cap, linear in its inertial number.
double RateAt1S(const dem::rve::Rve& specimen, double inertial_number) {
  return specimen.StableRate1S() * inertial_number / specimen.params().max_inertial_number;
}

// Runs `control` for max_strain / rate_1_s of DE time, calling `row` at the start and `rows`
// times on the way.
void RunInRows(dem::rve::Rve& specimen, const dem::rve::MixedControl& control, double rate_1_s,
               double max_strain, int rows, const std::function<void()>& row) {
  const long total_steps =
      static_cast<long>(std::ceil(max_strain / (rate_1_s * specimen.time_step_s())));
  const long steps_per_row = std::max(1L, total_steps / rows);
  row();
  for (long step = 0; step < total_steps;) {
    const long chunk = std::min(steps_per_row, total_steps - step);
    specimen.Run(control, static_cast<int>(chunk));
    step += chunk;
    row();
  }
}

void RequireLoading(double pressure_pa, double max_strain, double strain_limit,
                    const char* strain_limit_text, int rows, double inertial_number,
                    const std::string& test) {
  Require(std::isfinite(pressure_pa) && pressure_pa > 0, test + ".pressure_pa",
          "must be a positive pressure, Pa");
  Require(std::isfinite(max_strain) && max_strain > 0 && max_strain <= strain_limit,
          test + ".max_strain", std::string("must lie in (0, ") + strain_limit_text + "]");
  Require(rows >= 2, test + ".rows", "must be at least 2");
  Require(std::isfinite(inertial_number) && inertial_number > 0 && inertial_number <= 0.1,
          test + ".inertial_number", "must lie in (0, 0.1]");
}

}  // namespace

TriaxialCurve RunRveTriaxial(const dem::rve::RveMaterial& rve, double confining_pa,
                             double max_axial_strain, int rows, double inertial_number) {
  RequireLoading(confining_pa, max_axial_strain, 0.5, "0.5", rows, inertial_number, "triaxial");
  dem::rve::Rve specimen = rve.initial();
  specimen.SettleIsotropic(confining_pa);
  TriaxialCurve curve;
  curve.confining_pa = confining_pa;
  // Isotropic projection of the contact tangent (Voigt, engineering shear): bulk and shear moduli.
  const dem::rve::Voigt6x6 c = specimen.TangentPa();
  const double bulk_pa = (c.topLeftCorner<3, 3>().sum()) / 9;
  const double shear_pa = (c(0, 0) + c(1, 1) + c(2, 2) - c(0, 1) - c(0, 2) - c(1, 2) +
                           3 * (c(3, 3) + c(4, 4) + c(5, 5))) / 15;
  curve.elastic_poisson = (3 * bulk_pa - 2 * shear_pa) / (2 * (3 * bulk_pa + shear_pa));
  const double rate_1_s = RateAt1S(specimen, inertial_number);
  dem::rve::MixedControl control;
  control.strain_rate_1_s(2, 2) = -rate_1_s;
  for (int d = 0; d < 2; ++d) {
    control.stress_controlled[d][d] = true;
    control.target_stress_pa(d, d) = -confining_pa;
  }
  RunInRows(specimen, control, rate_1_s, max_axial_strain, rows,
            [&] { AppendRow(specimen.Snapshot(), &curve); });
  return curve;
}

SimpleShearCurve RunRveSimpleShear(const dem::rve::RveMaterial& rve, double normal_pa,
                                   double max_shear_strain, int rows, double inertial_number) {
  RequireLoading(normal_pa, max_shear_strain, 5, "5", rows, inertial_number, "simple_shear");
  dem::rve::Rve specimen = rve.initial();
  specimen.SettleIsotropic(normal_pa);
  const double rate_1_s = RateAt1S(specimen, inertial_number);
  dem::rve::MixedControl control;
  control.strain_rate_1_s(0, 2) = rate_1_s;  // u_x = gamma z
  control.stress_controlled[2][2] = true;
  control.target_stress_pa(2, 2) = -normal_pa;
  SimpleShearCurve curve;
  curve.normal_pa = normal_pa;
  RunInRows(specimen, control, rate_1_s, max_shear_strain, rows, [&] {
    const dem::rve::RveSnapshot snapshot = specimen.Snapshot();
    curve.shear_strain.push_back(2 * snapshot.strain(0, 2));
    curve.shear_stress_pa.push_back(std::abs(snapshot.stress_pa(0, 2)));
    curve.normal_stress_pa.push_back(-snapshot.stress_pa(2, 2));
  });
  return curve;
}

double HorizontalPlaneFrictionAngleDeg(double friction_angle_deg, double dilation_angle_deg) {
  if (!(friction_angle_deg > 0 && friction_angle_deg < 90)) {
    throw InputError("friction_angle_deg", "must be in (0, 90) deg");
  }
  if (!(dilation_angle_deg >= 0 && dilation_angle_deg <= friction_angle_deg)) {
    throw InputError("dilation_angle_deg", "must be in [0, friction_angle_deg]");
  }
  const double sin_phi = std::sin(units::DegreesToRadians(friction_angle_deg));
  const double psi = units::DegreesToRadians(dilation_angle_deg);
  // Davis (1968): tau / sigma_n = sin(phi) cos(psi) / (1 - sin(phi) sin(psi)).
  return units::RadiansToDegrees(
      std::atan(sin_phi * std::cos(psi) / (1 - sin_phi * std::sin(psi))));
}

double MobilisedFrictionAngleDeg(const TriaxialCurve& curve, std::size_t row) {
  const double sigma_3 =
      curve.lateral_stress_pa.empty() ? curve.confining_pa : curve.lateral_stress_pa.at(row);
  const double sigma_1 = sigma_3 + curve.deviator_pa.at(row);
  return units::RadiansToDegrees(std::asin((sigma_1 - sigma_3) / (sigma_1 + sigma_3)));
}

TriaxialFit FitDruckerPragerToTriaxials(const std::vector<TriaxialCurve>& curves,
                                        double dilatancy_window) {
  Require(curves.size() >= 2, "triaxial", "needs curves at two confinements at least");
  Require(std::isfinite(dilatancy_window) && dilatancy_window > 0, "triaxial.dilatancy_window",
          "must be a positive strain");
  TriaxialFit fit;
  double young = 0, poisson = 0, sin_psi = 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const TriaxialCurve& curve : curves) {
    const TriaxialCurveFit one = FitCurve(curve, dilatancy_window);
    fit.curves.push_back(one);
    young += one.secant_young_pa;
    poisson += std::isfinite(curve.elastic_poisson) ? curve.elastic_poisson : one.secant_poisson;
    sin_psi += std::sin(units::DegreesToRadians(one.dilation_angle_deg));
    const double sigma3 = one.lateral_stress_at_peak_pa;
    const double sigma1 = sigma3 + one.peak_deviator_pa;
    sx += sigma3;
    sy += sigma1;
    sxx += sigma3 * sigma3;
    sxy += sigma3 * sigma1;
  }
  const double n = static_cast<double>(curves.size());
  const double denominator = n * sxx - sx * sx;
  Require(denominator > 0, "triaxial", "needs two distinct confinements");
  double slope = (n * sxy - sx * sy) / denominator;  // N = (1 + sin phi) / (1 - sin phi)
  double intercept = (sy - slope * sx) / n;           // 2 c sqrt(N)
  if (intercept < 0) {  // cohesionless: the line through the origin
    slope = sxy / sxx;
    intercept = 0;
  }
  Require(slope > 1, "triaxial", "the peaks do not rise with confinement faster than it");
  material::DruckerPragerParams& dp = fit.strength;
  dp.match = material::DruckerPragerParams::Match::kTriaxialCompression;
  dp.friction_angle_deg = units::RadiansToDegrees(std::asin((slope - 1) / (slope + 1)));
  dp.cohesion_pa = intercept / (2 * std::sqrt(slope));
  dp.young_pa = young / n;
  dp.poisson = std::clamp(poisson / n, 0.0, 0.49);
  dp.dilation_angle_deg = std::min(units::RadiansToDegrees(std::asin(sin_psi / n)),
                                   dp.friction_angle_deg);
  return fit;
}

}  // namespace gonogo::tiers
