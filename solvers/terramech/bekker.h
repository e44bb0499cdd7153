// Bekker-Wong terramechanics of one wheel: the Bekker pressure-sinkage and Janosi-Hanamoto shear
// laws, the Wong-Reece driven rigid wheel (stresses over the contact arc, vertical equilibrium,
// drawbar pull and torque), Bekker's closed forms, and Wong's flexible-tyre (elastic mode) method.
// Pure functions, SI units; angles in radians measured from the vertical through the axle,
// positive forward (towards the entry point). Equations and sources: solvers/terramech/README.md.
//
// Sources
//   [W08]  Wong, J.Y. (2008) Theory of Ground Vehicles, 4th ed., Wiley. Ch. 2: section 2.4.1
//          (Bekker pressure-sinkage), 2.4.3 (Janosi-Hanamoto shear), 2.5 (thrust under a uniform
//          pressure), 2.7.1 (rigid wheel: Bekker's sinkage closed form), 2.7.2 (pneumatic tyre:
//          critical ground pressure p_gcr, rigid and elastic modes), Table 2.3 (terrain values).
//   [W10]  Wong, J.Y. (2010) Terramechanics and Off-Road Vehicle Engineering, 2nd ed., Elsevier.
//          Ch. 4-5: the same relations and the Wong-Reece stress model of the driven wheel.
//   [WR67] Wong, J.Y., Reece, A.R. (1967) Prediction of rigid wheel performance based on the
//          analysis of soil-wheel stresses. Part I: Performance of driven rigid wheels.
//          J. Terramechanics 4(1), 81-98. Part II: towed rigid wheels, 4(2), 7-25.
//   [B56]  Bekker, M.G. (1956) Theory of Land Locomotion; [B69] (1969) Introduction to
//          Terrain-Vehicle Systems. University of Michigan Press.
//   [JH61] Janosi, Z., Hanamoto, B. (1961) The analytical determination of drawbar pull as a
//          function of slip for tracked vehicles in deformable soils. Proc. 1st ISTVS Conf., Turin.
// Equation numbers of [W08] and [WR67] are not quoted: the printed books and papers could not be
// consulted to check them, so sections are cited instead.
#pragma once

#include "solvers/common/traction.h"

namespace gonogo::terramech {

// ---- Wong-Reece stress-distribution constants ----
// theta_m / theta_1 = c1 + c2 s: the angle of maximum normal stress moves forward with slip.
// [WR67] Part I found c1 = 0.43, c2 = 0.32 for their sand (as transcribed in the open Wong-Reece
// implementation of Madsen, Project Chrono, 2013). Rover studies after Ishigami et al. (2007,
// J. Field Robotics 24(3)) use about 0.4 and 0.15; both are within the published scatter.
inline constexpr double kWongReeceC1 = 0.43;
inline constexpr double kWongReeceC2 = 0.32;

// Options of the Wong-Reece rigid-wheel model.
struct WongReeceOptions {
  double max_stress_c1 = kWongReeceC1;  // c1 of theta_m = (c1 + c2 s) theta_1, -
  double max_stress_c2 = kWongReeceC2;  // c2, -
  double rear_angle_rad = 0;            // theta_2 >= 0: contact behind the vertical (rebound)
  // Composite Gauss-Legendre quadrature: 8 nodes per panel, this many panels on each of the two
  // regions [-theta_2, theta_m] and [theta_m, theta_1] (see RigidWheelContactAt).
  int quadrature_panels = 4;

