// The periodic RVE: isotropic consolidation to its target, homogenised stress and tangent against
// independent sums over the packing, save/restore and determinism, the constitutive seam, mixed
// control on the simple-shear path. The drained triaxial friction angle is in rve_triaxial_test.
#include "solvers/dem/rve/rve.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <memory>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/dem/rve/rve_material.h"

namespace gonogo::dem::rve {
namespace {

constexpr double kPressurePa = 100e3;

RveParams SmallFrictionless() {
  RveParams params;
  params.grain_count = 200;
  params.material.friction = 0.0;
  params.material.rolling_stiffness = 0.0;
  params.consolidation_pressure_pa = kPressurePa;
  return params;
}

// Every contact of the packing found by brute force over all pairs and the 27 images of the cell,
// with the Hertz force of its overlap along the centre line (frictionless, so nothing else).
struct BruteForce {
  Matrix3 virial_nm = Matrix3::Zero();
  Voigt6x6 stiffness_nm = Voigt6x6::Zero();
  int contacts = 0;
};

BruteForce SumOverContacts(const Simulation& sim, const MaterialParams& material) {
  const Particles& g = sim.particles();
  const Eigen::Matrix3d& edges = sim.cell().edges_m;
  const double e_star_pa = material.youngs_modulus_pa / (2.0 * (1.0 - std::pow(material.poisson_ratio, 2)));
  const int voigt_i[6] = {0, 1, 2, 1, 0, 0};
  const int voigt_j[6] = {0, 1, 2, 2, 2, 1};
  BruteForce sum;
  const int n = static_cast<int>(g.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      for (int a = -1; a <= 1; ++a) {
        for (int b = -1; b <= 1; ++b) {
          for (int c = -1; c <= 1; ++c) {
            const Vec3 d = g.position_m[i] - (g.position_m[j] + edges * Vec3(a, b, c));
            const double overlap = g.radius_m[i] + g.radius_m[j] - d.norm();
            if (overlap <= 0.0) continue;
            const double r_e = g.radius_m[i] * g.radius_m[j] / (g.radius_m[i] + g.radius_m[j]);
            const Vec3 normal = d.normalized();
            const double force = 4.0 / 3.0 * e_star_pa * std::sqrt(r_e) * std::pow(overlap, 1.5);
            const double k_n = 2.0 * e_star_pa * std::sqrt(r_e * overlap);
            sum.virial_nm += d * (force * normal).transpose();
            // k_n n_i d_j n_k d_l with d = |d| n is symmetric in (ij) and (kl) already.
            for (int row = 0; row < 6; ++row) {
              for (int col = 0; col < 6; ++col) {
                sum.stiffness_nm(row, col) += k_n * normal[voigt_i[row]] * d[voigt_j[row]] *
                                              normal[voigt_i[col]] * d[voigt_j[col]];
              }
            }
            ++sum.contacts;
          }
        }
      }
    }
  }
  return sum;
}

class RveTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    frictionless_ = std::make_unique<Rve>(Rve::Generate(SmallFrictionless()));
    RveParams seed_law;
    seed_law.grain_count = 200;
    seed_law.consolidation_pressure_pa = kPressurePa;
    seed_law_ = std::make_unique<Rve>(Rve::Generate(seed_law));
  }
  static void TearDownTestSuite() {
    frictionless_.reset();
    seed_law_.reset();
  }
  static std::unique_ptr<Rve> frictionless_;
  static std::unique_ptr<Rve> seed_law_;
};
std::unique_ptr<Rve> RveTest::frictionless_;
std::unique_ptr<Rve> RveTest::seed_law_;

TEST_F(RveTest, IsotropicConsolidationReachesItsTarget) {
  for (const Rve* rve : {frictionless_.get(), seed_law_.get()}) {
    const RveSnapshot s = rve->Snapshot();
    const double p = -s.stress_pa.trace() / 3.0;
    EXPECT_NEAR(p, kPressurePa, 0.01 * kPressurePa);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(-s.stress_pa(d, d), kPressurePa, 0.05 * kPressurePa);
    EXPECT_LT(s.stress_pa(0, 1) * s.stress_pa(0, 1) + s.stress_pa(0, 2) * s.stress_pa(0, 2) +
                  s.stress_pa(1, 2) * s.stress_pa(1, 2),
              std::pow(0.05 * kPressurePa, 2));
    EXPECT_LT(s.unbalanced_force_ratio, 5e-3);
    // Random packings of spheres jam between random loose (0.55) and random close (0.64)
    // packing (Scott & Kilgour 1969; Onoda & Liniger 1990); polydispersity allows a little more.
    EXPECT_GT(s.solid_fraction, 0.55);
    EXPECT_LT(s.solid_fraction, 0.67);
    EXPECT_GE(s.coordination_number, 4.0);  // isostatic frictionless jamming: Z = 6
    // Isotropic consolidation leaves the contact normals spread evenly: the fabric is I/3 within
    // the noise of a few hundred contacts (a component's mean of n_i n_j has a standard
    // deviation of about 0.3 / sqrt(N_c) = 0.017), trace 1 and symmetric exactly.
    EXPECT_NEAR(s.fabric.trace(), 1.0, 1e-12);
    EXPECT_LT((s.fabric - s.fabric.transpose()).norm(), 1e-15);
    EXPECT_LT((s.fabric - Matrix3::Identity() / 3.0).cwiseAbs().maxCoeff(), 0.07) << s.fabric;
  }
  // Frictionless consolidation reaches the isostatic coordination of 6 (O'Hern et al. 2003,
  // Phys. Rev. E 68, 011306) within rattlers; denser than with friction.
  EXPECT_NEAR(frictionless_->Snapshot().coordination_number, 6.0, 0.8);
}

