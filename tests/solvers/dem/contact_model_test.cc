// Contact sub-models against their closed forms: Hertz (seed 000), Mindlin stiffness, the
// restitution-damping coefficient, stick-to-slip at mu F_n and the rolling limit eta F_n r_e.
#include "solvers/dem/contact_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::dem {
namespace {

using units::kPi;

MaterialParams Seed000() {
  MaterialParams m;  // defaults are seed 000: E 1.5 GPa, nu 0.293, mu 0.452, beta 2.25, eta 0.99
  m.restitution = 1.0;
  return m;
}

// Two 0.87 mm quartz grains pressed together by d along z.
ContactKinematics Pressed(double overlap_m) {
  const double radius_m = 0.87e-3;
  const double mass_kg = 2650.0 * 4.0 / 3.0 * kPi * std::pow(radius_m, 3);
  ContactKinematics kin;
  kin.normal = Vec3::UnitZ();
  kin.overlap_m = overlap_m;
  kin.effective_radius_m = 0.5 * radius_m;
  kin.effective_mass_kg = 0.5 * mass_kg;
  kin.arm_i_m = radius_m - 0.5 * overlap_m;
  kin.arm_j_m = radius_m - 0.5 * overlap_m;
  return kin;
}

TEST(HertzNormal, MatchesSeedFormulaAndItsDerivative) {
  const MaterialParams m = Seed000();
  const HertzNormal hertz(m);
  const double r_e = 0.435e-3, d = 2e-6;
  const double seed_force = 2.0 * m.youngs_modulus_pa * std::sqrt(r_e * d) * d /
                            (3.0 * (1.0 - std::pow(m.poisson_ratio, 2)));
  const NormalResponse response = hertz.Evaluate(d, r_e);
  EXPECT_NEAR(response.force_n / seed_force, 1.0, 1e-14);
  const double h = 1e-12;
  const double slope =
      (hertz.Evaluate(d + h, r_e).force_n - hertz.Evaluate(d - h, r_e).force_n) / (2.0 * h);
  EXPECT_NEAR(response.stiffness_n_m / slope, 1.0, 1e-6);
  // U is the integral of F: dU/dd = F.
  const double dU = (hertz.ElasticEnergyJ(d + h, r_e) - hertz.ElasticEnergyJ(d - h, r_e)) / (2 * h);
  EXPECT_NEAR(dU / response.force_n, 1.0, 1e-6);
}

TEST(MindlinTangential, MatchesSeedFormula) {
  const MaterialParams m = Seed000();
  const double r_e = 0.435e-3, d = 2e-6;
  const double shear_pa = m.youngs_modulus_pa / (2.0 * (1.0 + m.poisson_ratio));
  EXPECT_NEAR(MindlinTangential(m).Stiffness(d, r_e) /
                  (4.0 * shear_pa * std::sqrt(r_e * d) / (2.0 - m.poisson_ratio)),
              1.0, 1e-14);
}

TEST(RestitutionDamping, BetaFromRestitution) {
  EXPECT_EQ(RestitutionDamping::BetaFromRestitution(1.0), 0.0);
  // ln 0.5 / sqrt(ln^2 0.5 + pi^2) = -0.21545...
  EXPECT_NEAR(RestitutionDamping::BetaFromRestitution(0.5), -0.215453, 1e-6);
  EXPECT_THROW(RestitutionDamping::BetaFromRestitution(0.0), InputError);
  const RestitutionDamping damping(0.5, false);
  EXPECT_NEAR(damping.NormalCoefficient(1e6, 1e-6), 2.0 * std::sqrt(5.0 / 6.0) * 0.215453, 1e-5);
  EXPECT_EQ(damping.TangentialCoefficient(1e6, 1e-6), 0.0);
}

TEST(ContactModel, StickThenSlipAtCoulombLimitThenElasticUnloading) {
  const MaterialParams m = Seed000();
  const ContactModel model = ContactModel::HertzMindlin(m);
  ContactKinematics kin = Pressed(2e-6);
  const double speed_m_s = 1e-3, dt_s = 1e-6;  // 1 nm per step
  kin.contact_velocity_m_s = Vec3(speed_m_s, 0.0, 0.0);
  const double f_n = HertzNormal(m).Evaluate(kin.overlap_m, kin.effective_radius_m).force_n;
  const double k_t = MindlinTangential(m).Stiffness(kin.overlap_m, kin.effective_radius_m);
  const double limit_n = m.friction * f_n;
  ContactHistory history;
  bool slipped = false;
  for (int step = 1; step <= 2000; ++step) {
    const ContactResult r = model.Evaluate(kin, dt_s, history);
    const double elastic_n = k_t * speed_m_s * dt_s * step;
    const double expected_n = std::min(elastic_n, limit_n);
    // Tangential force opposes the sliding of i over j.
    ASSERT_NEAR(-r.force_on_i_n.x(), expected_n, 1e-9 * limit_n) << "step " << step;
    ASSERT_NEAR(r.force_on_i_n.z(), f_n, 1e-9 * f_n);
    slipped = slipped || elastic_n > limit_n;
  }
  ASSERT_TRUE(slipped);
  // Reversal: the spring was reset to the cap, so it unloads with k_t from mu F_n.
  kin.contact_velocity_m_s = -kin.contact_velocity_m_s;
  const ContactResult back = model.Evaluate(kin, dt_s, history);
  EXPECT_NEAR(-back.force_on_i_n.x(), limit_n - k_t * speed_m_s * dt_s, 1e-9 * limit_n);
}

TEST(ContactModel, RollingTorqueGrowsWithStiffnessAndCapsAtEtaFnRe) {
  const MaterialParams m = Seed000();
  const ContactModel model = ContactModel::HertzMindlin(m);
  ContactKinematics kin = Pressed(2e-6);
  const double spin_rad_s = 1.0, dt_s = 1e-6;  // 1 microradian per step
  kin.relative_spin_rad_s = Vec3(spin_rad_s, 0.0, 0.0);
  // Rolling with no slip at the contact: the contact velocity stays zero.
  const NormalResponse spring = HertzNormal(m).Evaluate(kin.overlap_m, kin.effective_radius_m);
  const double r_e = kin.effective_radius_m;
  const double k_r =
      m.rolling_stiffness * spring.stiffness_n_m * std::pow(m.rolling_limit * r_e, 2);
  const double limit_n_m = m.rolling_limit * spring.force_n * r_e;
  ContactHistory history;
  bool capped = false;
  for (int step = 1; step <= 3000; ++step) {
    const ContactResult r = model.Evaluate(kin, dt_s, history);
    const double expected = std::min(k_r * spin_rad_s * dt_s * step, limit_n_m);
    ASSERT_NEAR(-r.torque_on_i_n_m.x(), expected, 1e-9 * limit_n_m) << "step " << step;
    ASSERT_NEAR(r.torque_on_j_n_m.x(), expected, 1e-9 * limit_n_m);
    capped = capped || k_r * spin_rad_s * dt_s * step > limit_n_m;
  }
  EXPECT_TRUE(capped);
  // Twist about the normal is not resisted by the rolling spring.
  ContactHistory twist_history;
  kin.relative_spin_rad_s = Vec3(0.0, 0.0, spin_rad_s);
  EXPECT_EQ(model.Evaluate(kin, dt_s, twist_history).torque_on_i_n_m.norm(), 0.0);
}

TEST(ContactModel, HistoryIsRotatedOntoTheContactPlaneKeepingItsLength) {
  Vec3 stored(3.0, 0.0, 4.0);
  ProjectOntoContactPlane(Vec3::UnitZ(), stored);
  EXPECT_NEAR(stored.x(), 5.0, 1e-15);
  EXPECT_NEAR(stored.z(), 0.0, 1e-15);
}

TEST(MaterialParams, RejectsNonsense) {
  MaterialParams m;
  m.poisson_ratio = 0.5;
  EXPECT_THROW(m.Validate(), InputError);
  m = MaterialParams{};
  m.restitution = 1.2;
  EXPECT_THROW(ContactModel::HertzMindlin(m), InputError);
  m = MaterialParams{};
  m.youngs_modulus_pa = -1.0;
  EXPECT_THROW(m.Validate(), InputError);
}

}  // namespace
}  // namespace gonogo::dem

