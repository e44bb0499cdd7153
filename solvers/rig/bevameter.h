// The virtual bevameter of seed 000's calibration, run over any soil bin (soil_bin.h): plate
// pressure-sinkage tests with two plate sizes and shear-ring tests at several normal pressures,
// fitted to the Bekker-Janosi parameters the bekker tier reads:
//   Bekker (1969):          p = (k_c / b + k_phi) z^n             (b: plate radius)
//   Mohr-Coulomb:           tau_max = c + sigma tan(phi)
//   Janosi & Hanamoto (1961): tau = tau_max (1 - exp(-j / K))
// (Wong 2008, Theory of Ground Vehicles 4th ed., sections 2.4.1 and 2.4.3.)
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "solvers/common/traction.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/soil_bin.h"
#include "solvers/rig/wheel_rig.h"

namespace gonogo::rig {

struct BevameterSpec {
  double small_plate_radius_m = 0.05;
  double large_plate_radius_m = 0.10;
  double plate_sinkage_m = 0.04;           // pushed to this depth
  double plate_speed_m_s = 0.2;
  double ring_inner_radius_m = 0.10;
  double ring_outer_radius_m = 0.20;
  std::vector<double> ring_normal_pressures_pa = {10e3, 20e3, 40e3};
  double ring_shear_displacement_m = 0.04;  // at the ring's mean radius
  double ring_speed_m_s = 0.2;              // at the mean radius
  // Smooth start of the plate push and of the ring's turn, s.
  double start_ramp_s = 0.02;
  // Mass damping while the ring turns, as a fraction of the bin's settling damping (the soil
  // under the ring turns with it, so a mass-scaled bin feels this drag scaled up).
  double ring_damping_fraction = 0.2;
  void Validate(const std::string& field_prefix) const;
};

struct PlateTest {
  double radius_m = 0;      // of the meshed (stair-stepped) plate with the same area
  std::vector<double> sinkage_m, pressure_pa;
  double k = 0, n = 0;      // p = k z^n fitted to this plate
};

struct RingTest {
  double normal_pressure_pa = 0;
  std::vector<double> shear_displacement_m, shear_stress_pa;
  double max_shear_stress_pa = 0;
};

struct BevameterResult {
  std::vector<PlateTest> plates;
  std::vector<RingTest> rings;
  BekkerParameters fitted;  // n, kc, kphi, c, phi, K
};

// Plate tests in quarter bins, ring tests in whole bins of `soil_bin`, each settled 0.05 s first.
// options.element_size_m: the bins' resolution (0: a quarter of the small plate's radius for the
// plates, a quarter of the ring's width for the rings); progress and cancelled as the wheel rig's.
BevameterResult RunVirtualBevameter(const SoilBinFactory& soil_bin, const BevameterSpec& spec,
                                    const RigOptions& options);
// The same on the fe-classic bins of an FeSoil (FeClassicBins).
BevameterResult RunVirtualBevameter(const FeSoil& soil, const BevameterSpec& spec,
                                    const RigOptions& options);
void PrintBevameter(const BevameterResult& result, std::FILE* out);

// --- the fits, also usable on measured data -----------------------------------------------------
struct PowerLaw {
  double k = 0, n = 0;  // y = k x^n
};
// Least squares of ln y = ln k + n ln x over the points with x, y > 0 (at least two).
PowerLaw FitPowerLaw(const std::vector<double>& x, const std::vector<double>& y);
// k_c and k_phi from two plates: k_i = k_c / b_i + k_phi (Wong 2008, section 2.4.1).
void FitBekkerModuli(double radius1_m, double k1, double radius2_m, double k2, double* kc,
                     double* kphi);
// c and phi (degrees) by least squares of tau_max against sigma (at least two pressures).
void FitMohrCoulomb(const std::vector<double>& normal_pa, const std::vector<double>& max_shear_pa,
                    double* cohesion_pa, double* friction_angle_deg);
// K by least squares of ln(1 - tau / tau_max) = -j / K over the points with
// 0.05 < tau / tau_max < 0.95.
double FitShearDeformationModulus(const std::vector<double>& j_m,
                                  const std::vector<double>& tau_pa, double max_tau_pa);

}  // namespace gonogo::rig
