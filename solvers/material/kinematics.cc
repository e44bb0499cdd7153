#include "solvers/material/kinematics.h"

#include <Eigen/LU>
#include <string>

namespace gonogo::material {

IncrementKinematics HughesWinget(const Matrix3& displacement_gradient_increment) {
  const Matrix3& dH = displacement_gradient_increment;
  const Matrix3 identity = Matrix3::Identity();
  IncrementKinematics kinematics;
  if (!dH.allFinite()) {
    kinematics.failure_reason = "displacement_gradient_increment is not finite";
    return kinematics;
  }
  // J = det(F_{n+1} F_n^-1) = det(I + dH) must stay positive.
  const double jacobian_end = (identity + dH).determinant();
  if (!(jacobian_end > 0.0)) {
    kinematics.failure_reason = "det(I + dH) = " + std::to_string(jacobian_end) +
                                " <= 0: the increment would invert the material; cut the step";
    return kinematics;
  }
  // dx_{n+1/2}/dx_n = I + dH/2; its inverse maps the gradient onto the midpoint configuration.
  const Matrix3 midpoint_map = identity + 0.5 * dH;
  const double jacobian_mid = midpoint_map.determinant();
  if (!(jacobian_mid > kMinMidpointJacobian)) {
    kinematics.failure_reason = "det(I + dH/2) = " + std::to_string(jacobian_mid) +
                                " is not positive: the increment rotates by about 180 degrees or "
                                "more; cut the step";
    return kinematics;
  }
  // G = dH (I + dH/2)^-1 (Hughes & Winget 1980).
  const Matrix3 gradient_mid = dH * midpoint_map.inverse();
  kinematics.strain_increment = 0.5 * (gradient_mid + gradient_mid.transpose());
  const Matrix3 spin = 0.5 * (gradient_mid - gradient_mid.transpose());
  // R = (I - W/2)^-1 (I + W/2): det(I - W/2) = 1 + |w|^2/4 > 0 for any skew W.
  kinematics.rotation = (identity - 0.5 * spin).inverse() * (identity + 0.5 * spin);
  return kinematics;
}

Matrix3 DisplacementGradientForStrain(const Matrix3& strain_increment) {
  return strain_increment * (Matrix3::Identity() - 0.5 * strain_increment).inverse();
}

Vector6 StressToVoigt(const Matrix3& stress) {
  Vector6 voigt;
  voigt << stress(0, 0), stress(1, 1), stress(2, 2), stress(1, 2), stress(0, 2), stress(0, 1);
  return voigt;
}

Matrix3 VoigtToStress(const Vector6& voigt) {
  Matrix3 stress;
  stress << voigt(0), voigt(5), voigt(4),  //
      voigt(5), voigt(1), voigt(3),        //
      voigt(4), voigt(3), voigt(2);
  return stress;
}

Vector6 StrainToVoigt(const Matrix3& strain) {
  Vector6 voigt;
  // gamma_ij = eps_ij + eps_ji: the engineering shear of sym(strain).
  voigt << strain(0, 0), strain(1, 1), strain(2, 2), strain(1, 2) + strain(2, 1),
      strain(0, 2) + strain(2, 0), strain(0, 1) + strain(1, 0);
  return voigt;
}

Matrix3 VoigtToStrain(const Vector6& voigt) {
  Vector6 tensor = voigt;
  tensor.tail<3>() *= 0.5;
  return VoigtToStress(tensor);
}

}  // namespace gonogo::material
