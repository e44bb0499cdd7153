// The virtual bevameter: the fits against synthetic data with known parameters, then plate and
// shear-ring tests on the fe-classic soil, whose fitted strength is checked against the soil's
// own c and phi.
#include "solvers/rig/bevameter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/units.h"
#include "solvers/rig/fe_soils.h"

namespace gonogo::rig {
namespace {

TEST(BevameterFitTest, RecoversBekkerAndJanosiParametersFromSyntheticTests) {
  const double n = 0.79, kc = 102e3, kphi = 5301e3;  // LETE sand, Wong (2008) Table 2.3
  std::vector<double> z, p1, p2;
  for (int i = 1; i <= 20; ++i) {
    z.push_back(0.002 * i);
    p1.push_back((kc / 0.05 + kphi) * std::pow(z.back(), n));
    p2.push_back((kc / 0.10 + kphi) * std::pow(z.back(), n));
  }
  const PowerLaw f1 = FitPowerLaw(z, p1), f2 = FitPowerLaw(z, p2);
  EXPECT_NEAR(f1.n, n, 1e-9);
  double fitted_kc = 0, fitted_kphi = 0;
  FitBekkerModuli(0.05, f1.k, 0.10, f2.k, &fitted_kc, &fitted_kphi);
  EXPECT_NEAR(fitted_kc, kc, 1e-6 * kc);
  EXPECT_NEAR(fitted_kphi, kphi, 1e-6 * kphi);

  double c = 0, phi = 0;
  FitMohrCoulomb({10e3, 20e3, 40e3},
                 {1300 + 10e3 * std::tan(units::DegreesToRadians(31.1)),
                  1300 + 20e3 * std::tan(units::DegreesToRadians(31.1)),
                  1300 + 40e3 * std::tan(units::DegreesToRadians(31.1))},
                 &c, &phi);
  EXPECT_NEAR(c, 1300, 1e-6);
  EXPECT_NEAR(phi, 31.1, 1e-9);

  std::vector<double> j, tau;
  for (int i = 0; i <= 40; ++i) {
    j.push_back(0.001 * i);
    tau.push_back(8000 * (1 - std::exp(-j.back() / 0.01)));
  }
  EXPECT_NEAR(FitShearDeformationModulus(j, tau, 8000), 0.01, 1e-9);
}

// The shear ring's strength is bounded by the soil's. Below: Drucker-Prager matched to
// Mohr-Coulomb in triaxial compression circumscribes Mohr-Coulomb, and with zero dilation the
// horizontal plane of simple shear carries at least tau = c cos(phi) + sigma sin(phi) (Davis 1968,
// non-associated Mohr-Coulomb; Potts & Zdravkovic 1999, sec. 7.8). Above: the torque also carries
// the shear on the ring's inner and outer cylinders over the one-element-thick shear band h, which
// adds at most 3 h (r_i^2 + r_o^2) / (r_o^3 - r_i^3) (0.54 for h = 25 mm) of a shear stress no
// larger than the ring's own, and the circumscribed cone is at most eta_c / eta_ps times
// stronger than Mohr-Coulomb in plane shear, eta_c = 6 sin(phi) / (sqrt(3) (3 - sin(phi))),
// eta_ps = 3 tan(phi) / sqrt(9 + 12 tan^2(phi)) (de Souza Neto, Peric & Owen 2008, sec. 6.4.3).
TEST(VirtualBevameterTest, FittedStrengthMatchesTheSoil) {
  const FeSoil& soil = *FeSoilLibrary::Builtin().Find("lll_dry_sand");
  RigOptions options;
  options.threads = 2;
  const BevameterSpec spec;
  const BevameterResult r = RunVirtualBevameter(soil, spec, options);
  PrintBevameter(r, stdout);
  const BekkerParameters& b = r.fitted;
  const double c = soil.strength.cohesion_pa;
  const double phi = units::DegreesToRadians(soil.strength.friction_angle_deg);
  const double band_m = 0.25 * (spec.ring_outer_radius_m - spec.ring_inner_radius_m);
  const double side_share =
      3 * band_m * (std::pow(spec.ring_inner_radius_m, 2) + std::pow(spec.ring_outer_radius_m, 2)) /
      (std::pow(spec.ring_outer_radius_m, 3) - std::pow(spec.ring_inner_radius_m, 3));
  const double circumscribed_excess =
      (6 * std::sin(phi) / (std::sqrt(3.0) * (3 - std::sin(phi)))) /
      (3 * std::tan(phi) / std::sqrt(9 + 12 * std::pow(std::tan(phi), 2)));
  for (size_t i = 0; i < r.rings.size(); ++i) {
    const double sigma = r.rings[i].normal_pressure_pa;
    EXPECT_GT(r.rings[i].max_shear_stress_pa, c * std::cos(phi) + sigma * std::sin(phi)) << sigma;
    EXPECT_LT(r.rings[i].max_shear_stress_pa,
              (1 + side_share) * circumscribed_excess * (c + sigma * std::tan(phi)))
        << sigma;
    if (i > 0) {
      EXPECT_GT(r.rings[i].max_shear_stress_pa, r.rings[i - 1].max_shear_stress_pa);
    }
  }
  EXPECT_GT(b.friction_angle_deg, soil.strength.friction_angle_deg - 1.0);
  EXPECT_LT(b.friction_angle_deg, soil.strength.friction_angle_deg + 4.0);
  EXPECT_GT(b.cohesion_pa, c);
  EXPECT_GT(b.shear_deformation_m, 0.0);
  EXPECT_LT(b.shear_deformation_m, spec.ring_shear_displacement_m);
  // Pressure-sinkage: pressure rises with sinkage. Drucker-Prager has no cap, so the soil does not
  // compact and the exponent stays below the n = 1.1 published for this sand (README, Limits).
  for (const PlateTest& p : r.plates) {
    EXPECT_GT(p.n, 0.2);
    EXPECT_LT(p.n, 1.0);
    EXPECT_GT(p.k, 0.0);
  }
  EXPECT_GT(b.kphi + b.kc / spec.large_plate_radius_m, 0.0);
}

}  // namespace
}  // namespace gonogo::rig
