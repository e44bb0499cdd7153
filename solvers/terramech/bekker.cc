#include "solvers/terramech/bekker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::terramech {

namespace {

using units::kHalfPi;
using units::kRadiansPerDegree;

// 8-point Gauss-Legendre rule on [-1, 1]: nodes +-x_i with weights w_i (Abramowitz & Stegun 25.4).
constexpr double kGaussNodes[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                   0.9602898564975363};
constexpr double kGaussWeights[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                     0.1012285362903763};

// Exponent of the endpoint map theta = end -/+ length u^q (see RigidWheelContactAt).
constexpr double kEndpointMapExponent = 3.0;

// Brent's method: absolute tolerance on theta_1 and an iteration cap it never reaches in practice.
constexpr double kEntryAngleToleranceRad = 1e-13;
constexpr int kMaxBrentIterations = 200;

bool PositiveFinite(double v) { return std::isfinite(v) && v > 0; }

void RequireSoil(const BekkerParameters& soil) { soil.Validate("soil."); }

void RequireLength(double v, const std::string& field) {
  Require(PositiveFinite(v), field, "must be a positive number of metres");
}

void RequireSlip(double slip) {
  Require(std::isfinite(slip) && slip >= 0 && slip <= 1, "slip", "must lie in [0, 1]");
}

void RequireLoad(double wheel_load_n) {
  Require(PositiveFinite(wheel_load_n), "wheel_load_n", "must be a positive number of newtons");
}

void RequireEntryAngle(double entry_angle_rad) {
  Require(std::isfinite(entry_angle_rad) && entry_angle_rad > 0 && entry_angle_rad <= kHalfPi,
          "entry_angle_rad", "must lie in (0, pi/2]");
}

std::string Format(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// 1 - (1 - exp(-x)) / x for x >= 0: the slip factor of the uniform-pressure thrust ([W08] 2.5).
// Its series x/2 - x^2/6 is used below 1e-6, where the quotient loses digits.
double UniformPressureSlipFactor(double x) {
  if (x < 1e-6) return x * (0.5 - x / 6.0);
  return 1.0 + std::expm1(-x) / x;
}

// The integrands of RigidWheelContactAt at one angle theta, given the normal stress there.
struct RimStress {
  double vertical = 0;  // sigma cos theta + tau sin theta
  double drawbar = 0;   // tau cos theta - sigma sin theta
  double shear = 0;     // tau
};

RimStress StressAt(const BekkerParameters& soil, double tan_phi, double radius_m, double slip,
                   double entry_angle_rad, double angle_rad, double normal_stress_pa) {
  // j = r [(theta_1 - theta) - (1 - s)(sin theta_1 - sin theta)]  [WR67] Part I; the sine
  // difference as 2 cos((theta_1 + theta)/2) sin((theta_1 - theta)/2) keeps j accurate (>= 0).
  const double gap = entry_angle_rad - angle_rad;
  const double sine_difference =
      2.0 * std::cos(0.5 * (entry_angle_rad + angle_rad)) * std::sin(0.5 * gap);
  const double j = std::max(0.0, radius_m * (gap - (1.0 - slip) * sine_difference));
  // Janosi-Hanamoto [JH61]: tau = (c + sigma tan phi)(1 - exp(-j/K)).
  const double tau =
      (soil.cohesion_pa + normal_stress_pa * tan_phi) * -std::expm1(-j / soil.shear_deformation_m);
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  return RimStress{normal_stress_pa * c + tau * s, tau * c - normal_stress_pa * s, tau};
}

// RigidWheelContactAt without the argument checks, for the equilibrium iteration.
RigidWheelContact ContactUnchecked(const BekkerParameters& soil, double radius_m, double width_m,
                                   const WongReeceOptions& options, double slip,
                                   double entry_angle_rad) {
  const double k = soil.kc / width_m + soil.kphi;
  const double theta_1 = entry_angle_rad;
  const double theta_m = (options.max_stress_c1 + options.max_stress_c2 * slip) * theta_1;
  const double theta_rear = -options.rear_angle_rad;
  const double front_length = theta_1 - theta_m;    // [theta_m, theta_1]
  const double rear_length = theta_m - theta_rear;  // [-theta_2, theta_m]
  const double tan_phi = std::tan(soil.friction_angle_deg * kRadiansPerDegree);
  const double k_rn = k * std::pow(radius_m, soil.n);
  const double q = kEndpointMapExponent;

  // u in [0, 1] per region: front theta = theta_1 - L_f u^q, rear theta = -theta_2 + L_r u^q, so
  // both stresses vanish at u = 0 and the mapped rear angle satisfies theta_1 - theta_e = L_f u^q:
  // the two regions share sigma(u) = k r^n (cos(theta_1 - L_f u^q) - cos theta_1)^n.
  double vertical = 0, drawbar = 0, shear = 0;
  const int panels = options.quadrature_panels;
  const double panel_width = 1.0 / panels;
  for (int p = 0; p < panels; ++p) {
    const double centre = (p + 0.5) * panel_width;
    for (int i = 0; i < 8; ++i) {
      const double node = (i < 4 ? -kGaussNodes[i] : kGaussNodes[i - 4]);
      const double weight = kGaussWeights[i < 4 ? i : i - 4] * 0.5 * panel_width;
      const double u = centre + 0.5 * panel_width * node;
      const double u_q = std::pow(u, q);
      const double du_weight = weight * q * u_q / u;  // weight * d(u^q)/du
      const double gap = front_length * u_q;          // theta_1 - theta_e
      const double depth_ratio = 2.0 * std::sin(theta_1 - 0.5 * gap) * std::sin(0.5 * gap);
      const double sigma = k_rn * std::pow(std::max(0.0, depth_ratio), soil.n);
      if (front_length > 0) {
        const RimStress f = StressAt(soil, tan_phi, radius_m, slip, theta_1, theta_1 - gap, sigma);
        const double w = du_weight * front_length;
        vertical += w * f.vertical;
        drawbar += w * f.drawbar;
        shear += w * f.shear;
      }
      if (rear_length > 0) {
        const RimStress r =
            StressAt(soil, tan_phi, radius_m, slip, theta_1, theta_rear + rear_length * u_q, sigma);
        const double w = du_weight * rear_length;
        vertical += w * r.vertical;
        drawbar += w * r.drawbar;
        shear += w * r.shear;
      }
    }
  }
  // W = r b Int(...), D = r b Int(...), T = r^2 b Int tau  [WR67] Part I.
  const double rb = radius_m * width_m;
  return RigidWheelContact{rb * vertical, rb * drawbar, rb * radius_m * shear};
}

}  // namespace

void WongReeceOptions::Validate(const std::string& p) const {
  Require(std::isfinite(max_stress_c1) && max_stress_c1 >= 0, p + "max_stress_c1",
          "must be a finite number >= 0");
  Require(std::isfinite(max_stress_c2) && max_stress_c2 >= 0, p + "max_stress_c2",
          "must be a finite number >= 0");
  Require(max_stress_c1 + max_stress_c2 < 1, p + "max_stress_c2",
          "c1 + c2 must be below 1 so that theta_m stays inside the contact arc");
  Require(std::isfinite(rear_angle_rad) && rear_angle_rad >= 0 && rear_angle_rad < kHalfPi,
          p + "rear_angle_rad", "must lie in [0, pi/2)");
  Require(quadrature_panels >= 1 && quadrature_panels <= 256, p + "quadrature_panels",
          "must lie in [1, 256]");
}

double SinkageModulus(const BekkerParameters& soil, double contact_width_m) {
  RequireSoil(soil);
  RequireLength(contact_width_m, "contact_width_m");
  return soil.kc / contact_width_m + soil.kphi;
}

double BekkerPressurePa(const BekkerParameters& soil, double contact_width_m, double sinkage_m) {
  Require(std::isfinite(sinkage_m) && sinkage_m >= 0, "sinkage_m", "must be a length >= 0");
  // p = (kc/b + kphi) z^n  [B56], [W08] 2.4.1.
  return SinkageModulus(soil, contact_width_m) * std::pow(sinkage_m, soil.n);
}

double PlateSinkageM(const BekkerParameters& soil, double contact_width_m, double pressure_pa) {
  Require(std::isfinite(pressure_pa) && pressure_pa >= 0, "pressure_pa",
          "must be a pressure >= 0 in Pa");
  // z = (p / k)^(1/n), the inverse of the Bekker law.
  return std::pow(pressure_pa / SinkageModulus(soil, contact_width_m), 1.0 / soil.n);
}

double JanosiHanamotoShearPa(const BekkerParameters& soil, double normal_stress_pa,
                             double shear_displacement_m) {
  RequireSoil(soil);
  Require(std::isfinite(normal_stress_pa) && normal_stress_pa >= 0, "normal_stress_pa",
          "must be a stress >= 0 in Pa");
  Require(std::isfinite(shear_displacement_m) && shear_displacement_m >= 0, "shear_displacement_m",
          "must be a length >= 0");
  // tau = (c + sigma tan phi)(1 - exp(-j/K))  [JH61], [W08] 2.4.3.
  return (soil.cohesion_pa +
          normal_stress_pa * std::tan(soil.friction_angle_deg * kRadiansPerDegree)) *
         -std::expm1(-shear_displacement_m / soil.shear_deformation_m);
}

double WheelShearDisplacementM(double radius_m, double slip, double entry_angle_rad,
                               double angle_rad) {
  RequireLength(radius_m, "radius_m");
  RequireSlip(slip);
  RequireEntryAngle(entry_angle_rad);
  Require(std::isfinite(angle_rad) && angle_rad > -kHalfPi && angle_rad <= entry_angle_rad,
          "angle_rad", "must lie in (-pi/2, theta_1]");
  const double gap = entry_angle_rad - angle_rad;
  const double sine_difference =
      2.0 * std::cos(0.5 * (entry_angle_rad + angle_rad)) * std::sin(0.5 * gap);
  return std::max(0.0, radius_m * (gap - (1.0 - slip) * sine_difference));
}

double MaxStressAngleRad(const WongReeceOptions& options, double slip, double entry_angle_rad) {
  options.Validate();
  RequireSlip(slip);
  RequireEntryAngle(entry_angle_rad);
  return (options.max_stress_c1 + options.max_stress_c2 * slip) * entry_angle_rad;
}

double WheelNormalStressPa(const BekkerParameters& soil, double radius_m, double width_m,
                           const WongReeceOptions& options, double slip, double entry_angle_rad,
                           double angle_rad) {
  const double k = SinkageModulus(soil, width_m);
  RequireLength(radius_m, "radius_m");
  Require(std::isfinite(angle_rad), "angle_rad", "must be finite");
  const double theta_m = MaxStressAngleRad(options, slip, entry_angle_rad);
  const double theta_rear = -options.rear_angle_rad;
  if (angle_rad > entry_angle_rad || angle_rad < theta_rear) return 0.0;
  // Front: the depth below the surface is r (cos theta - cos theta_1). Rear: the same profile at
  // the mapped angle theta_e [WR67] Part I.
  double gap = entry_angle_rad - angle_rad;
  if (angle_rad < theta_m) {
    gap = (angle_rad - theta_rear) / (theta_m - theta_rear) * (entry_angle_rad - theta_m);
  }
  const double depth_ratio =
      2.0 * std::sin(entry_angle_rad - 0.5 * gap) * std::sin(0.5 * gap);  // cos th_e - cos th_1
  return k * std::pow(radius_m * std::max(0.0, depth_ratio), soil.n);
}

RigidWheelContact RigidWheelContactAt(const BekkerParameters& soil, double radius_m, double width_m,
                                      const WongReeceOptions& options, double slip,
                                      double entry_angle_rad) {
  RequireSoil(soil);
  RequireLength(radius_m, "radius_m");
  RequireLength(width_m, "width_m");
  RequireSlip(slip);
  RequireEntryAngle(entry_angle_rad);
  options.Validate("options.");
  return ContactUnchecked(soil, radius_m, width_m, options, slip, entry_angle_rad);
}

RigidWheelState SolveRigidWheel(const BekkerParameters& soil, double radius_m, double width_m,
                                double wheel_load_n, double slip, const WongReeceOptions& options,
                                double entry_angle_guess_rad) {
  RequireSoil(soil);
  RequireLength(radius_m, "radius_m");
  RequireLength(width_m, "width_m");
  RequireLoad(wheel_load_n);
  RequireSlip(slip);
  options.Validate("options.");
  auto excess = [&](double theta_1) {
    if (theta_1 <= 0) return -wheel_load_n;  // no contact carries nothing
    return ContactUnchecked(soil, radius_m, width_m, options, slip, theta_1).vertical_load_n -
           wheel_load_n;
  };

  // Bracket: theta_1 = 0 carries nothing; theta_1 = 90 degrees is the axle at the surface. A
  // guess (the previous slip's theta_1) first tries [0.7, 1.4] x guess.
  double a = 0, fa = -wheel_load_n, b = kHalfPi, fb = std::numeric_limits<double>::quiet_NaN();
  if (std::isfinite(entry_angle_guess_rad) && entry_angle_guess_rad > 0 &&
      entry_angle_guess_rad < kHalfPi) {
    const double lo = 0.7 * entry_angle_guess_rad;
    const double hi = 1.4 * entry_angle_guess_rad;
    const double f_lo = excess(lo);
    if (f_lo >= 0) {
      b = lo;
      fb = f_lo;
    } else {
      a = lo;
      fa = f_lo;
      if (hi < kHalfPi) {
        const double f_hi = excess(hi);
        if (f_hi >= 0) {
          b = hi;
          fb = f_hi;
        }
      }
    }
  }
  if (std::isnan(fb)) {
    const double f_axle = excess(kHalfPi);
    if (!(f_axle >= 0)) {
      throw CannotCarryError("wheel_load_n",
                       "the soil cannot carry " + Format(wheel_load_n) +
                           " N on this wheel at slip " + Format(slip) +
                           ": the wheel would sink past its axle (at a sinkage of one radius it "
                           "carries " +
                           Format(f_axle + wheel_load_n) + " N)");
    }
    b = kHalfPi;
    fb = f_axle;
  }

  // Brent's method (Brent 1973, ch. 4): inverse quadratic interpolation or secant steps, with a
  // bisection whenever they would leave the bracket or converge too slowly. fa < 0 <= fb.
  double c = a, fc = fa, d = b - a, e = d;
  for (int iteration = 0; iteration < kMaxBrentIterations && fb != 0; ++iteration) {
    if ((fb > 0) == (fc > 0)) {
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (std::fabs(fc) < std::fabs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double tolerance =
        2.0 * std::numeric_limits<double>::epsilon() * std::fabs(b) + 0.5 * kEntryAngleToleranceRad;
    const double half_interval = 0.5 * (c - b);
    if (std::fabs(half_interval) <= tolerance) break;
    if (std::fabs(e) >= tolerance && std::fabs(fa) > std::fabs(fb)) {
      const double s = fb / fa;
      double p, q;
      if (a == c) {
        p = 2.0 * half_interval * s;
        q = 1.0 - s;
      } else {
        const double qa = fa / fc, r = fb / fc;
        p = s * (2.0 * half_interval * qa * (qa - r) - (b - a) * (r - 1.0));
        q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0) q = -q;
      p = std::fabs(p);
      if (2.0 * p <
          std::min(3.0 * half_interval * q - std::fabs(tolerance * q), std::fabs(e * q))) {
        e = d;
        d = p / q;
      } else {
        d = half_interval;
        e = d;
      }
    } else {
      d = half_interval;
      e = d;
    }
    a = b;
    fa = fb;
    b += std::fabs(d) > tolerance ? d : std::copysign(tolerance, half_interval);
    fb = excess(b);
  }

  RigidWheelState state;
  state.entry_angle_rad = std::clamp(b, std::numeric_limits<double>::min(), kHalfPi);
  state.max_stress_angle_rad = MaxStressAngleRad(options, slip, state.entry_angle_rad);
  // z = r (1 - cos theta_1) = 2 r sin^2(theta_1 / 2).
  const double half = std::sin(0.5 * state.entry_angle_rad);
  state.sinkage_m = 2.0 * radius_m * half * half;
  const RigidWheelContact contact =
      ContactUnchecked(soil, radius_m, width_m, options, slip, state.entry_angle_rad);
  state.drawbar_pull_n = contact.drawbar_pull_n;
  state.torque_nm = contact.torque_nm;
  state.gross_traction_n = contact.torque_nm / radius_m;
  state.motion_resistance_n = state.gross_traction_n - state.drawbar_pull_n;
  // eta = D (1 - s) r / T where both are positive.
  state.tractive_efficiency = (state.drawbar_pull_n > 0 && state.torque_nm > 0)
                                  ? state.drawbar_pull_n * (1.0 - slip) / state.gross_traction_n
                                  : 0.0;
  return state;
}

double BekkerRigidWheelSinkageM(const BekkerParameters& soil, double diameter_m, double width_m,
                                double wheel_load_n) {
  const double k = SinkageModulus(soil, width_m);
  RequireLength(diameter_m, "diameter_m");
  RequireLoad(wheel_load_n);
  const double n = soil.n;
  Require(n < 3, "soil.n", "Bekker's rigid-wheel closed form needs n < 3");
  // z0 = (3 W / ((3 - n) b k sqrt(D)))^(2/(2n+1))  [B56], [W08] 2.7.1.
  return std::pow(3.0 * wheel_load_n / ((3.0 - n) * width_m * k * std::sqrt(diameter_m)),
                  2.0 / (2.0 * n + 1.0));
}

double ParabolicRigidWheelSinkageM(const BekkerParameters& soil, double diameter_m, double width_m,
                                   double wheel_load_n) {
  const double k = SinkageModulus(soil, width_m);
  RequireLength(diameter_m, "diameter_m");
  RequireLoad(wheel_load_n);
  const double n = soil.n;
  // W = b k Int_0^z0 z^n dx with x^2 = D (z0 - z): W = (b k sqrt(D)/2) B(n+1, 1/2) z0^(n+1/2).
  const double beta = std::tgamma(n + 1.0) * std::tgamma(0.5) / std::tgamma(n + 1.5);
  return std::pow(2.0 * wheel_load_n / (width_m * k * std::sqrt(diameter_m) * beta),
                  2.0 / (2.0 * n + 1.0));
}

double CriticalGroundPressurePa(const BekkerParameters& soil, double diameter_m, double width_m,
                                double wheel_load_n) {
  // p_gcr = k z0^n  [W08] 2.7.2.
  return BekkerPressurePa(soil, width_m,
                          BekkerRigidWheelSinkageM(soil, diameter_m, width_m, wheel_load_n));
}

FlexibleTyreState SolveFlexibleTyre(const BekkerParameters& soil, const TyreGeometry& tyre,
                                    double ground_pressure_pa, double wheel_load_n, double slip) {
  RequireSoil(soil);
  tyre.Validate("tyre.");
  RequireLoad(wheel_load_n);
  RequireSlip(slip);
  Require(PositiveFinite(ground_pressure_pa), "tyre.inflation_pressure_pa",
          "the ground pressure of the elastic mode must be a positive pressure in Pa");
  FlexibleTyreState state;
  state.ground_pressure_pa = ground_pressure_pa;
  const double b = tyre.width_m;
  const double d = tyre.diameter_m;
  const double h = tyre.section_height_m;
  // Flat contact carrying W at p_g: A = W / p_g, l = A / b.
  const double area_m2 = wheel_load_n / ground_pressure_pa;
  state.contact_length_m = area_m2 / b;
  // The chord at a deflection of one section height bounds the flat length: 2 sqrt(d h - h^2).
  const double max_length_m = 2.0 * std::sqrt(d * h - h * h);
  if (state.contact_length_m > max_length_m) {
    throw InputError("tyre.inflation_pressure_pa",
                     "too low for the load: carrying " + Format(wheel_load_n) + " N at " +
                         Format(ground_pressure_pa) + " Pa needs a flat contact " +
                         Format(state.contact_length_m) + " m long, more than the " +
                         Format(max_length_m) + " m chord at full deflection");
  }
  // k with the tyre width, as [W08] 2.7.2 writes the elastic-mode sinkage.
  const double k = SinkageModulus(soil, b);
  const double n = soil.n;
  state.sinkage_m = std::pow(ground_pressure_pa / k, 1.0 / n);
  if (!(state.sinkage_m < 0.5 * d)) {
    throw CannotCarryError("wheel_load_n", "the soil cannot carry " + Format(wheel_load_n) +
                                         " N on this tyre: it would sink past its axle");
  }
  // Compaction resistance Rc = b k z^(n+1) / (n+1)  [B56], [W08] 2.7.2.
  state.motion_resistance_n = b * k * std::pow(state.sinkage_m, n + 1.0) / (n + 1.0);
  // Thrust of a uniform-pressure contact with j = s x  [JH61], [W08] 2.5.
  const double tan_phi = std::tan(soil.friction_angle_deg * kRadiansPerDegree);
  const double shear_strength_n = area_m2 * soil.cohesion_pa + wheel_load_n * tan_phi;
  state.gross_traction_n =
      shear_strength_n *
      UniformPressureSlipFactor(slip * state.contact_length_m / soil.shear_deformation_m);
  state.drawbar_pull_n = state.gross_traction_n - state.motion_resistance_n;
  state.torque_nm = state.gross_traction_n * tyre.RollingRadius();
  state.tractive_efficiency = (state.drawbar_pull_n > 0 && state.gross_traction_n > 0)
                                  ? state.drawbar_pull_n * (1.0 - slip) / state.gross_traction_n
                                  : 0.0;
  return state;
}

}  // namespace gonogo::terramech
