// The periodic representative volume element of seed 000's FE-DE model: about 500 polydisperse
// spheres in a fully periodic cell that deforms homogeneously (the cell edges follow
// X_{n+1} = X_n + dX_n, grains are remapped affinely and relax), with the homogenised Cauchy
// stress and the contact tangent of seed 000 (after Guo & Zhao 2014, IJNME 99, 789).
//
// Sign conventions: stresses and strains here are tension positive (continuum mechanics); the
// driver's CSV reports compression positive, as soil mechanics does.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <string>

#include "solvers/dem/simulation.h"

namespace gonogo::dem::rve {

using Matrix3 = Eigen::Matrix3d;
using Voigt6x6 = Eigen::Matrix<double, 6, 6>;

struct RveParams {
  // Grain contact law; defaults are seed 000's (rve_hertz_mindlin.csv) with restitution 0.5,
  // which seed 000 does not give (any value in (0, 1) only sets how fast the packing settles).
  MaterialParams material = SeedMaterial();
  int grain_count = 500;
  double mean_radius_m = 0.87e-3;  // seed 000
  double radius_spread = 0.2;      // radii uniform in r_mean (1 +- spread), [0, 0.5]
  unsigned seed = 1;               // random placement
  double initial_solid_fraction = 0.25;  // of the random gas before consolidation, (0, 0.4]
  // Isotropic consolidation target (mean stress, compression positive).
  double consolidation_pressure_pa = 100e3;
  // Inter-particle friction during consolidation; 0 gives the densest packing, the material's
  // friction a looser one. The material's own friction is restored for loading.
  double consolidation_friction = 0.0;
  double time_step_safety = 0.3;  // fraction of the Rayleigh step of the smallest grain
  // Loading rate bound from the inertial number I = rate d sqrt(rho / p) (GDR MiDi 2004): rates
  // are capped so that I <= max_inertial_number at the current mean stress (quasi-static).
  double max_inertial_number = 1e-3;
  int threads = 1;

  static MaterialParams SeedMaterial();
  void Validate() const;
};

// Which components a loading step prescribes: a strain rate for some, a stress (held by a servo)
// for the others. Components are of the velocity gradient / Cauchy stress, tension positive; a
// stress-controlled shear component is held through the symmetric part.
struct MixedControl {
  Matrix3 strain_rate_1_s = Matrix3::Zero();
  std::array<std::array<bool, 3>, 3> stress_controlled = {};
  Matrix3 target_stress_pa = Matrix3::Zero();
};

struct RveSnapshot {
  double time_s = 0.0;
  // Accumulated since consolidation: sum of sym(L) dt over servo steps (Run) plus
  // sym(log(I + dH)) per increment (ApplyIncrement; zero for a rigid rotation).
  Matrix3 strain = Matrix3::Zero();
  Matrix3 stress_pa = Matrix3::Zero();  // homogenised Cauchy, symmetric part
  double volume_m3 = 0.0;
  double solid_fraction = 0.0;
  double coordination_number = 0.0;  // 2 contacts / grains
  Matrix3 fabric = Matrix3::Zero();  // Simulation::ContactFabric: trace 1, I/3 when isotropic
  double unbalanced_force_ratio = 0.0;
};

class Rve {
 public:
  // Random gas of params.grain_count grains, isotropically consolidated to the target mean
  // stress until the unbalanced-force ratio is below 1e-3 and the mean stress within 1 %.
  // Throws LimitError if that is not reached within the step budget. `progress` (may be empty)
  // gets the fraction done, about every 1000 steps.
  static Rve Generate(const RveParams& params,
                      const std::function<void(double)>& progress = nullptr);

  // Runs `steps` steps under mixed control.
  void Run(const MixedControl& control, int steps);
  // Brings the packing, with its own friction, to the isotropic stress mean_stress_pa
  // (compression positive) under the servo, settled as Generate settles (mean within 1 %, each
  // component within 3 %, unbalanced-force ratio below 5e-3): unloading a consolidated packing to
  // the stress of its depth keeps the density its preparation gave. The strain is not reset.
  // Throws InputError for a non-positive pressure, LimitError when it does not settle within
  // the step budget.
  void SettleIsotropic(double mean_stress_pa);
  // Applies a displacement-gradient increment dH to the cell over n steps, enough to respect the
  // inertial-number cap on its stretch (IncrementStrain) and at least min_steps, then
  // `relax_steps` with the cell fixed. Each step maps the cell by A = (I + dH)^(1/n), so the cell
  // ends at exactly (I + dH) H_0; the rotation part spins the grains and their contacts with it
  // (Simulation::SetVelocityGradient), so a rigid rotation Q gives Q sigma Q^T. Throws
  // InputError if dH is not finite or I + dH has no real logarithm (IncrementProblem).
  void ApplyIncrement(const Matrix3& displacement_gradient_increment, int min_steps,
                      int relax_steps);
  // Why ApplyIncrement cannot take dH (empty if it can): not finite, or I + dH has a real
  // eigenvalue <= 0 (det <= 0: the cell would be inverted or flattened; or a half turn).
  static std::string IncrementProblem(const Matrix3& displacement_gradient_increment);
  // The stretch of an increment, rotation-free: the largest |component| of U - I with
  // I + dH = R U (polar split; Biot strain). For a symmetric dH that is |dH|_max itself.
  // Needs IncrementProblem(dH) empty.
  static double IncrementStrain(const Matrix3& displacement_gradient_increment);

  // Homogenised Cauchy stress, symmetric part (Pa): sigma = -(1/V) sum_c d^c (x) f^c with d^c
  // from the grain to its neighbour (seed 000), at the last step.
  Matrix3 StressPa() const;
  // Contact tangent (1/V) sum_c (k_n n d n d + k_t (I - n n) d d) (seed 000), Voigt, Pa.
  Voigt6x6 TangentPa() const;
  RveSnapshot Snapshot() const;
  double StableRate1S() const;  // the inertial-number cap on strain rate at the current stress
  double time_step_s() const { return simulation_->time_step_s(); }
  const Simulation& simulation() const { return *simulation_; }
  const RveParams& params() const { return params_; }

  // Everything needed to continue bit-identically on another rank: parameters, strain, grains,
  // cell, contacts with their history. `threads` > 0 replaces the saved thread count (results do
  // not depend on it).
  std::string Save() const;
  static Rve Restore(const std::string& bytes, int threads = 0);

  Rve(const Rve& other);
  Rve& operator=(const Rve& other);
  Rve(Rve&&) noexcept = default;
  Rve& operator=(Rve&&) noexcept = default;

 private:
  Rve(const RveParams& params, std::unique_ptr<Simulation> simulation);
  void ServoStep(const MixedControl& control);
  // The isotropic servo of Generate and SettleIsotropic; false when the budget ran out.
  bool ServoToIsotropic(double target_pa, const std::function<void(double)>& progress);
  double StableRateAt1S(const Matrix3& stress_pa) const;  // StableRate1S for a known stress

  RveParams params_;
  std::unique_ptr<Simulation> simulation_;
  Matrix3 strain_ = Matrix3::Zero();
  Voigt6x6 servo_stiffness_pa_ = Voigt6x6::Zero();
  int steps_since_stiffness_ = 1 << 30;
};

}  // namespace gonogo::dem::rve
