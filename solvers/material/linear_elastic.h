// Isotropic linear elasticity behind the constitutive seam, hypoelastic with the Hughes-Winget
// objective update (kinematics.h):
//   sigma_{n+1} = R sigma_n R^T + C : d_eps,   C = K 1 (x) 1 + 2 G (I_s - 1 (x) 1 / 3),
//   K = E / (3 (1 - 2 nu)),  G = E / (2 (1 + nu)).
// Also the isotropic C that the plastic models share.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"

namespace gonogo::material {

struct LinearElasticParams {
  double young_pa = 0;  // Young's modulus E, > 0
  double poisson = 0;   // Poisson's ratio nu, in (-1, 0.5)

  // Throws gonogo::InputError naming field_prefix + the offending field ("material.young_pa").
  void Validate(const std::string& field_prefix) const;
  double bulk_pa() const { return young_pa / (3.0 * (1.0 - 2.0 * poisson)); }
  double shear_pa() const { return young_pa / (2.0 * (1.0 + poisson)); }
};

// sigma = K tr(eps) 1 + 2 G dev(eps) for a symmetric strain (increment) eps.
Matrix3 IsotropicElasticStress(double bulk_pa, double shear_pa, const Matrix3& strain);
// The same map as a 6 x 6 Voigt matrix (engineering shear strains).
Voigt6x6 IsotropicElasticTangent(double bulk_pa, double shear_pa);

// The hypoelastic predictor both classical models start from: R sigma_n R^T + C : d_eps with R
// and d_eps of the Hughes-Winget kinematics of `displacement_gradient_increment` (symmetrised
// against round-off). Returns false, with `reason` set, for an inadmissible increment.
bool ElasticTrialStress(const Matrix3& committed_stress_pa,
                        const Matrix3& displacement_gradient_increment, double bulk_pa,
                        double shear_pa, Matrix3* trial_stress_pa, std::string* reason);

// A state that is the Cauchy stress alone. Serialize(): 6 doubles, Voigt order xx yy zz yz xz xy.
class StressState : public MaterialState {
 public:
  explicit StressState(const Matrix3& stress_pa) : stress_pa_(stress_pa) {}
  std::unique_ptr<MaterialState> Clone() const override;
  std::string Serialize() const override;
  const Matrix3& stress_pa() const { return stress_pa_; }

 private:
  Matrix3 stress_pa_;
};

class LinearElastic : public ConstitutiveModel {
 public:
  // Throws gonogo::InputError ("material.young_pa", ...) for invalid parameters.
  explicit LinearElastic(const LinearElasticParams& params);

  std::string Name() const override { return "linear-elastic"; }
  // Zero stress.
  std::unique_ptr<MaterialState> InitialState() const override;
  // Throws gonogo::InputError("material.state", ...) for bytes that are not 6 finite doubles.
  std::unique_ptr<MaterialState> RestoreState(const std::string& bytes) const override;
  // Tangent: C.
  std::vector<PointResponse> Update(const std::vector<PointIncrement>& increments,
                                    bool want_tangent) const override;

  const LinearElasticParams& params() const { return params_; }

 private:
  PointResponse UpdateOne(const PointIncrement& increment, bool want_tangent) const;

  LinearElasticParams params_;
  double bulk_pa_;
  double shear_pa_;
};

}  // namespace gonogo::material
