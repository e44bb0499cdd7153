// The calibration chain of the fe-de tier (fe_de_calibration.h) and the fe-de wheel's response to
// load: the Drucker-Prager fit recovers a Drucker-Prager soil from its own closed-form triaxial
// curves; on the RVE it gives a soil whose continuum twin runs the same rig; the fe-de wheel sinks
// deeper under a larger load; the virtual bevameter on the fe-de soil reads the RVE's friction.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/rig/bevameter.h"
#include "solvers/tiers/fe_de_calibration.h"
#include "solvers/tiers/fe_de_tier.h"
#include "tests/solvers/tiers/fe_de_test_configuration.h"
#include "solvers/tiers/soil_catalogue.h"

namespace gonogo::tiers {
namespace {

// Drained triaxial compression of a perfectly plastic Drucker-Prager soil matched to
// Mohr-Coulomb in triaxial compression, in closed form (compression positive): elastic,
// q = E eps_a and eps_v = (1 - 2 nu) eps_a, up to sigma_1 = N sigma_3 + 2 c sqrt(N); then q holds
// and the plastic flow of the cone (dSN eq. 6.119 with psi) gives d eps_v / d eps_a =
// -2 sin(psi) / (1 - sin(psi)).
TriaxialCurve ClosedFormTriaxial(const material::DruckerPragerParams& dp, double confining_pa) {
  const double sin_phi = std::sin(units::DegreesToRadians(dp.friction_angle_deg));
  const double sin_psi = std::sin(units::DegreesToRadians(dp.dilation_angle_deg));
  const double n = (1 + sin_phi) / (1 - sin_phi);
  const double yield_q = (n - 1) * confining_pa + 2 * dp.cohesion_pa * std::sqrt(n);
  const double yield_strain = yield_q / dp.young_pa;
  const double dilatancy = -2 * sin_psi / (1 - sin_psi);
  TriaxialCurve curve;
  curve.confining_pa = confining_pa;
  for (int k = 0; k <= 200; ++k) {
    const double ea = 0.1 * k / 200;
    curve.axial_strain.push_back(ea);
    curve.deviator_pa.push_back(std::min(dp.young_pa * ea, yield_q));
    curve.volumetric_strain.push_back(
        ea <= yield_strain ? (1 - 2 * dp.poisson) * ea
                           : (1 - 2 * dp.poisson) * yield_strain + dilatancy * (ea - yield_strain));
  }
  return curve;
}

TEST(FeDeCalibration, TheFitRecoversADruckerPragerSoilFromItsOwnTriaxials) {
  for (const auto& [c, phi, psi] : {std::tuple{0.0, 38.0, 8.0}, std::tuple{4e3, 31.0, 0.0},
                                    std::tuple{1.5e3, 50.0, 20.0}}) {
    material::DruckerPragerParams soil;
    soil.young_pa = 20e6;
    soil.poisson = 0.28;
    soil.cohesion_pa = c;
    soil.friction_angle_deg = phi;
    soil.dilation_angle_deg = psi;
    const TriaxialFit fit = FitDruckerPragerToTriaxials(
        {ClosedFormTriaxial(soil, 10e3), ClosedFormTriaxial(soil, 25e3),
         ClosedFormTriaxial(soil, 60e3)});
    EXPECT_NEAR(fit.strength.young_pa / soil.young_pa, 1.0, 1e-9) << phi;
    EXPECT_NEAR(fit.strength.poisson, soil.poisson, 1e-9) << phi;
    EXPECT_NEAR(fit.strength.cohesion_pa, soil.cohesion_pa, 1e-6) << phi;
    EXPECT_NEAR(fit.strength.friction_angle_deg, soil.friction_angle_deg, 1e-9) << phi;
    EXPECT_NEAR(fit.strength.dilation_angle_deg, soil.dilation_angle_deg, 1e-9) << phi;
    EXPECT_EQ(fit.strength.match, material::DruckerPragerParams::Match::kTriaxialCompression);
  }
  // A single confinement cannot separate c from phi.
  material::DruckerPragerParams soil;
  soil.young_pa = 20e6;
  soil.poisson = 0.3;
  soil.friction_angle_deg = 35;
  EXPECT_THROW(FitDruckerPragerToTriaxials({ClosedFormTriaxial(soil, 10e3)}), InputError);
  EXPECT_THROW(FitDruckerPragerToTriaxials(
                   {ClosedFormTriaxial(soil, 10e3), ClosedFormTriaxial(soil, 10e3)}),
               InputError);
}

// Davis (1968) in its two limits, and in between: associated flow measures tan(phi) on the
// horizontal plane, flow at constant volume sin(phi) (the critical state); dilation raises it.
TEST(FeDeCalibration, TheRingsHorizontalPlaneFrictionFollowsDavis) {
  for (double phi : {20.0, 35.0, 54.3}) {
    const double phi_rad = units::DegreesToRadians(phi);
    EXPECT_NEAR(HorizontalPlaneFrictionAngleDeg(phi, phi), phi, 1e-9);
    EXPECT_NEAR(HorizontalPlaneFrictionAngleDeg(phi, 0),
                units::RadiansToDegrees(std::atan(std::sin(phi_rad))), 1e-9);
    EXPECT_LT(HorizontalPlaneFrictionAngleDeg(phi, 0), HorizontalPlaneFrictionAngleDeg(phi, 5));
  }
  // The fe-de soil's fit (phi 54.3, psi 13.5 deg) on a ring: 44.2 deg, by hand.
  EXPECT_NEAR(HorizontalPlaneFrictionAngleDeg(54.3, 13.5), 44.26, 0.01);
  EXPECT_THROW(HorizontalPlaneFrictionAngleDeg(30, 31), InputError);
  EXPECT_THROW(HorizontalPlaneFrictionAngleDeg(90, 0), InputError);
  EXPECT_THROW(HorizontalPlaneFrictionAngleDeg(30, -1), InputError);
}

// A triaxial curve's mobilised friction angle reads its measured lateral stress.
TEST(FeDeCalibration, TheMobilisedFrictionAngleReadsTheMeasuredLateralStress) {
  TriaxialCurve curve;
  curve.confining_pa = 10e3;
  curve.deviator_pa = {20e3};
  EXPECT_NEAR(MobilisedFrictionAngleDeg(curve, 0), 30.0, 1e-9);  // sigma_1 = 3 sigma_3
  curve.lateral_stress_pa = {15e3};
  EXPECT_NEAR(MobilisedFrictionAngleDeg(curve, 0),
              units::RadiansToDegrees(std::asin(20.0 / 50.0)), 1e-9);
}

TractionRequest Request(double load_n) {
  TractionRequest request;
  request.soil.soil_name = "seed000_sand_rve100";
  request.tyre.diameter_m = 0.5;
  request.tyre.width_m = 0.2;
  request.tyre.section_height_m = 0.1;
  request.wheel_load_n = load_n;
  request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
  return request;
}

// The RVE's triaxials (the tier's numerics) fitted, and the fitted soil through the same rig.
TEST(FeDeCalibration, TheRveFitsADilatantFrictionalSoilWhoseTwinPullsMoreWithSlip) {
  const FeDeTier tier(TinyFeDeOptions());
  const SoilParameters soil = tier.ResolveSoil(Request(1000).soil, "soil");
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(soil, tier.options().numerics, "soil"));
  std::vector<TriaxialCurve> curves;
  for (double pressure : {5e3, 15e3, 40e3}) {
    curves.push_back(RunRveTriaxial(*rve, pressure, 0.1, 100));
    // Drained: the servo holds the lateral stress.
    double worst = 0;
    for (double lateral : curves.back().lateral_stress_pa) {
      worst = std::max(worst, std::abs(lateral / pressure - 1));
    }
    EXPECT_LT(worst, 0.1) << pressure;
  }
  const TriaxialFit fit = FitDruckerPragerToTriaxials(curves);
  const material::DruckerPragerParams& dp = fit.strength;
  std::cout << "  fitted: E " << dp.young_pa << " Pa, nu " << dp.poisson << ", c "
            << dp.cohesion_pa << " Pa, phi " << dp.friction_angle_deg << " deg, psi "
            << dp.dilation_angle_deg << " deg\n";
  // The RVE's peaks rise with confinement and the dense packing dilates.
  EXPECT_GT(fit.curves[1].peak_deviator_pa, fit.curves[0].peak_deviator_pa);
  EXPECT_GT(fit.curves[2].peak_deviator_pa, fit.curves[1].peak_deviator_pa);
  EXPECT_GT(dp.friction_angle_deg, 35.0);
  EXPECT_LT(dp.friction_angle_deg, 75.0);
  EXPECT_GT(dp.young_pa, 0.0);
  EXPECT_NO_THROW(dp.Validate("fit."));