TEST_F(RveTest, HomogenisedStressAndTangentMatchIndependentSums) {
  Rve rve = *frictionless_;
  rve.Run(MixedControl{}, 2000);  // settle further with the cell fixed
  const BruteForce sum = SumOverContacts(rve.simulation(), rve.params().material);
  ASSERT_GT(sum.contacts, 300);
  EXPECT_EQ(sum.contacts, rve.simulation().ContactCount());
  const double volume_m3 = rve.simulation().cell().VolumeM3();
  const Matrix3 expected_stress = -0.5 * (sum.virial_nm + sum.virial_nm.transpose()) / volume_m3;
  // The residual difference is the contact dashpots of a packing not perfectly at rest.
  EXPECT_LT((rve.StressPa() - expected_stress).norm(), 2e-3 * kPressurePa)
      << rve.StressPa() << "\n" << expected_stress;
  const Voigt6x6 expected_tangent = sum.stiffness_nm / volume_m3;
  EXPECT_LT((rve.TangentPa() - expected_tangent).norm(), 1e-9 * expected_tangent.norm());
  // The tangent has major symmetry and is positive semi-definite.
  EXPECT_LT((rve.TangentPa() - rve.TangentPa().transpose()).norm(), 1e-9 * expected_tangent.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Voigt6x6>(rve.TangentPa()).eigenvalues().minCoeff(),
            -1e-9 * expected_tangent.norm());
}

TEST_F(RveTest, SaveRestoreIsBitIdenticalAndGenerationIsDeterministic) {
  MixedControl shear;
  shear.strain_rate_1_s(0, 2) = 2.0;
  shear.stress_controlled[2][2] = true;
  shear.target_stress_pa(2, 2) = -kPressurePa;
  Rve original = *seed_law_;
  original.Run(shear, 300);
  const std::string saved = original.Save();
  original.Run(shear, 500);
  Rve restored = Rve::Restore(saved);
  restored.Run(shear, 500);
  EXPECT_EQ(restored.Save(), original.Save());
  EXPECT_TRUE(restored.StressPa() == original.StressPa());
  // Under 1 kB per grain (grains, about 3 contacts each with history and forces).
  EXPECT_LT(saved.size(), 1000u * 200u);
  EXPECT_THROW(Rve::Restore(saved.substr(0, 100)), InputError);
  EXPECT_THROW(Rve::Restore(saved + "x"), InputError);

  // Same seed, same bytes; another seed, another packing.
  RveParams params = SmallFrictionless();
  EXPECT_EQ(Rve::Generate(params).Save(), frictionless_->Save());
  params.seed = 2;
  EXPECT_FALSE(Rve::Generate(params).Snapshot().stress_pa == frictionless_->Snapshot().stress_pa);
}

TEST_F(RveTest, ThreadCountDoesNotChangeTheResult) {
  MixedControl shear;
  shear.strain_rate_1_s(0, 1) = 2.0;
  Rve one = *seed_law_;
  one.Run(shear, 400);
  Rve two = Rve::Restore(seed_law_->Save(), 2);
  ASSERT_EQ(two.params().threads, 2);
  two.Run(shear, 400);
  EXPECT_TRUE(one.StressPa() == two.StressPa());
}

