// Perfectly plastic Drucker-Prager with non-associated flow behind the constitutive seam.
// de Souza Neto, Peric & Owen, "Computational Methods for Plasticity", Wiley 2008 (dSN below),
// whose stresses are tension positive like this seam's:
//   yield function   F   = sqrt(J2(s)) + eta p - xi c                           (dSN eq. 6.118)
//   flow potential   Psi = sqrt(J2(s)) + eta_bar p,  d_eps_p = d_gamma dPsi/dsigma
//   p = tr(sigma) / 3,  s = sigma - p 1,  J2 = s : s / 2
// The coefficients match Mohr-Coulomb (c, phi; psi for eta_bar), see DruckerPragerParams::Match.
// Integration: Hughes-Winget rotation of the committed stress (kinematics.h), elastic predictor,
// return to the smooth cone or to the apex (dSN sec. 8.3.2, Box 8.9, without hardening) and the
// consistent tangent (dSN Box 8.10). No tension cutoff: the apex is the only limit in tension.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"

namespace gonogo::material {

struct DruckerPragerParams {
  // How the cone is fitted to the Mohr-Coulomb surface of (c, phi).
  enum class Match {
    kTriaxialCompression,  // outer cone: equal in triaxial compression (dSN eq. 6.119)
    kPlaneStrain,          // equal limit loads in plane strain (dSN eq. 6.121)
  };

  double young_pa = 0;            // Young's modulus E, > 0
  double poisson = 0;             // Poisson's ratio nu, in (-1, 0.5)
  double cohesion_pa = 0;         // Mohr-Coulomb cohesion c, >= 0
  double friction_angle_deg = 0;  // Mohr-Coulomb friction angle phi, in [0, 90)
  double dilation_angle_deg = 0;  // dilation angle psi, in [0, phi]; psi = phi is associated
  Match match = Match::kTriaxialCompression;

  // Throws gonogo::InputError naming field_prefix + the offending field. c = 0 and phi = 0
  // together are refused (no strength).
  void Validate(const std::string& field_prefix) const;
};

// State: the Cauchy stress and, for output, the accumulated equivalent plastic strain
// eps_p_eq = sum sqrt(2/3 de_p : de_p) (de_p the deviatoric plastic strain increment).
// Serialize(): 7 doubles, the stress in Voigt order xx yy zz yz xz xy, then eps_p_eq.
class DruckerPragerState : public MaterialState {
 public:
  DruckerPragerState(const Matrix3& stress_pa, double equivalent_plastic_strain)
      : stress_pa_(stress_pa), equivalent_plastic_strain_(equivalent_plastic_strain) {}
  std::unique_ptr<MaterialState> Clone() const override;
  std::string Serialize() const override;
  const Matrix3& stress_pa() const { return stress_pa_; }
  double equivalent_plastic_strain() const { return equivalent_plastic_strain_; }

 private:
  Matrix3 stress_pa_;
  double equivalent_plastic_strain_;
};

class DruckerPrager : public ConstitutiveModel {
 public:
  // Throws gonogo::InputError ("material.friction_angle_deg", ...) for invalid parameters.
  explicit DruckerPrager(const DruckerPragerParams& params);

  std::string Name() const override { return "drucker-prager"; }
  // Zero stress, no plastic strain.
  std::unique_ptr<MaterialState> InitialState() const override;
  // Throws gonogo::InputError("material.state", ...) for bytes that are not 7 finite doubles or
  // carry a negative plastic strain.
  std::unique_ptr<MaterialState> RestoreState(const std::string& bytes) const override;
  // Tangent: C when elastic, dSN Box 8.10 on the cone (not symmetric unless psi = phi), zero at the
  // apex. Fails (kFailed, no state) only for an inadmissible increment (kinematics.h) or a missing
  // committed state.
  std::vector<PointResponse> Update(const std::vector<PointIncrement>& increments,
                                    bool want_tangent) const override;

  const DruckerPragerParams& params() const { return params_; }
  double eta() const { return eta_; }          // friction coefficient of F
  double xi() const { return xi_; }            // cohesion coefficient of F
  double eta_bar() const { return eta_bar_; }  // dilatancy coefficient of Psi
  // F(sigma) = sqrt(J2) + eta p - xi c, in Pa (dSN eq. 6.118).
  double YieldFunctionPa(const Matrix3& stress_pa) const;

 private:
  struct Returned {
    Matrix3 stress_pa = Matrix3::Zero();
    double equivalent_plastic_strain_increment = 0;
    Voigt6x6 tangent_pa = Voigt6x6::Zero();  // set only when asked for
  };
  PointResponse UpdateOne(const PointIncrement& increment, bool want_tangent) const;
  Returned ReturnMap(const Matrix3& trial_stress_pa, bool want_tangent) const;

  DruckerPragerParams params_;
  double bulk_pa_;
  double shear_pa_;
  double eta_;
  double xi_;
  double eta_bar_;
};

}  // namespace gonogo::material