  const FeDeRunReport twin = tier.RunContinuumTwin(Request(1000), dp, ComputeContext{});
  ASSERT_EQ(twin.curve.points.size(), 5u) << twin.curve.immobile_reason;
  EXPECT_EQ(twin.curve.tier, "fe-de-twin");
  EXPECT_GT(twin.curve.points[4].drawbar_pull_n, twin.curve.points[0].drawbar_pull_n);
  EXPECT_GT(twin.curve.points[0].sinkage_m, 0.0);
}

// Drawbar pull rises with slip and sinkage with load (seed 001 Figs. 14-17, Wong 2008 ch. 4).
TEST(FeDeWheel, PullsMoreWithSlipAndSinksDeeperUnderMoreLoad) {
  const FeDeTier tier(TinyFeDeOptions());
  const TractionCurve light = tier.Compute(Request(600), ComputeContext{});
  const TractionCurve heavy = tier.Compute(Request(1500), ComputeContext{});
  ASSERT_EQ(light.points.size(), 5u) << light.immobile_reason;
  ASSERT_EQ(heavy.points.size(), 5u) << heavy.immobile_reason;
  for (const TractionCurve* curve : {&light, &heavy}) {
    EXPECT_GT(curve->points[4].drawbar_pull_n, curve->points[0].drawbar_pull_n);
    EXPECT_GT(curve->points[2].drawbar_pull_n, curve->points[0].drawbar_pull_n);
  }
  double light_mean = 0, heavy_mean = 0;
  for (int k = 0; k < 5; ++k) {
    std::cout << "  s " << light.points[k].slip << ": sinkage " << 1e3 * light.points[k].sinkage_m
              << " mm at 600 N, " << 1e3 * heavy.points[k].sinkage_m << " mm at 1500 N\n";
    light_mean += light.points[k].sinkage_m / 5;
    heavy_mean += heavy.points[k].sinkage_m / 5;
  }
  EXPECT_GT(heavy.points[0].sinkage_m, light.points[0].sinkage_m);
  EXPECT_GT(heavy_mean, 1.2 * light_mean);
}

// The virtual bevameter on the fe-de soil. The shear ring turns the soil under it at a constant
// speed once past its start ramp, so the stress it keeps there is quasi-static even in the
// mass-scaled bin (its peak is not: the ramp accelerates a soil the scaling made many times
// heavier). That residual strength against the normal pressure must have the friction angle of
// the RVE's own simple shear at the same pressures, large strain (gamma 0.5), within 5 degrees;
// the intercept
// carries the shear on the ring's inner and outer cylinders (solvers/rig/README.md). The plates
// sink with rising pressure.
TEST(FeDeBevameter, TheRingsResidualFrictionIsTheRvesInSimpleShear) {
  const FeDeTier tier(FeDeOptions::Preset("ci"));
  rig::BevameterSpec spec;
  spec.small_plate_radius_m = 0.05;
  spec.large_plate_radius_m = 0.1;
  spec.plate_sinkage_m = 0.02;
  spec.ring_inner_radius_m = 0.05;
  spec.ring_outer_radius_m = 0.1;
  spec.ring_shear_displacement_m = 0.03;
  spec.ring_normal_pressures_pa = {10e3, 40e3};
  spec.ring_damping_fraction = 0;
  spec.start_ramp_s = 0.05;
  const FeDeBevameterReport report =
      tier.RunBevameter(Request(1000).soil, spec, 0.025, ComputeContext{});
  const rig::BevameterResult& b = report.bevameter;
  std::cout << "  fe-de bevameter in " << report.wall_seconds << " s\n";
  for (const rig::PlateTest& plate : b.plates) {
    std::cout << "  plate " << plate.radius_m << " m: p = " << plate.k << " z^" << plate.n << "\n";
    EXPECT_GT(plate.n, 0.3);
    EXPECT_GT(plate.pressure_pa.back(), plate.pressure_pa[plate.pressure_pa.size() / 2]);
  }
  std::vector<double> residual_pa;
  for (const rig::RingTest& ring : b.rings) {
    double sum = 0;
    int count = 0;
    const double from_m = 2.0 / 3.0 * spec.ring_shear_displacement_m;
    for (size_t k = 0; k < ring.shear_displacement_m.size(); ++k) {
      if (ring.shear_displacement_m[k] < from_m) continue;
      sum += ring.shear_stress_pa[k];
      ++count;
    }
    ASSERT_GT(count, 2);
    residual_pa.push_back(sum / count);
    std::cout << "  ring at " << ring.normal_pressure_pa << " Pa: peak " << ring.max_shear_stress_pa
              << " Pa, residual " << residual_pa.back() << " Pa\n";
  }
  const double ring_phi_deg = units::RadiansToDegrees(std::atan(
      (residual_pa[1] - residual_pa[0]) / (spec.ring_normal_pressures_pa[1] -
                                           spec.ring_normal_pressures_pa[0])));

  const auto rve = dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(
      tier.ResolveSoil(Request(1000).soil, "soil"), tier.options().numerics, "soil"));
  std::vector<double> rve_residual_pa;
  for (double pressure : spec.ring_normal_pressures_pa) {
    rve_residual_pa.push_back(RunRveSimpleShear(*rve, pressure, 0.5, 50).shear_stress_pa.back());
  }
  const double rve_phi_deg = units::RadiansToDegrees(std::atan(
      (rve_residual_pa[1] - rve_residual_pa[0]) / (spec.ring_normal_pressures_pa[1] -
                                                   spec.ring_normal_pressures_pa[0])));
  std::cout << "  residual friction angle: ring " << ring_phi_deg << " deg, RVE simple shear "
            << rve_phi_deg << " deg\n";
  EXPECT_NEAR(ring_phi_deg, rve_phi_deg, 5.0);
  EXPECT_GT(rve_phi_deg, 20.0);
}

}  // namespace
}  // namespace gonogo::tiers
