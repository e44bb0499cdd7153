#include "solvers/material/linear_elastic.h"

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/material/kinematics.h"

namespace gonogo::material {

void LinearElasticParams::Validate(const std::string& field_prefix) const {
  Require(std::isfinite(young_pa) && young_pa > 0.0, field_prefix + "young_pa", "must be > 0 Pa");
  Require(poisson > -1.0 && poisson < 0.5, field_prefix + "poisson", "must be in (-1, 0.5)");
}

Matrix3 IsotropicElasticStress(double bulk_pa, double shear_pa, const Matrix3& strain) {
  const double volumetric = strain.trace();
  const Matrix3 deviatoric = strain - (volumetric / 3.0) * Matrix3::Identity();
  return bulk_pa * volumetric * Matrix3::Identity() + 2.0 * shear_pa * deviatoric;
}

Voigt6x6 IsotropicElasticTangent(double bulk_pa, double shear_pa) {
  // Normal block: K 1 1^T + 2G (I - 1 1^T / 3); shear block: G (engineering shear strains).
  Voigt6x6 tangent = Voigt6x6::Zero();
  tangent.topLeftCorner<3, 3>().setConstant(bulk_pa - 2.0 * shear_pa / 3.0);
  tangent.diagonal().head<3>().array() += 2.0 * shear_pa;
  tangent.diagonal().tail<3>().setConstant(shear_pa);
  return tangent;
}

std::unique_ptr<MaterialState> StressState::Clone() const {
  return std::make_unique<StressState>(stress_pa_);
}

std::string StressState::Serialize() const {
  const Vector6 voigt = StressToVoigt(stress_pa_);
  return PackDoubles(voigt.data(), 6);
}

LinearElastic::LinearElastic(const LinearElasticParams& params)
    : params_(params), bulk_pa_(params.bulk_pa()), shear_pa_(params.shear_pa()) {
  params_.Validate("material.");
}

std::unique_ptr<MaterialState> LinearElastic::InitialState() const {
  return std::make_unique<StressState>(Matrix3::Zero());
}

std::unique_ptr<MaterialState> LinearElastic::RestoreState(const std::string& bytes) const {
  const std::vector<double> values = UnpackDoubles(bytes, 6, "material.state");
  return std::make_unique<StressState>(VoigtToStress(Eigen::Map<const Vector6>(values.data())));
}

bool ElasticTrialStress(const Matrix3& committed_stress_pa,
                        const Matrix3& displacement_gradient_increment, double bulk_pa,
                        double shear_pa, Matrix3* trial_stress_pa, std::string* reason) {
  const IncrementKinematics kinematics = HughesWinget(displacement_gradient_increment);
  if (!kinematics.ok()) {
    *reason = kinematics.failure_reason;
    return false;
  }
  const Matrix3& rotation = kinematics.rotation;
  const Matrix3 rotated = rotation * committed_stress_pa * rotation.transpose();
  *trial_stress_pa = 0.5 * (rotated + rotated.transpose()) +
                     IsotropicElasticStress(bulk_pa, shear_pa, kinematics.strain_increment);
  return true;
}

std::vector<PointResponse> LinearElastic::Update(const std::vector<PointIncrement>& increments,
                                                 bool want_tangent) const {
  return UpdateEachPoint(increments, [this, want_tangent](const PointIncrement& increment) {
    return UpdateOne(increment, want_tangent);
  });
}

PointResponse LinearElastic::UpdateOne(const PointIncrement& increment, bool want_tangent) const {
  PointResponse response;
  const auto* committed = dynamic_cast<const StressState*>(increment.committed);
  if (committed == nullptr) {
    response.reason = "committed state is missing or not a linear-elastic state";
    return response;
  }
  // sigma_{n+1} = R sigma_n R^T + C : d_eps (Hughes & Winget 1980).
  if (!ElasticTrialStress(committed->stress_pa(), increment.displacement_gradient_increment,
                          bulk_pa_, shear_pa_, &response.stress_pa, &response.reason)) {
    return response;
  }
  if (want_tangent) {
    response.tangent_pa = IsotropicElasticTangent(bulk_pa_, shear_pa_);
    response.has_tangent = true;
  }
  response.state = std::make_unique<StressState>(response.stress_pa);
  response.status = UpdateStatus::kOk;
  return response;
}

}  // namespace gonogo::material