namespace gonogo::dem {
namespace {

// The fused seed 000 path equals the general path through the four sub-models, to round-off,
// over random contacts (sticking, sliding, rolling at the limit, with and without damping), and
// it is taken only for the exact seed 000 sub-model types.
TEST(ContactModel, FusedSeedPathEqualsTheGeneralPath) {
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (double restitution : {1.0, 0.5}) {
    for (double rolling_limit : {0.0, 0.99}) {
      MaterialParams material;
      material.restitution = restitution;
      material.rolling_limit = rolling_limit;
      const ContactModel model = ContactModel::HertzMindlin(material);
      ASSERT_TRUE(model.fused());
      for (int trial = 0; trial < 20000; ++trial) {
        ContactKinematics kin;
        kin.normal = Vec3(unit(random), unit(random), unit(random)).normalized();
        kin.overlap_m = 1e-6 * (1.001 + unit(random));
        kin.effective_radius_m = 0.5e-3 * (1.5 + unit(random));
        kin.effective_mass_kg = 1e-6 * (1.5 + unit(random));
        kin.arm_i_m = 0.8e-3;
        kin.arm_j_m = 0.9e-3;
        kin.contact_velocity_m_s = 0.1 * Vec3(unit(random), unit(random), unit(random));
        kin.relative_spin_rad_s = 100.0 * Vec3(unit(random), unit(random), unit(random));
        ContactHistory fused_history;
        fused_history.tangential_displacement_m = 2e-7 * Vec3(unit(random), unit(random), unit(random));
        fused_history.rolling_angle_rad = 2e-3 * Vec3(unit(random), unit(random), unit(random));
        ContactHistory general_history = fused_history;
        const ContactResult fused = model.Evaluate(kin, 1e-6, fused_history);
        const ContactResult general = model.EvaluateGeneral(kin, 1e-6, general_history);
        const double force_scale = general.force_on_i_n.norm();
        ASSERT_LT((fused.force_on_i_n - general.force_on_i_n).norm(), 1e-12 * force_scale);
        const double torque_scale = general.torque_on_i_n_m.norm() + general.torque_on_j_n_m.norm() + 1e-30;
        ASSERT_LT((fused.torque_on_i_n_m - general.torque_on_i_n_m).norm(), 1e-12 * torque_scale);
        ASSERT_LT((fused.torque_on_j_n_m - general.torque_on_j_n_m).norm(), 1e-12 * torque_scale);
        ASSERT_EQ(fused.sliding, general.sliding);
        ASSERT_NEAR(fused.normal_stiffness_n_m, general.normal_stiffness_n_m,
                    1e-13 * general.normal_stiffness_n_m);
        ASSERT_LT((fused_history.tangential_displacement_m - general_history.tangential_displacement_m).norm(),
                  1e-12 * general_history.tangential_displacement_m.norm() + 1e-30);
        ASSERT_LT((fused_history.rolling_angle_rad - general_history.rolling_angle_rad).norm(),
                  1e-12 * general_history.rolling_angle_rad.norm() + 1e-30);
      }
    }
  }
  // Another law keeps the general path.
  const ContactModel eepa = ContactModel::Eepa(Seed001EepaSoil("FGS"));
  EXPECT_FALSE(eepa.fused());
}

// The paired rotation of the two history vectors gives the bits of two single rotations: for
// random vectors, one already in the plane (no normal part: unchanged), one along the normal
// (at most round-off left in the plane), and the zero vector.
TEST(ContactModel, PairedHistoryRotationEqualsTwoSingleOnes) {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 normal = Vec3(unit(random), unit(random), unit(random)).normalized();
    Vec3 first = 2e-7 * Vec3(unit(random), unit(random), unit(random));
    Vec3 second = 2e-3 * Vec3(unit(random), unit(random), unit(random));
    if (trial % 4 == 1) second = 3e-3 * normal;
    if (trial % 4 == 2) first -= first.dot(normal) * normal;
    if (trial % 4 == 3) first.setZero();
    if (trial % 4 == 2 && first.dot(normal) != 0.0) continue;  // rounding left a normal part
    Vec3 first_single = first;
    Vec3 second_single = second;
    ProjectOntoContactPlane(normal, first_single);
    ProjectOntoContactPlane(normal, second_single);
    ProjectTwoOntoContactPlane(normal, first, second);
    ASSERT_EQ(first, first_single) << trial;
    ASSERT_EQ(second, second_single) << trial;
  }
}

}  // namespace
}  // namespace gonogo::dem
