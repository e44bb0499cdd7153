// Drained triaxial compression of the seed 000 RVE (500 grains, E 1.5 GPa, nu 0.293, mu 0.452,
// rolling beta 2.25, eta 0.99) at 100 kPa confining pressure: the lateral stresses stay at the
// confining pressure, a dense packing contracts then dilates, and the peak friction angle falls
// in the range published for this friction and rolling resistance.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "solvers/dem/rve/rve.h"

namespace gonogo::dem::rve {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kConfiningPa = 100e3;

// PUBLISHED_RANGE_PLACEHOLDER
constexpr double kPeakFrictionLowDeg = 40.0;
constexpr double kPeakFrictionHighDeg = 56.0;

double MobilisedFrictionDeg(const Matrix3& stress_pa) {
  // Compression positive principal stresses; sin(phi) = (s1 - s3) / (s1 + s3).
  const Eigen::Vector3d s = Eigen::SelfAdjointEigenSolver<Matrix3>(-stress_pa).eigenvalues();
  return std::asin((s[2] - s[0]) / (s[2] + s[0])) * 180.0 / kPi;
}

TEST(RveTriaxial, DenseSeedPackingPeaksInThePublishedRange) {
  RveParams params;  // seed 000 defaults, 500 grains, dense (frictionless) consolidation
  params.consolidation_pressure_pa = kConfiningPa;
  Rve rve = Rve::Generate(params);
  MixedControl triaxial;
  const double rate_1_s = rve.StableRate1S();
  triaxial.strain_rate_1_s(2, 2) = -rate_1_s;
  for (int d = 0; d < 2; ++d) {
    triaxial.stress_controlled[d][d] = true;
    triaxial.target_stress_pa(d, d) = -kConfiningPa;
  }
  const int steps_per_row = static_cast<int>(0.0025 / (rate_1_s * rve.time_step_s()));
  double peak_deg = 0.0, peak_axial = 0.0, min_volumetric = 0.0, worst_lateral_pa = 0.0;
  for (int row = 1; row <= 40; ++row) {  // to 10 % axial strain
    rve.Run(triaxial, steps_per_row);
    const RveSnapshot s = rve.Snapshot();
    const double axial = -s.strain(2, 2), volumetric = -s.strain.trace();
    const double friction_deg = MobilisedFrictionDeg(s.stress_pa);
    if (friction_deg > peak_deg) {
      peak_deg = friction_deg;
      peak_axial = axial;
    }
    min_volumetric = std::min(min_volumetric, volumetric);
    if (row > 2) {
      for (int d = 0; d < 2; ++d) {
        worst_lateral_pa = std::max(worst_lateral_pa, std::abs(-s.stress_pa(d, d) - kConfiningPa));
      }
    }
  }
  RecordProperty("peak_friction_deg", std::to_string(peak_deg));
  std::printf("peak friction angle %.2f deg at axial strain %.4f; largest dilation %.4f; "
              "worst lateral stress error %.0f Pa\n",
              peak_deg, peak_axial, -min_volumetric, worst_lateral_pa);
  EXPECT_GT(peak_deg, kPeakFrictionLowDeg);
  EXPECT_LT(peak_deg, kPeakFrictionHighDeg);
  // A dense packing peaks early and dilates (volumetric strain turns negative).
  EXPECT_LT(peak_axial, 0.08);
  EXPECT_LT(min_volumetric, -0.01);
  // Drained: the servo holds the lateral stresses within 5 % of the confining pressure.
  EXPECT_LT(worst_lateral_pa, 0.05 * kConfiningPa);
}

}  // namespace
}  // namespace gonogo::dem::rve
