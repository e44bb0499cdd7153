#include "solvers/material/drucker_prager.h"

#include <cassert>
#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/kinematics.h"
#include "solvers/material/linear_elastic.h"

namespace gonogo::material {
namespace {

const double kSqrt2 = std::sqrt(2.0);
const double kSqrt3 = std::sqrt(3.0);

// A trial stress is plastic when F_trial > kYieldTolerance * (sqrt(J2) + |eta p| + xi c): a point
// returned to the cone (F ~ 1e-16 of that scale after roundoff) and then rotated or given a zero
// increment stays elastic, so its stress is left exactly as it was.
constexpr double kYieldTolerance = 1e-12;

// A Drucker-Prager cone fitted to a Mohr-Coulomb surface of angle `angle_deg`: the coefficient of
// p (eta from phi, or eta_bar from psi) and the coefficient of c (xi).
struct ConeFit {
  double pressure_coefficient;
  double cohesion_coefficient;
};

ConeFit FitMohrCoulomb(double angle_deg, DruckerPragerParams::Match match) {
  const double angle = units::DegreesToRadians(angle_deg);
  if (match == DruckerPragerParams::Match::kPlaneStrain) {
    // dSN eq. 6.121: eta = 3 tan(phi) / sqrt(9 + 12 tan^2 phi), xi = 3 / sqrt(9 + 12 tan^2 phi);
    // exact Mohr-Coulomb limit loads in plane strain with associated flow.
    const double tangent = std::tan(angle);
    const double root = std::sqrt(9.0 + 12.0 * tangent * tangent);
    return {3.0 * tangent / root, 3.0 / root};
  }
  // dSN eq. 6.119 (outer cone, meets Mohr-Coulomb on the triaxial compression meridian):
  // eta = 6 sin(phi) / (sqrt(3) (3 - sin phi)), xi = 6 cos(phi) / (sqrt(3) (3 - sin phi)).
  const double denominator = kSqrt3 * (3.0 - std::sin(angle));
  return {6.0 * std::sin(angle) / denominator, 6.0 * std::cos(angle) / denominator};
}

}  // namespace

void DruckerPragerParams::Validate(const std::string& field_prefix) const {
  Require(std::isfinite(young_pa) && young_pa > 0.0, field_prefix + "young_pa", "must be > 0 Pa");
  Require(poisson > -1.0 && poisson < 0.5, field_prefix + "poisson", "must be in (-1, 0.5)");
  Require(std::isfinite(cohesion_pa) && cohesion_pa >= 0.0, field_prefix + "cohesion_pa",
          "must be >= 0 Pa");
  Require(friction_angle_deg >= 0.0 && friction_angle_deg < 90.0,
          field_prefix + "friction_angle_deg", "must be in [0, 90) degrees");
  Require(dilation_angle_deg >= 0.0 && dilation_angle_deg <= friction_angle_deg,
          field_prefix + "dilation_angle_deg", "must be in [0, friction_angle_deg] degrees");
  Require(cohesion_pa > 0.0 || friction_angle_deg > 0.0, field_prefix + "cohesion_pa",
          "cohesion_pa and friction_angle_deg are both zero: the material has no strength");
  Require(match == Match::kTriaxialCompression || match == Match::kPlaneStrain,
          field_prefix + "match", "must be triaxial compression or plane strain");
}

std::unique_ptr<MaterialState> DruckerPragerState::Clone() const {
  return std::make_unique<DruckerPragerState>(stress_pa_, equivalent_plastic_strain_);
}

std::string DruckerPragerState::Serialize() const {
  double values[7];
  Eigen::Map<Vector6> stress(values);
  stress = StressToVoigt(stress_pa_);
  values[6] = equivalent_plastic_strain_;
  return PackDoubles(values, 7);
}

DruckerPrager::DruckerPrager(const DruckerPragerParams& params) : params_(params) {
  params_.Validate("material.");
  const LinearElasticParams elastic{params_.young_pa, params_.poisson};
  bulk_pa_ = elastic.bulk_pa();
  shear_pa_ = elastic.shear_pa();
  const ConeFit friction = FitMohrCoulomb(params_.friction_angle_deg, params_.match);
  eta_ = friction.pressure_coefficient;
  xi_ = friction.cohesion_coefficient;
  eta_bar_ = FitMohrCoulomb(params_.dilation_angle_deg, params_.match).pressure_coefficient;
}

std::unique_ptr<MaterialState> DruckerPrager::InitialState() const {
  return std::make_unique<DruckerPragerState>(Matrix3::Zero(), 0.0);
}

std::unique_ptr<MaterialState> DruckerPrager::RestoreState(const std::string& bytes) const {
  const std::vector<double> values = UnpackDoubles(bytes, 7, "material.state");
  Require(values[6] >= 0.0, "material.state", "negative equivalent plastic strain");
  return std::make_unique<DruckerPragerState>(
      VoigtToStress(Eigen::Map<const Vector6>(values.data())), values[6]);
}

double DruckerPrager::YieldFunctionPa(const Matrix3& stress_pa) const {
  const double pressure = stress_pa.trace() / 3.0;
  const Matrix3 deviator = stress_pa - pressure * Matrix3::Identity();
  return std::sqrt(0.5 * deviator.squaredNorm()) + eta_ * pressure - xi_ * params_.cohesion_pa;
}

std::vector<PointResponse> DruckerPrager::Update(const std::vector<PointIncrement>& increments,
                                                 bool want_tangent) const {
  return UpdateEachPoint(increments, [this, want_tangent](const PointIncrement& increment) {
    return UpdateOne(increment, want_tangent);
  });
}

PointResponse DruckerPrager::UpdateOne(const PointIncrement& increment, bool want_tangent) const {
  PointResponse response;
  const auto* committed = dynamic_cast<const DruckerPragerState*>(increment.committed);
  if (committed == nullptr) {
    response.reason = "committed state is missing or not a drucker-prager state";
    return response;
  }
  // Objective rotation of the committed stress (Hughes & Winget 1980), then the elastic
  // predictor sigma_trial = R sigma_n R^T + C : d_eps (dSN Box 8.9, step 1).
  Matrix3 trial;
  if (!ElasticTrialStress(committed->stress_pa(), increment.displacement_gradient_increment,
                          bulk_pa_, shear_pa_, &trial, &response.reason)) {
    return response;
  }
  const Returned returned = ReturnMap(trial, want_tangent);
  response.stress_pa = returned.stress_pa;
  if (want_tangent) {
    response.tangent_pa = returned.tangent_pa;
    response.has_tangent = true;
  }
  response.state = std::make_unique<DruckerPragerState>(
      returned.stress_pa,
      committed->equivalent_plastic_strain() + returned.equivalent_plastic_strain_increment);
  response.status = UpdateStatus::kOk;
  return response;
}

DruckerPrager::Returned DruckerPrager::ReturnMap(const Matrix3& trial_stress_pa,
                                                 bool want_tangent) const {
  const double bulk = bulk_pa_, shear = shear_pa_, cohesion = params_.cohesion_pa;
  const Matrix3 identity = Matrix3::Identity();
  const double pressure_trial = trial_stress_pa.trace() / 3.0;
  const Matrix3 deviator_trial = trial_stress_pa - pressure_trial * identity;
  const double root_j2_trial = std::sqrt(0.5 * deviator_trial.squaredNorm());
  Returned out;

  // Elastic: F_trial <= 0 (dSN Box 8.9, step 2).
  const double yield_trial = root_j2_trial + eta_ * pressure_trial - xi_ * cohesion;
  const double yield_scale = root_j2_trial + std::abs(eta_ * pressure_trial) + xi_ * cohesion;
  if (!(yield_trial > kYieldTolerance * yield_scale)) {
    out.stress_pa = trial_stress_pa;
    if (want_tangent) out.tangent_pa = IsotropicElasticTangent(bulk, shear);
    return out;
  }

  // Return to the smooth cone (dSN Box 8.9, step 3, H = 0): F is linear in d_gamma, so
  //   d_gamma = F_trial / (G + K eta eta_bar),
  //   s = (1 - G d_gamma / sqrt(J2_trial)) s_trial,   p = p_trial - K eta_bar d_gamma,
  // valid while sqrt(J2_trial) - G d_gamma >= 0 (dSN step 4).
  const double cone_stiffness = shear + bulk * eta_ * eta_bar_;
  const double d_gamma = yield_trial / cone_stiffness;
  if (root_j2_trial - shear * d_gamma >= 0.0) {
    const double shrink = shear * d_gamma / root_j2_trial;
    out.stress_pa =
        (1.0 - shrink) * deviator_trial + (pressure_trial - bulk * eta_bar_ * d_gamma) * identity;
    // de_p = d_gamma s_trial / (2 sqrt(J2_trial)), |de_p| = d_gamma / sqrt(2), so
    // sqrt(2/3 de_p : de_p) = d_gamma / sqrt(3).
    out.equivalent_plastic_strain_increment = d_gamma / kSqrt3;
    if (!want_tangent) return out;
    // Consistent tangent, dSN Box 8.10 with H = 0, A = 1 / (G + K eta eta_bar),
    // n = s_trial / |s_trial|, I_d = I_s - 1 (x) 1 / 3, and G d_gamma / sqrt(J2_trial) written for
    // dSN's d_gamma / (sqrt(2) |eps_d_e_trial|):
    //   D = 2G (1 - G d_gamma / sqrt(J2_trial)) I_d + 2G (G d_gamma / sqrt(J2_trial) - G A) n (x) n
    //       - sqrt(2) G A K (eta n (x) 1 + eta_bar 1 (x) n) + K (1 - K eta eta_bar A) 1 (x) 1.
    // In Voigt form a (x) b is a_v b_v^T with tensor components in both (engineering strains).
    const double a = 1.0 / cone_stiffness;
    const Vector6 n = StressToVoigt(deviator_trial / deviator_trial.norm());
    Vector6 one;
    one << 1, 1, 1, 0, 0, 0;
    Voigt6x6 deviatoric_identity = Voigt6x6::Zero();
    deviatoric_identity.diagonal() << 1, 1, 1, 0.5, 0.5, 0.5;
    deviatoric_identity -= one * one.transpose() / 3.0;
    out.tangent_pa =
        2.0 * shear * (1.0 - shrink) * deviatoric_identity +
        2.0 * shear * (shrink - shear * a) * n * n.transpose() -
        kSqrt2 * shear * a * bulk * (eta_ * n * one.transpose() + eta_bar_ * one * n.transpose()) +
        bulk * (1.0 - bulk * eta_ * eta_bar_ * a) * one * one.transpose();
    return out;
  }

  // Return to the apex (dSN Box 8.9, step 4 fails), perfectly plastic: p = xi c / eta, s = 0;
  // the apex is the origin when c = 0. There is no apex when phi = 0 (eta = 0): then
  // sqrt(J2_trial) - G d_gamma = xi c > 0 and the cone return above is always valid.
  assert(eta_ > 0.0);
  out.stress_pa = (xi_ * cohesion / eta_) * identity;
  // The whole trial deviator is plastic: de_p = s_trial / (2G), sqrt(2/3 de_p : de_p) =
  // sqrt(J2_trial) / (sqrt(3) G).
  out.equivalent_plastic_strain_increment = root_j2_trial / (kSqrt3 * shear);
  // Perfect plasticity: the apex stress does not depend on the strain.
  if (want_tangent) out.tangent_pa = Voigt6x6::Zero();
  return out;
}

}  // namespace gonogo::material