TEST_F(RveTest, SimpleShearHoldsTheNormalStressAndMobilisesFriction) {
  Rve rve = *seed_law_;
  MixedControl shear;
  const double rate_1_s = rve.StableRate1S();
  shear.strain_rate_1_s(0, 2) = rate_1_s;
  shear.stress_controlled[2][2] = true;
  shear.target_stress_pa(2, 2) = -kPressurePa;
  const double gamma = 0.1;
  rve.Run(shear, static_cast<int>(gamma / (rate_1_s * rve.time_step_s())));
  const RveSnapshot s = rve.Snapshot();
  EXPECT_NEAR(-s.stress_pa(2, 2), kPressurePa, 0.05 * kPressurePa);
  EXPECT_NEAR(2.0 * s.strain(0, 2), gamma, 1e-3);
  EXPECT_NEAR(s.strain(0, 0), 0.0, 1e-12);  // no lateral strain
  EXPECT_NEAR(s.strain(1, 1), 0.0, 1e-12);
  // Shear stress mobilised in the direction of shearing: tau / sigma_n well above zero and below
  // tan 60 deg (the triaxial test checks the friction angle against published ranges).
  const double ratio = s.stress_pa(0, 2) / -s.stress_pa(2, 2);
  EXPECT_GT(ratio, 0.3);
  EXPECT_LT(ratio, std::tan(units::DegreesToRadians(60.0)));
  // The contacts turn towards the major compression, (1, 0, -1)/sqrt 2 for a positive sigma_xz:
  // the fabric's xz component takes the other sign, and exceeds the consolidated noise.
  const Matrix3 consolidated = seed_law_->Snapshot().fabric;
  EXPECT_LT(s.fabric(0, 2), -0.05) << s.fabric;
  EXPECT_LT(std::abs(consolidated(0, 2)), std::abs(s.fabric(0, 2)));
  EXPECT_NEAR(s.fabric.trace(), 1.0, 1e-12);
}

TEST_F(RveTest, ConstitutiveSeamLeavesCommittedStatesAndFailsCleanly) {
  RveMaterialParams params;
  params.rve = seed_law_->params();
  params.batch_threads = 2;
  const RveMaterial material(params, *seed_law_);
  const std::unique_ptr<material::MaterialState> committed = material.InitialState();
  const std::string before = committed->Serialize();
  std::vector<material::PointIncrement> batch(4);
  for (int k = 0; k < 4; ++k) {
    batch[k].committed = committed.get();
    batch[k].displacement_gradient_increment(2, 2) = -1e-4 * (k + 1);
  }
  batch[3].displacement_gradient_increment(0, 0) = 0.5;  // too large: refused
  const std::vector<material::PointResponse> responses = material.Update(batch, true);
  ASSERT_EQ(responses.size(), 4u);
  EXPECT_EQ(committed->Serialize(), before);
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(responses[k].status, material::UpdateStatus::kOk) << responses[k].reason;
    ASSERT_TRUE(responses[k].state);
    EXPECT_TRUE(responses[k].has_tangent);
    // Compressing the axis raises its stress; more compression, more stress.
    EXPECT_LT(responses[k].stress_pa(2, 2), -kPressurePa);
    if (k > 0) {
      EXPECT_LT(responses[k].stress_pa(2, 2), responses[k - 1].stress_pa(2, 2));
    }
  }
  EXPECT_EQ(responses[3].status, material::UpdateStatus::kFailed);
  EXPECT_FALSE(responses[3].state);
  EXPECT_NE(responses[3].reason.find("exceeds"), std::string::npos);

  // One point at a time on one thread gives the same bits as the batch on two.
  RveMaterialParams serial_params = params;
  serial_params.batch_threads = 1;
  const RveMaterial serial(serial_params, *seed_law_);
  const std::vector<material::PointResponse> single = serial.Update({batch[1]}, false);
  EXPECT_TRUE(single[0].stress_pa == responses[1].stress_pa);
  // States move between ranks as bytes.
  const std::unique_ptr<material::MaterialState> moved =
      material.RestoreState(responses[1].state->Serialize());
  EXPECT_EQ(moved->Serialize(), responses[1].state->Serialize());
}

TEST(RveParamsTest, BadInputNamesTheField) {
  auto rejects = [](auto mutate, const std::string& field) {
    RveParams params;
    mutate(params);
    try {
      params.Validate();
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
    }
  };
  rejects([](RveParams& p) { p.grain_count = 5; }, "grain_count");
  rejects([](RveParams& p) { p.mean_radius_m = -1.0; }, "mean_radius_m");
  rejects([](RveParams& p) { p.radius_spread = 0.9; }, "radius_spread");
  rejects([](RveParams& p) { p.consolidation_pressure_pa = 0.0; }, "consolidation_pressure_pa");
  rejects([](RveParams& p) { p.initial_solid_fraction = 0.7; }, "initial_solid_fraction");
  rejects([](RveParams& p) { p.material.poisson_ratio = 0.6; }, "poisson_ratio");
  rejects([](RveParams& p) { p.max_inertial_number = 0.0; }, "max_inertial_number");
}

}  // namespace
}  // namespace gonogo::dem::rve
