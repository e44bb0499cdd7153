#include "solvers/mobility/similarity.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/tiers/bekker_tier.h"
#include "solvers/tiers/empirical_tier.h"

namespace gonogo::mobility {
namespace {

// Seed 001 Table 4: the FED Alpha tyre (scale 1) with its load of Table 6.
TractionRequest FullScale() {
  TractionRequest r;
  r.soil.cone_index_pa = 149e3;  // 2NS sand
  r.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0.4728};
  r.wheel_load_n = 13438;
  r.slips = TractionRequest::SlipSweep(0.05);
  return r;
}

// Lengths scaled by k, load by k^2: equal W/(b d) (seed 001 Table 6).
TractionRequest Scaled(double k) {
  TractionRequest r = FullScale();
  r.tyre.diameter_m *= k;
  r.tyre.width_m *= k;
  r.tyre.section_height_m *= k;
  r.tyre.deflection_m *= k;
  r.tyre.rolling_radius_m *= k;
  r.wheel_load_n *= k * k;
  return r;
}

TEST(PiTerms, SeedScaledTyresShareTheirPiTerms) {
  const PiTerms full = ComputePiTerms(FullScale());
  EXPECT_NEAR(full.width_over_diameter, 0.3314, 1e-4);
  EXPECT_NEAR(full.load_over_bd_pa, 13438 / (0.335 * 1.011), 1e-6);
  for (double k : {0.7, 0.5, 0.25}) EXPECT_TRUE(PiTermsMatch(full, ComputePiTerms(Scaled(k))));
  TractionRequest heavier = Scaled(0.7);
  heavier.wheel_load_n *= 1.02;
  EXPECT_FALSE(PiTermsMatch(full, ComputePiTerms(heavier))) << "2 % more pressure";
  TractionRequest wider = Scaled(0.7);
  wider.tyre.width_m *= 1.05;
  wider.wheel_load_n *= 1.05;  // same W/(b d), other b/d
  EXPECT_FALSE(PiTermsMatch(full, ComputePiTerms(wider)));
}

TEST(Dimensionless, RoundTripIsExact) {
  tiers::EmpiricalTier tier;
  const TractionRequest r = FullScale();
  const TractionCurve c = tier.Compute(r);
  const TractionCurve back = FromDimensionless(r, ToDimensionless(r, c));
  ASSERT_EQ(back.points.size(), c.points.size());
  for (size_t i = 0; i < c.points.size(); ++i) {
    EXPECT_NEAR(back.points[i].drawbar_pull_n, c.points[i].drawbar_pull_n, 1e-9);
    EXPECT_NEAR(back.points[i].torque_nm, c.points[i].torque_nm, 1e-9);
    EXPECT_NEAR(back.points[i].sinkage_m, c.points[i].sinkage_m, 1e-12);
    EXPECT_NEAR(back.points[i].gross_traction_n, c.points[i].gross_traction_n, 1e-9);
  }
}

// The empirical tier depends on the pi-terms only, so a similarity answer must equal the curve
// computed directly for the scaled tyre: the closed-form check of the scaling law.
TEST(Dimensionless, ScaledEmpiricalCurveEqualsTheDirectComputation) {
  tiers::EmpiricalTier tier;
  const TractionRequest full = FullScale();
  const auto dimensionless = ToDimensionless(full, tier.Compute(full));
  for (double k : {0.7, 0.5, 0.25}) {
    const TractionRequest small = Scaled(k);
    const TractionCurve direct = tier.Compute(small);
    const TractionCurve scaled = FromDimensionless(small, dimensionless);
    for (size_t i = 0; i < direct.points.size(); ++i) {
      const auto& a = direct.points[i];
      const auto& b = scaled.points[i];
      EXPECT_NEAR(b.drawbar_pull_n, a.drawbar_pull_n, 1e-9 * small.wheel_load_n) << k;
      EXPECT_NEAR(b.torque_nm, a.torque_nm, 1e-9 * small.wheel_load_n) << k;
      EXPECT_NEAR(b.sinkage_m, a.sinkage_m, 1e-12) << k;
      EXPECT_NEAR(b.tractive_efficiency, a.tractive_efficiency, 1e-12) << k;
    }
  }
}

// The Bekker tier's own similarity law. On a purely frictional soil (c = 0, kc = 0) the Wong-Reece
// stresses are kphi z^n and tan(phi) times that, so scaling every length (wheel, sinkage and the
// shear modulus K) by k scales stresses by k^n and forces by k^(n+2): with W ~ k^(n+2) the
// dimensionless curves must coincide exactly. With seed 001's law W ~ k^2 they must not, unless n = 0,
// and the direction follows from the model: the smaller tyre then carries relatively more load
// (k^2 > k^(n+2) for k < 1), so it sinks deeper relative to its size.
TEST(BekkerSimilarity, FrictionalSoilIsSelfSimilarUnderItsOwnLawNotUnderEqualPressure) {
  tiers::BekkerTier tier;
  const double n = 0.8;
  const BekkerParameters full_soil{n, 0.0, 1.5e6, 0.0, 32.0, 0.02};
  auto request = [&](double k, double load_exponent) {
    TractionRequest r;
    BekkerParameters soil = full_soil;
    soil.shear_deformation_m *= k;
    r.soil.parameters = soil.ToSoilModel();
    r.tyre = TyreGeometry{1.0 * k, 0.3 * k, 0.25 * k, 0.0, 0.0};  // rigid wheel
    r.wheel_load_n = 6000.0 * std::pow(k, load_exponent);
    r.slips = TractionRequest::SlipSweep(0.1);
    return r;
  };
  const TractionRequest full = request(1.0, 2.0);
  const auto reference = ToDimensionless(full, tier.Compute(full));
  for (double k : {0.7, 0.5}) {
    const TractionRequest own = request(k, n + 2.0);
    const auto same = ToDimensionless(own, tier.Compute(own));
    const TractionRequest seed = request(k, 2.0);
    const auto differs = ToDimensionless(seed, tier.Compute(seed));
    for (size_t i = 0; i < reference.size(); ++i) {
      EXPECT_NEAR(same[i].drawbar_pull_coefficient, reference[i].drawbar_pull_coefficient, 1e-6)
          << "k " << k << " slip " << reference[i].slip;
      EXPECT_NEAR(same[i].gross_traction_coefficient, reference[i].gross_traction_coefficient, 1e-6);
      EXPECT_NEAR(same[i].sinkage_over_diameter, reference[i].sinkage_over_diameter, 1e-7);
      EXPECT_GT(differs[i].sinkage_over_diameter, reference[i].sinkage_over_diameter * 1.01)
          << "equal W/(b d) sinks the smaller wheel deeper, k " << k;
    }
  }
}

TEST(BandAgreement, CountsPointsInsideTheFullScaleStandardDeviation) {
  // Full scale D/W = 0, 0.1, ..., 0.4 over five slips: sample SD = sqrt(0.025) = 0.158.
  std::vector<DimensionlessPoint> full, scaled;
  for (int i = 0; i < 5; ++i) {
    full.push_back({0.25 * i, 0.1 * i, 0.2 * i, 0, 0.1 * i, 0});
    scaled.push_back(full.back());
  }
  EXPECT_NEAR(FullScaleBand(full).drawbar_pull, std::sqrt(0.025), 1e-12);
  BandAgreement same = CompareToFullScale(full, scaled);
  EXPECT_DOUBLE_EQ(same.drawbar_pull_pct, 100);
  EXPECT_DOUBLE_EQ(same.efficiency_pct, 100);
  scaled[1].drawbar_pull_coefficient += 0.15;  // inside (0.15 < 0.158)
  scaled[2].drawbar_pull_coefficient -= 0.17;  // outside
  scaled[3].drawbar_pull_coefficient += 0.50;  // outside
  EXPECT_DOUBLE_EQ(CompareToFullScale(full, scaled).drawbar_pull_pct, 60);
  scaled.pop_back();
  EXPECT_THROW(CompareToFullScale(full, scaled), InputError);
}

TEST(ScalabilityTable, Seed001FiguresByScaleAndSoil) {
  const ScalabilityTable& t = ScalabilityTable::Seed001();
  ASSERT_EQ(t.records().size(), 6u);
  auto r = t.For(0.7, 149e3);  // 2NS, scale 0.7: Table 7
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->soil, "2NS");
  EXPECT_DOUBLE_EQ(r->gross_traction_pct, 97.1);
  r = t.For(0.6, 22e3);  // between the tabulated scales: the smaller (0.5), FGS: Table 8
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->soil, "FGS");
  EXPECT_DOUBLE_EQ(r->scale, 0.5);
  EXPECT_DOUBLE_EQ(r->drawbar_pull_pct, 70.7);
  r = t.For(0.95, 300e3);  // above 0.7: the 0.7 row; 300 kPa is nearer 2NS
  EXPECT_EQ(r->soil, "2NS");
  EXPECT_DOUBLE_EQ(r->scale, 0.7);
  r = t.For(0.5, 0);  // no cone index: the lower of both soils
  EXPECT_DOUBLE_EQ(r->drawbar_pull_pct, 70.7);
  EXPECT_DOUBLE_EQ(r->gross_traction_pct, 41.4);
  EXPECT_DOUBLE_EQ(r->efficiency_pct, 56.1);
  EXPECT_FALSE(t.For(0.2, 149e3).has_value()) << "below every tabulated scale";
}

}  // namespace
}  // namespace gonogo::mobility
