// Kinematics of one increment at a material point, and the Voigt conversions every model shares.
//
// Hughes & Winget (1980), "Finite rotation effects in numerical integration of rate constitutive
// equations arising in large-deformation analysis", Int. J. Numer. Meth. Engng 15:1862-1867:
// a stress rate integrated with
//   G      = d(du)/dx_{n+1/2} = dH (I + dH/2)^-1      (gradient on the midpoint configuration)
//   d_eps  = sym(G),  W = skew(G)
//   R      = (I - W/2)^-1 (I + W/2)                   (Cayley transform of W: exactly orthogonal)
//   sigma_{n+1} = R sigma_n R^T + (constitutive part driven by d_eps)
// is incrementally objective: for a rigid rotation increment, I + dH = Q, G is skew, so d_eps = 0
// and R = Q exactly (the Cayley transform of 2 (Q - I)(Q + I)^-1 is Q), whatever the size of Q.
// Q must not turn by 180 degrees (then I + dH/2 is singular).
#pragma once

#include <Eigen/Core>
#include <string>

#include "solvers/material/constitutive.h"

namespace gonogo::material {

using Vector6 = Eigen::Matrix<double, 6, 1>;

// What a model needs from one increment.
struct IncrementKinematics {
  Matrix3 strain_increment = Matrix3::Zero();  // d_eps = sym(G), symmetric, dimensionless
  Matrix3 rotation = Matrix3::Identity();      // R, proper orthogonal
  std::string failure_reason;                  // empty when the increment is admissible
  bool ok() const { return failure_reason.empty(); }
};

// Smallest det(I + dH/2) accepted: below it the midpoint configuration is (nearly) singular.
inline constexpr double kMinMidpointJacobian = 1e-6;

// The Hughes-Winget split of a displacement-gradient increment dH = d(du)/dx_n (see above).
// Never throws: an increment with a non-finite entry, det(I + dH) <= 0 (the material would be
// inverted) or det(I + dH/2) <= kMinMidpointJacobian comes back with a failure_reason.
IncrementKinematics HughesWinget(const Matrix3& displacement_gradient_increment);

// The displacement-gradient increment whose Hughes-Winget strain increment is the symmetric
// `strain_increment` e, with no rotation: dH = e (I - e/2)^-1 (inverts G = dH (I + dH/2)^-1 for
// commuting symmetric matrices). For drivers and tests that prescribe strain.
Matrix3 DisplacementGradientForStrain(const Matrix3& strain_increment);

// Voigt order xx yy zz yz xz xy.
Vector6 StressToVoigt(const Matrix3& stress);  // tensor components
Matrix3 VoigtToStress(const Vector6& voigt);
Vector6 StrainToVoigt(const Matrix3& strain);  // of sym(strain), engineering shears gamma = 2 eps
Matrix3 VoigtToStrain(const Vector6& voigt);   // halves the shears back

}  // namespace gonogo::material
