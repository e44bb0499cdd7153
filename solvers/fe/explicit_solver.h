// Explicit total-Lagrangian finite elements for soil (the upper scale of seed 000's multiscale
// model).
//
// Kinematics and forces as seed 000 writes them, at one integration point per 8-node hexahedron:
//   Green-Lagrange strain     E = (F^T F - I) / 2,      F = sum_a x_a (x) dN_a/dX
//   second Piola-Kirchhoff    S = J F^-1 sigma F^-T     (sigma: Cauchy stress from the material)
//   internal forces           Q_s = int (dE/de)^T S dV_0, which for node a is  V_0 F S dN_a/dX
//   equations of motion       M e'' = Q_s + Q_e         (here with Q_s entering as -f_int)
// with a lumped (row-sum) mass, central differences in time (Belytschko, Liu & Moran 2000, Box
// 6.1), Flanagan-Belytschko hourglass control (incremental stiffness returned with the element,
// and viscous), gravity, prescribed velocities per degree
// of freedom (fixed and roller boundaries), and optional mass-proportional damping for the
// quasi-static phases.
//
// The material never sees F: every step, each element hands the constitutive seam its
// displacement-gradient increment dH = F_{n+1} F_n^-1 - I on the configuration at the start of the
// step, in one batch for the whole mesh, so a return map, a DE RVE or a network answers without
// the solver knowing which. The solver holds only a handle per element into the model's point
// store (solvers/material/point_store.h): it tries the batch, commits it when every element
// answered and the step goes on, and discards it otherwise, so the states may live elsewhere.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "solvers/common/units.h"
#include "solvers/fe/hex8.h"
#include "solvers/fe/mesh.h"
#include "solvers/material/constitutive.h"
#include "solvers/material/point_store.h"

namespace gonogo::fe {

struct ExplicitOptions {
  double density_kg_m3 = 0;                  // reference density rho_0
  Vec3 gravity_m_s2 = Vec3(0, 0, -units::kStandardGravityMps2);
  double hourglass_coefficient = 0.05;       // epsilon_hg of the stiffness form, 0 to 0.15
  double hourglass_viscosity = 0.1;          // Q_hg of the viscous form, 0 to 0.15
  double time_step_safety = 0.5;             // fraction of the critical step StableTimeStep uses
  double mass_damping_per_s = 0;             // alpha of C = alpha M
  // Mass scaling for quasi-static runs: inertia (the lumped masses, hence the stable step, which
  // grows as sqrt(mass_scaling)) uses mass_scaling x density_kg_m3; weight uses density_kg_m3.
  // 1: none. A quasi-static answer must not depend on it (check the kinetic energy).
  double mass_scaling = 1;
  int threads = 1;                           // OpenMP threads of the element and node loops

  void Validate(const std::string& field_prefix) const;
};

// The outcome of one step. On failure nothing was changed: positions, velocities and material
// states are those of the start of the step.
struct StepStatus {
  bool ok = true;
  std::string reason;
};

// The fraction of its elastic-trial deviatoric stress an element keeps over one step,
// ||dev sigma_{n+1}|| / ||dev sigma_n + 2 G dev(sym dH)||, in [0, 1]; 1 for an elastic step.
// The incremental hourglass stresses are scaled by it, Q_{n+1} = r (Q_n + kappa dq): they are
// elastic while the element is and are returned with its stress when it flows, so hourglass
// control does not stiffen plastic flow. For Drucker-Prager's return to the cone r is exactly the
// radial-return factor 1 - G dgamma / ||s_trial|| (de Souza Neto et al. 2008, eq. 8.89 form).
double RetainedDeviatoricFraction(const Eigen::Matrix3d& stress_n_pa,
                                  const Eigen::Matrix3d& stress_next_pa,
                                  const Eigen::Matrix3d& displacement_gradient_increment,
                                  double shear_modulus_pa);

class ExplicitSolver {
 public:
  // Throws InputError for bad options or a degenerate mesh.
  ExplicitSolver(HexMesh mesh, std::shared_ptr<const material::ConstitutiveModel> model,
                 const ExplicitOptions& options);

  // --- boundary conditions and loads -----------------------------------------------------------
  // Prescribes the velocity of one degree of freedom (dof 0, 1, 2 = x, y, z); 0 fixes it.
  void PrescribeVelocity(int node, int dof, double velocity_m_s = 0);
  void Release(int node, int dof);
  // Forces the caller applies (contact, footing loads); they stay until changed. Gravity is added
  // by the solver.
  std::vector<Vec3>& external_forces_n() { return external_forces_n_; }
  void set_mass_damping_per_s(double alpha) { options_.mass_damping_per_s = alpha; }
  // Sets ExplicitOptions::mass_scaling after construction, before the first step (the bins pick
  // it from the stable step they measure): masses x factor / old factor, stable step and viscous
  // hourglass coefficients x sqrt of that. Throws InputError for a factor < 1, std::logic_error
  // once stepping has begun.
  void SetMassScaling(double mass_scaling);
  // Replaces the committed material state of an element's point before the first step (an
  // initial stress field: geostatic RVEs, a prestressed layer), as MaterialState bytes of the
  // model. Throws InputError for bytes the model cannot read, std::logic_error once stepping has
  // begun.
  void SetInitialPointState(int element, const std::string& state_bytes);