  // Throws InputError naming the field: c1, c2 >= 0, c1 + c2 < 1 (theta_m inside the arc),
  // theta_2 in [0, pi/2), panels in [1, 256].
  void Validate(const std::string& field_prefix = "") const;
};

// Pressure-sinkage modulus k = kc / b + kphi of a contact of smaller dimension b, N/m^(n+2).
double SinkageModulus(const BekkerParameters& soil, double contact_width_m);

// Bekker pressure-sinkage [B56], [W08] 2.4.1: p = (kc / b + kphi) z^n, Pa. z >= 0.
double BekkerPressurePa(const BekkerParameters& soil, double contact_width_m, double sinkage_m);

// Its inverse for a flat plate or track under a uniform pressure p: z = (p / (kc/b + kphi))^(1/n).
double PlateSinkageM(const BekkerParameters& soil, double contact_width_m, double pressure_pa);

// Janosi-Hanamoto shear stress [JH61], [W08] 2.4.3, Pa:
//   tau = (c + sigma tan phi) (1 - exp(-j / K)),  sigma >= 0, j >= 0.
double JanosiHanamotoShearPa(const BekkerParameters& soil, double normal_stress_pa,
                             double shear_displacement_m);

// Shear displacement of the soil at angle theta on a driven rigid wheel [WR67] Part I,
//   j(theta) = r [(theta_1 - theta) - (1 - s)(sin theta_1 - sin theta)],
// which is >= 0 for theta <= theta_1.
double WheelShearDisplacementM(double radius_m, double slip, double entry_angle_rad,
                               double angle_rad);

// Angle of maximum normal stress [WR67] Part I: theta_m = (c1 + c2 s) theta_1.
double MaxStressAngleRad(const WongReeceOptions& options, double slip, double entry_angle_rad);

// Wong-Reece normal stress on the rim at angle theta [WR67] Part I, with k = kc/b + kphi:
//   front, theta_m <= theta <= theta_1:  sigma = k r^n (cos theta - cos theta_1)^n
//   rear, -theta_2 <= theta <= theta_m:  sigma = k r^n (cos theta_e - cos theta_1)^n,
//     theta_e = theta_1 - (theta + theta_2) / (theta_m + theta_2) (theta_1 - theta_m)
// so the rear profile is the front one mapped onto [-theta_2, theta_m]; zero outside the arc.
double WheelNormalStressPa(const BekkerParameters& soil, double radius_m, double width_m,
                           const WongReeceOptions& options, double slip, double entry_angle_rad,
                           double angle_rad);

// Resultants of the rim stresses for one entry angle theta_1 [WR67] Part I:
//   W = r b Int (sigma cos theta + tau sin theta) dtheta        vertical load carried, N
//   D = r b Int (tau cos theta - sigma sin theta) dtheta        drawbar pull, N
//   T = r^2 b Int tau dtheta                                    driving torque, N m
// over [-theta_2, theta_1]. Quadrature: each region is mapped to u in [0, 1] by
// theta = end -/+ length u^3 at the end where the stress vanishes like distance^n (the entry
// angle for the front, -theta_2 for the rear), which removes the endpoint singularity of the
// derivative, then integrated by composite 8-point Gauss-Legendre on `quadrature_panels` panels.
// With the default 4 panels the worst relative error found against 256 panels is 1.4e-7 (n 0.11 to
// 1.6, theta_1 0.01 rad to pi/2, slip 0 to 1, K 6 and 25 mm, theta_2 0 and 0.1 rad); 2 panels give
// 1e-4, 8 panels 1e-9. bekker_test checks 1e-6.
struct RigidWheelContact {
  double vertical_load_n = 0;
  double drawbar_pull_n = 0;
  double torque_nm = 0;
};
RigidWheelContact RigidWheelContactAt(const BekkerParameters& soil, double radius_m, double width_m,
                                      const WongReeceOptions& options, double slip,
                                      double entry_angle_rad);

// A driven rigid wheel in equilibrium at one slip.
struct RigidWheelState {
  double entry_angle_rad = 0;       // theta_1, from W(theta_1) = wheel load
  double max_stress_angle_rad = 0;  // theta_m
  double sinkage_m = 0;             // z = r (1 - cos theta_1)
  double drawbar_pull_n = 0;        // D
  double torque_nm = 0;             // T
  double gross_traction_n = 0;      // T / r
  double motion_resistance_n = 0;   // T / r - D
  double tractive_efficiency = 0;   // D (1 - s) r / T; 0 where D <= 0 or T <= 0
};

// Solves W(theta_1) = wheel_load_n for theta_1 in (0, pi/2] (bracket [0, pi/2] and Brent's method
// to 1e-13 rad), then evaluates the resultants. `entry_angle_guess_rad` (> 0) narrows the first
// bracket (the previous slip's theta_1 in a sweep); it never changes the answer. Throws
// CannotCarryError("wheel_load_n", ...) when even theta_1 = 90 degrees (sinkage = r) cannot carry
// the load, and InputError naming the field for bad arguments. Never returns NaN.
RigidWheelState SolveRigidWheel(const BekkerParameters& soil, double radius_m, double width_m,
                                double wheel_load_n, double slip,
                                const WongReeceOptions& options = {},
                                double entry_angle_guess_rad = 0);

// ---- Bekker's closed forms [B56], [W08] 2.7.1-2.7.2 ----

// Small-sinkage rigid-wheel sinkage: W = b k sqrt(D) z0^((2n+1)/2) (3 - n)/3, i.e.
//   z0 = (3 W / ((3 - n) b (kc/b + kphi) sqrt(D)))^(2 / (2n + 1)).
// Bekker's (3 - n)/3 approximates B(n + 1, 1/2) / 2 (exact at n = 0 and n = 1).
double BekkerRigidWheelSinkageM(const BekkerParameters& soil, double diameter_m, double width_m,
                                double wheel_load_n);

// The same parabolic-contact integral without Bekker's approximation of the Beta function:
//   W = (b k sqrt(D) / 2) B(n + 1, 1/2) z0^((2n+1)/2).
double ParabolicRigidWheelSinkageM(const BekkerParameters& soil, double diameter_m, double width_m,
                                   double wheel_load_n);

// Critical ground pressure [W08] 2.7.2: the pressure under the lowest point of a rigid wheel of the
// tyre's size in equilibrium, p_gcr = k z0^n with Bekker's z0, i.e.
//   p_gcr = k^(1/(2n+1)) (3 W / ((3 - n) b sqrt(D)))^(2n/(2n+1)).
// A tyre with p_i + p_c > p_gcr runs in the rigid mode, otherwise in the elastic mode.
double CriticalGroundPressurePa(const BekkerParameters& soil, double diameter_m, double width_m,
                                double wheel_load_n);

// ---- Pneumatic tyre in the elastic mode [W08] 2.7.2 and 2.5 ----

// The tyre flattens until its ground pressure is p_g = p_i + p_c over a flat contact of width b
// and length l = W / (b p_g). Then
//   z  = (p_g / k)^(1/n), k = kc/b + kphi with the tyre width b  ([W08] 2.7.2)
//   Rc = b k z^(n+1) / (n + 1)                                   compaction resistance
//   F  = (A c + W tan phi) [1 - K/(s l) (1 - exp(-s l / K))]     thrust, A = b l  ([W08] 2.5)
//   D  = F - Rc,  T = F r_rolling,  eta = D (1 - s) / F (0 where D <= 0 or F <= 0).
struct FlexibleTyreState {
  double ground_pressure_pa = 0;  // p_g
  double contact_length_m = 0;    // l
  double sinkage_m = 0;
  double drawbar_pull_n = 0;
  double torque_nm = 0;
  double gross_traction_n = 0;     // F
  double motion_resistance_n = 0;  // Rc
  double tractive_efficiency = 0;
};
// Throws InputError("tyre.inflation_pressure_pa", ...) when the flat contact the load needs is
// longer than the chord at a deflection of one section height (the tyre would bottom out), and
// InputError("wheel_load_n", ...) when the sinkage would reach the axle.
FlexibleTyreState SolveFlexibleTyre(const BekkerParameters& soil, const TyreGeometry& tyre,
                                    double ground_pressure_pa, double wheel_load_n, double slip);

}  // namespace gonogo::terramech
