// Drucker-Prager against closed forms: the Mohr-Coulomb deviator at failure in drained triaxial
// compression, the flow rule's dilatancy, the apex, the plane-strain match, and parameter errors.
#include "solvers/material/drucker_prager.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/kinematics.h"
#include "solvers/material/linear_elastic.h"
#include "solvers/material/registry.h"

namespace gonogo::material {
namespace {

constexpr double kYoungPa = 20e6;
constexpr double kPoisson = 0.3;

DruckerPragerParams Soil(
    double cohesion_pa, double phi_deg, double psi_deg,
    DruckerPragerParams::Match match = DruckerPragerParams::Match::kTriaxialCompression) {
  return DruckerPragerParams{kYoungPa, kPoisson, cohesion_pa, phi_deg, psi_deg, match};
}

// One material point driven along a path on which each Voigt component is either strain
// controlled (its increment prescribed) or stress controlled (held at a target by Newton
// iterations on its strain increment, with the model's tangent). Strains are Hughes-Winget
// strain increments applied without rotation.
class MixedControlPoint {
 public:
  explicit MixedControlPoint(const ConstitutiveModel& model)
      : model_(model), state_(model.InitialState()) {}

  // `strain_increment`: used for the strain-controlled components and as the first guess for the
  // others. Returns the strain increment taken.
  Vector6 Step(Vector6 strain_increment, const std::array<bool, 6>& stress_controlled,
               const Vector6& target_stress_pa) {
    std::vector<int> free;
    for (int j = 0; j < 6; ++j)
      if (stress_controlled[j]) free.push_back(j);
    for (int iteration = 0; iteration < 50; ++iteration) {
      PointResponse response = Apply(strain_increment);
      EXPECT_EQ(response.status, UpdateStatus::kOk) << response.reason;
      const Vector6 stress = StressToVoigt(response.stress_pa);
      Eigen::VectorXd residual(free.size());
      Eigen::MatrixXd jacobian(free.size(), free.size());
      for (size_t a = 0; a < free.size(); ++a) {
        residual(a) = stress(free[a]) - target_stress_pa(free[a]);
        for (size_t b = 0; b < free.size(); ++b)
          jacobian(a, b) = response.tangent_pa(free[a], free[b]);
      }
      if (free.empty() || residual.norm() < 1e-10 * std::max(target_stress_pa.norm(), 1.0)) {
        state_ = std::move(response.state);
        stress_pa_ = stress;
        strain_ += strain_increment;
        return strain_increment;
      }
      const Eigen::VectorXd correction = jacobian.fullPivLu().solve(residual);
      for (size_t a = 0; a < free.size(); ++a) strain_increment(free[a]) -= correction(a);
    }
    ADD_FAILURE() << "mixed control did not converge";
    return strain_increment;
  }

  PointResponse Apply(const Vector6& strain_increment) const {
    std::vector<PointIncrement> one(1);
    one[0].displacement_gradient_increment =
        DisplacementGradientForStrain(VoigtToStrain(strain_increment));
    one[0].committed = state_.get();
    std::vector<PointResponse> responses = model_.Update(one, true);
    return std::move(responses[0]);
  }

  const Vector6& stress_pa() const { return stress_pa_; }
  const Vector6& strain() const { return strain_; }
  const MaterialState& state() const { return *state_; }

