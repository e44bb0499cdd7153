// The calibration chain of the fe-de tier's verification (solvers/tiers/README.md, "fe-de
// against its continuum twin"): drained triaxial tests of the RVE that the fe-de tier puts at
// every integration point, the fe-classic soil (Drucker-Prager, matched to Mohr-Coulomb in
// triaxial compression) fitted to them by a fixed recipe, and that continuum soil run through the
// same rig as the fe-de curve (FeDeTier::RunContinuumTwin: same wheel, mesh, procedure, mass
// scaling and rim contact), so that the difference of the two curves is the difference of the two
// constitutive models.
//
// The recipe (nothing tuned; compression positive throughout):
//   peak       the largest deviator q* = sigma_1 - sigma_3 of each curve
//   c, phi     least squares of sigma_1* = N sigma_3* + 2 c sqrt(N) over the confinements
//              (sigma_3* the lateral stress measured at the peak),
//              sin(phi) = (N - 1) / (N + 1); a negative intercept is dropped (c = 0, the line
//              through the origin)
//   E          secant at half the peak, E50 = q* / 2 / eps_a50, averaged over the confinements (a
//              Drucker-Prager soil has one modulus)
//   nu         of the RVE's contact tangent before loading (its isotropic part), averaged: the
//              secant nu50 = (eps_a - eps_v) / (2 eps_a) of a dense packing is already past 0.5
//              by half the peak (dilation), which no elastic continuum can take; nu50 where
//              the tangent is unknown
//   psi        from the dilatancy just past the peak, D = d eps_v / d eps_a over the next
//              dilatancy_window of axial strain: sin(psi) = -D / (2 - D) (the flow direction of a
//              cone matched in triaxial compression, exact for Drucker-Prager's own curves),
//              averaged, within [0, phi]
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "solvers/dem/rve/rve_material.h"
#include "solvers/material/drucker_prager.h"

namespace gonogo::tiers {

// One drained triaxial compression test, compression positive.
struct TriaxialCurve {
  double confining_pa = 0;  // sigma_3, held
  std::vector<double> axial_strain;       // eps_a
  std::vector<double> volumetric_strain;  // eps_v, contraction positive
  std::vector<double> deviator_pa;        // q = sigma_1 - sigma_3
  // The lateral stress as measured (the servo's hold of confining_pa), Pa; empty: confining_pa.
  std::vector<double> lateral_stress_pa;
  // Poisson's ratio of the specimen's elastic (contact) stiffness before loading; NaN: unknown,
  // the fit then takes the secant nu50.
  double elastic_poisson = std::numeric_limits<double>::quiet_NaN();
};

// The soil's RVE template settled isotropically at confining_pa (as the fe-de bin settles each
// point at the stress of its depth), then compressed axially to max_axial_strain at the rate of
// inertial number `inertial_number` with the lateral stresses held by the RVE's servo; `rows` rows
// after the start. The cap is computed at the RVE's preparation pressure or above, so at a few
// kPa the actual inertial number is sqrt(p_prep / p) times larger: at 2e-4 the servo holds a
// 100-grain RVE's lateral stress within 10 % from 5 to 40 kPa; at 1e-3 it lets it climb 15 %, at
// the ci preset's 1e-2 to 3x the target (an undrained-like test).
TriaxialCurve RunRveTriaxial(const dem::rve::RveMaterial& rve, double confining_pa,
                             double max_axial_strain, int rows, double inertial_number = 2e-4);

// Simple shear of the soil's RVE, what a shear ring imposes on the soil under it: the template
// settled isotropically at normal_pa, then sheared (u_x = gamma z) to max_shear_strain at the
// rate of `inertial_number` with the normal stress sigma_zz held by the servo. Rows: gamma,
// tau = sigma_xz, the held sigma_zz (compression positive).
struct SimpleShearCurve {
  double normal_pa = 0;
  std::vector<double> shear_strain, shear_stress_pa, normal_stress_pa;
};
SimpleShearCurve RunRveSimpleShear(const dem::rve::RveMaterial& rve, double normal_pa,
                                   double max_shear_strain, int rows,
                                   double inertial_number = 2e-4);

// The friction angle a shear ring (or direct or simple shear) measures on its horizontal plane,
// atan(tau / sigma_n), of a soil with Mohr-Coulomb friction angle phi flowing with dilation angle
// psi: Davis (1968), for coaxial plastic flow with no strain along the plane,
//   tau / sigma_n = sin(phi) cos(psi) / (1 - sin(phi) sin(psi)),
// so tan(phi) for associated flow (psi = phi) and sin(phi) at constant volume (psi = 0, the
// critical state). Degrees in, degrees out; psi within [0, phi].
double HorizontalPlaneFrictionAngleDeg(double friction_angle_deg, double dilation_angle_deg);

// What a triaxial curve mobilises, compression positive: the friction angle
// asin((sigma_1 - sigma_3) / (sigma_1 + sigma_3)) with sigma_3 the measured lateral stress.
double MobilisedFrictionAngleDeg(const TriaxialCurve& curve, std::size_t row);

struct TriaxialCurveFit {
  double peak_deviator_pa = 0;
  double lateral_stress_at_peak_pa = 0;
  double axial_strain_at_peak = 0;
  double secant_young_pa = 0;      // E50
  double secant_poisson = 0;       // nu50
  double dilatancy_at_peak = 0;    // d eps_v / d eps_a just past the peak (< 0: dilating)
  double dilation_angle_deg = 0;   // of that dilatancy
};

struct TriaxialFit {
  material::DruckerPragerParams strength;  // E, nu, c, phi, psi; triaxial-compression match
  std::vector<TriaxialCurveFit> curves;    // in the order given
};

// The recipe above. Throws InputError("triaxial", ...) with fewer than two distinct
// confinements or a curve with no loading.
TriaxialFit FitDruckerPragerToTriaxials(const std::vector<TriaxialCurve>& curves,
                                        double dilatancy_window = 0.02);

}  // namespace gonogo::tiers