  // --- time stepping ---------------------------------------------------------------------------
  // time_step_safety x min over elements of L_e / c_d, c_d = sqrt((K + 4G/3) / rho_0) from the
  // material's initial elastic moduli (with the hourglass stiffness added), in s.
  double StableTimeStep() const { return stable_time_step_s_; }
  // One central-difference step of size dt_s.
  StepStatus Step(double dt_s);

  // --- state -----------------------------------------------------------------------------------
  const HexMesh& mesh() const { return mesh_; }
  double time_s() const { return time_s_; }
  const std::vector<Vec3>& positions_m() const { return positions_m_; }     // x_n
  const std::vector<Vec3>& velocities_m_s() const { return velocities_m_s_; }  // v_{n-1/2}
  // f_int(x_n) of the last step, including hourglass forces; a prescribed node's reaction is
  // f_int - f_ext - m g (quasi-statically).
  const std::vector<Vec3>& internal_forces_n() const { return internal_forces_n_; }
  // Inertial masses, mass_scaling x the physical ones (ExplicitOptions::mass_scaling).
  const std::vector<double>& nodal_masses_kg() const { return nodal_masses_kg_; }
  double mass_scaling() const { return options_.mass_scaling; }
  // Cauchy stress of each element after the last step, Pa, tension positive.
  const std::vector<Eigen::Matrix3d>& element_stress_pa() const { return stress_pa_; }
  // The committed material points, one per element (handle element_point(e)).
  const material::MaterialPointStore& material_points() const { return *material_points_; }
  material::PointHandle element_point(int element) const { return element_points_[element]; }
  Eigen::Matrix3d element_deformation_gradient(int element) const { return previous_f_[element]; }
  const Hex8Reference& element_reference(int element) const { return references_[element]; }
  double KineticEnergyJ() const;

  // --- checkpoints ---------------------------------------------------------------------------
  // The solver's own state: time, node positions, velocities and internal forces, each element's
  // last F, stress and hourglass history, and the mass damping. Not the material points (their
  // store checkpoints them, material_points()) nor the mesh, boundary conditions or options,
  // which the caller rebuilds the same way. RestoreState on a solver built the same way continues
  // bit for bit; it throws InputError for bytes of another mesh or a damaged buffer, and then
  // changes nothing.
  std::string SaveState() const;
  void RestoreState(const std::string& bytes);
  material::MaterialPointStore& mutable_material_points() { return *material_points_; }
  int threads() const { return options_.threads; }

 private:
  StepStatus ComputeInternalForces();

  HexMesh mesh_;
  std::shared_ptr<const material::ConstitutiveModel> model_;
  ExplicitOptions options_;
  material::ElasticModuli moduli_;
  double stable_time_step_s_ = 0;
  double time_s_ = 0;

  // Per element (elements x ...).
  std::vector<Hex8Reference> references_;
  std::vector<double> hourglass_stiffness_n_m_;
  std::vector<double> hourglass_viscosity_n_s_m_;
  // Hourglass generalised stresses Q_alpha (4 x 3, N) and modes q_alpha (4 x 3, m) of the last
  // committed step, for the incremental form.
  std::vector<Eigen::Matrix<double, 4, 3>> hourglass_forces_n_;
  std::vector<Eigen::Matrix<double, 4, 3>> hourglass_modes_m_;
  std::vector<Eigen::Matrix3d> previous_f_;          // F at the last committed step
  // Declared after model_, so it is destroyed first (a local store refers to the model).
  std::unique_ptr<material::MaterialPointStore> material_points_;
  std::vector<material::PointHandle> element_points_;  // (elements) handle of each element's point
  std::vector<Eigen::Matrix3d> stress_pa_;
  std::vector<Mat83> element_forces_n_;               // (8 x 3) scratch of the element loop
  std::vector<Eigen::Matrix3d> trial_f_;              // scratch: F at x_n
  std::vector<Eigen::Matrix3d> increments_;           // scratch: dH of each element, one batch

  // Node -> (element * 8 + local node) in a compressed row layout, for a deterministic gather.
  std::vector<int> node_element_offsets_;
  std::vector<int> node_element_slots_;

  // Per node (nodes x ...).
  std::vector<Vec3> positions_m_, velocities_m_s_, internal_forces_n_, external_forces_n_;
  std::vector<double> nodal_masses_kg_;
  std::vector<Eigen::Matrix<bool, 3, 1>> prescribed_;
  std::vector<Vec3> prescribed_velocity_m_s_;
};

}  // namespace gonogo::fe