 private:
  const ConstitutiveModel& model_;
  std::unique_ptr<MaterialState> state_;
  Vector6 stress_pa_ = Vector6::Zero();
  Vector6 strain_ = Vector6::Zero();  // accumulated, engineering shears
};

constexpr std::array<bool, 6> kAllNormalStresses = {true, true, true, false, false, false};
constexpr std::array<bool, 6> kLateralStresses = {true, true, false, false, false, false};

Vector6 Isotropic(double stress_pa) {
  Vector6 v = Vector6::Zero();
  v.head<3>().setConstant(stress_pa);
  return v;
}

Vector6 Voigt(double xx, double yy, double zz, double yz, double xz, double xy) {
  Vector6 v;
  v << xx, yy, zz, yz, xz, xy;
  return v;
}

// The coefficients against hand values of dSN eqs. 6.119 and 6.121 at 30 degrees.
TEST(DruckerPragerTest, MatchingCoefficients) {
  const DruckerPrager triaxial(Soil(10e3, 30, 30));
  EXPECT_NEAR(triaxial.eta(), 1.2 / std::sqrt(3.0), 1e-14);  // 6 (1/2) / (sqrt 3 * 5/2)
  EXPECT_NEAR(triaxial.xi(), 1.2, 1e-14);                    // 6 (sqrt 3 / 2) / (sqrt 3 * 5/2)
  EXPECT_NEAR(triaxial.eta_bar(), triaxial.eta(), 1e-15);
  const DruckerPrager plane(Soil(10e3, 30, 0, DruckerPragerParams::Match::kPlaneStrain));
  EXPECT_NEAR(plane.eta(), std::sqrt(3.0 / 13.0), 1e-14);  // tan 30 = 1/sqrt 3: 9 + 4 = 13
  EXPECT_NEAR(plane.xi(), 3.0 / std::sqrt(13.0), 1e-14);
  EXPECT_EQ(plane.eta_bar(), 0.0);
}

// (1) Drained triaxial compression, lateral stress held at -sigma3: elastic slope E (and lateral
// strain -nu), then the Mohr-Coulomb deviator q_f = 2 (c cos phi + sigma3 sin phi) / (1 - sin phi)
// (compression positive), held while the strain grows, with the dilatancy of the flow rule:
// d eps_v / d eps_a = eta_bar / (eta_bar / 3 - 1 / sqrt 3) once the stress is stationary.
TEST(DruckerPragerTest, DrainedTriaxialReachesMohrCoulomb) {
  const double cohesion = 10e3, phi = units::DegreesToRadians(30), sigma3 = 100e3;
  const DruckerPrager model(Soil(cohesion, 30, 10));
  MixedControlPoint point(model);
  point.Step(Vector6::Zero(), kAllNormalStresses, Isotropic(-sigma3));
  ASSERT_NEAR(point.stress_pa()(2), -sigma3, 1e-6);

  const double axial_step = -1e-4;
  const double q_failure =
      2 * (cohesion * std::cos(phi) + sigma3 * std::sin(phi)) / (1 - std::sin(phi));  // 234.6 kPa
  double q_max = 0;
  Vector6 guess = Voigt(0, 0, axial_step, 0, 0, 0);
  Vector6 last;
  for (int k = 0; k < 300; ++k) {
    const double axial_stress_before = point.stress_pa()(2);
    last = point.Step(guess, kLateralStresses, Isotropic(-sigma3));
    guess = last;
    const double q = -point.stress_pa()(2) - sigma3;
    q_max = std::max(q_max, q);
    if (k < 5) {  // elastic: q_f is reached at an axial strain of about q_f / E = 0.0117
      EXPECT_NEAR((point.stress_pa()(2) - axial_stress_before) / axial_step, kYoungPa,
                  1e-9 * kYoungPa);
      EXPECT_NEAR(last(0) / last(2), -kPoisson, 1e-9);
    }
  }
  const double q = -point.stress_pa()(2) - sigma3;
  EXPECT_NEAR(q, q_failure, 1e-6 * q_failure);
  EXPECT_LE(q_max, q_failure * (1 + 1e-9));
  const double eta_bar = model.eta_bar();
  const double volumetric = last.head<3>().sum();
  EXPECT_NEAR(volumetric / last(2), eta_bar / (eta_bar / 3 - 1 / std::sqrt(3.0)), 1e-6);
  EXPECT_GT(volumetric, 0);  // dilation under compression
}

// (2) Non-associated flow: the plastic strain of one increment from the cone is
// d_gamma (s / (2 sqrt J2) + eta_bar / 3 1) with d_gamma = F_trial / (G + K eta eta_bar): its
// volume change is eta_bar d_gamma (none for psi = 0), its deviatoric norm d_gamma / sqrt 2, and
// for psi = phi it is normal to the yield surface.
TEST(DruckerPragerTest, PlasticStrainFollowsTheFlowRule) {
  for (double psi_deg : {0.0, 10.0, 30.0}) {
    SCOPED_TRACE(psi_deg);
    const DruckerPrager model(Soil(10e3, 30, psi_deg));
    const double bulk = kYoungPa / (3 * (1 - 2 * kPoisson));
    const double shear = kYoungPa / (2 * (1 + kPoisson));
    MixedControlPoint point(model);
    point.Step(Voigt(-1e-3, -1e-3, -1e-3, 0, 0, 0), {}, Vector6::Zero());
    for (int k = 0; k < 6; ++k) point.Step(Voigt(5e-4, 5e-4, -1e-3, 0, 0, 0), {}, Vector6::Zero());
    const Matrix3 stress_before = VoigtToStress(point.stress_pa());
    ASSERT_NEAR(model.YieldFunctionPa(stress_before), 0.0, 1e-9 * stress_before.norm());
    const double plastic_before =
        dynamic_cast<const DruckerPragerState&>(point.state()).equivalent_plastic_strain();

    const Vector6 strain = Voigt(3e-4, 1e-4, -1e-3, 2e-4, 0, 1e-4);
    const Matrix3 strain_tensor = VoigtToStrain(strain);
    point.Step(strain, {}, Vector6::Zero());
    const Matrix3 stress_after = VoigtToStress(point.stress_pa());
    // Plastic strain = total - elastic, the elastic part from the stress change by compliance.
    const Matrix3 stress_change = stress_after - stress_before;
    const Matrix3 elastic_strain =
        stress_change.trace() / (9 * bulk) * Matrix3::Identity() +
        (stress_change - stress_change.trace() / 3 * Matrix3::Identity()) / (2 * shear);
    const Matrix3 plastic = strain_tensor - elastic_strain;
    const Matrix3 plastic_deviator = plastic - plastic.trace() / 3 * Matrix3::Identity();

    // Closed form from the trial stress.
    const Matrix3 trial = stress_before + IsotropicElasticStress(bulk, shear, strain_tensor);
    const Matrix3 trial_deviator = trial - trial.trace() / 3 * Matrix3::Identity();
    const double root_j2 = std::sqrt(0.5 * trial_deviator.squaredNorm());
    const double d_gamma =
        model.YieldFunctionPa(trial) / (shear + bulk * model.eta() * model.eta_bar());
    ASSERT_GT(d_gamma, 1e-5);
    EXPECT_NEAR(plastic.trace(), model.eta_bar() * d_gamma, 1e-7 * d_gamma);
    EXPECT_NEAR(plastic_deviator.norm(), d_gamma / std::sqrt(2.0), 1e-7 * d_gamma);
    EXPECT_LT((plastic_deviator - d_gamma * trial_deviator / (2 * root_j2)).norm(), 1e-7 * d_gamma);
    if (psi_deg == 0) {
      EXPECT_LT(std::abs(plastic.trace()), 1e-7 * d_gamma);
    }
    const double plastic_after =
        dynamic_cast<const DruckerPragerState&>(point.state()).equivalent_plastic_strain();
    EXPECT_NEAR(plastic_after - plastic_before, std::sqrt(2.0 / 3.0) * plastic_deviator.norm(),
                1e-7 * d_gamma);
    if (psi_deg == 30) {
      // Normality: plastic strain parallel to dF/dsigma = s / (2 sqrt J2) + eta / 3 1.
      const Matrix3 deviator = stress_after - stress_after.trace() / 3 * Matrix3::Identity();
      const Matrix3 normal = deviator / (2 * std::sqrt(0.5 * deviator.squaredNorm())) +
                             model.eta() / 3 * Matrix3::Identity();
      EXPECT_LT((plastic / plastic.norm() - normal / normal.norm()).norm(), 1e-7);
    }
  }
}

// (3) Apex: a large isotropic extension ends at p = xi c / eta, s = 0 (zero stress when c = 0),
// with a zero tangent.
TEST(DruckerPragerTest, IsotropicExtensionReturnsToTheApex) {
  for (double cohesion : {10e3, 0.0}) {
    SCOPED_TRACE(cohesion);
    const DruckerPrager model(Soil(cohesion, 30, 10));
    MixedControlPoint point(model);
    const PointResponse response = point.Apply(Voigt(1e-2, 1e-2, 1e-2, 0, 0, 0));
    ASSERT_EQ(response.status, UpdateStatus::kOk);
    const double apex = cohesion * std::sqrt(3.0);  // xi c / eta = 1.2 c / (1.2 / sqrt 3) at 30 deg
    const Matrix3 expected = apex * Matrix3::Identity();
    EXPECT_LE((response.stress_pa - expected).norm(), 1e-12 * apex);
    EXPECT_EQ(response.tangent_pa.norm(), 0.0);
  }
}

// (4) Plane-strain match. Pure shear with phi = 0: sqrt(J2) = tau = xi c, which is c (Tresca's
// limit) with dSN eq. 6.121 and 2c / sqrt 3 with eq. 6.119. With phi = psi = 30 degrees, in-plane
// normal stresses held at sigma_m and eps_zz = 0, the limit shear stress is Mohr-Coulomb's
// tau = c cos phi - sigma_m sin phi (tension positive) in plane strain.
TEST(DruckerPragerTest, PlaneStrainMatchGivesMohrCoulombInPlaneStrain) {
  const double cohesion = 10e3;
  const std::array<DruckerPragerParams::Match, 2> matches = {
      DruckerPragerParams::Match::kPlaneStrain, DruckerPragerParams::Match::kTriaxialCompression};
  const std::array<double, 2> limits = {cohesion, 2 * cohesion / std::sqrt(3.0)};
  for (int m = 0; m < 2; ++m) {
    SCOPED_TRACE(m);
    const DruckerPrager model(Soil(cohesion, 0, 0, matches[m]));
    MixedControlPoint point(model);
    for (int k = 0; k < 50; ++k) point.Step(Voigt(0, 0, 0, 0, 0, 2e-4), {}, Vector6::Zero());
    EXPECT_NEAR(point.stress_pa()(5), limits[m], 1e-10 * limits[m]);
    EXPECT_LT(point.stress_pa().head<5>().norm(), 1e-9 * limits[m]);
  }

  const double phi = units::DegreesToRadians(30), mean = -100e3;
  const DruckerPrager model(Soil(cohesion, 30, 30, DruckerPragerParams::Match::kPlaneStrain));
  MixedControlPoint point(model);
  point.Step(Vector6::Zero(), kAllNormalStresses, Isotropic(mean));
  const std::array<bool, 6> in_plane = {true, true, false, false, false, false};
  const Vector6 target = Isotropic(mean);
  Vector6 guess = Voigt(0, 0, 0, 0, 0, 2e-4);
  double previous = 0;
  for (int k = 0; k < 500; ++k) {
    previous = point.stress_pa()(5);
    guess = point.Step(guess, in_plane, target);
  }
  const double tau = point.stress_pa()(5);
  const double expected = cohesion * std::cos(phi) - mean * std::sin(phi);  // 58.66 kPa
  EXPECT_NEAR(tau, expected, 1e-6 * expected);
  EXPECT_NEAR(tau, previous, 1e-9 * expected);  // a limit, not still rising
}

// (5) Parameter errors name their field; the registry names unknown and missing keys.
TEST(DruckerPragerTest, ErrorsNameTheField) {
  auto message_of = [](const DruckerPragerParams& params) -> std::string {
    try {
      DruckerPrager model(params);
    } catch (const InputError& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_NE(message_of(Soil(10e3, 95, 0)).find("material.friction_angle_deg"), std::string::npos);
  EXPECT_NE(message_of(Soil(10e3, 30, 35)).find("dilation_angle_deg"), std::string::npos);
  EXPECT_NE(message_of(Soil(-1, 30, 0)).find("cohesion_pa"), std::string::npos);
  EXPECT_NE(message_of(Soil(0, 0, 0)).find("cohesion_pa"), std::string::npos);
  DruckerPragerParams soft = Soil(10e3, 30, 0);
  soft.young_pa = 0;
  EXPECT_NE(message_of(soft).find("young_pa"), std::string::npos);
  soft = Soil(10e3, 30, 0);
  soft.poisson = 0.5;
  EXPECT_NE(message_of(soft).find("poisson"), std::string::npos);
  EXPECT_EQ(message_of(Soil(10e3, 30, 0)), "");

  MaterialRegistry registry;
  RegisterBuiltinMaterials(registry);
  ParameterMap parameters = registry.Get("drucker-prager").example_parameters;
  EXPECT_NO_THROW(registry.Make("drucker-prager", parameters));
  auto factory_message = [&](const ParameterMap& map) -> std::string {
    try {
      registry.Make("drucker-prager", map);
    } catch (const InputError& error) {
      return error.field();
    }
    return "";
  };
  ParameterMap unknown = parameters;
  unknown["friction_angle"] = 30;
  EXPECT_EQ(factory_message(unknown), "material.friction_angle");
  ParameterMap missing = parameters;
  missing.erase("cohesion_pa");
  EXPECT_EQ(factory_message(missing), "material.cohesion_pa");
  ParameterMap invalid = parameters;
  invalid["friction_angle_deg"] = 95;
  EXPECT_EQ(factory_message(invalid), "material.friction_angle_deg");
  ParameterMap bad_match = parameters;
  bad_match["plane_strain_match"] = 0.5;
  EXPECT_EQ(factory_message(bad_match), "material.plane_strain_match");
  try {
    registry.Get("mohr-coulomb");
    ADD_FAILURE() << "no error for an unknown model";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "material");
    EXPECT_NE(std::string(error.what()).find("drucker-prager, linear-elastic"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(registry.Register(registry.Get("linear-elastic")), InputError);  // twice
}

}  // namespace
}  // namespace gonogo::material
