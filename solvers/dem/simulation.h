// Time integration of a sphere packing: velocity Verlet, linked-cell neighbours with a Verlet skin,
// periodic or wall-bounded orthogonal box that a periodic packing may deform (general homogeneous
// deformation of the cell), gravity, OpenMP force loop with a fixed summation order.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "solvers/dem/contact_model.h"
#include "solvers/dem/neighbor_list.h"
#include "solvers/dem/particles.h"

namespace gonogo::dem {

// Static plane: grains stay on the side `normal` points to; contact is sphere-plane Hertz.
struct Wall {
  Vec3 point_m = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();  // unit, into the domain
};

struct SimulationParams {
  MaterialParams material;
  Box box;
  std::vector<Wall> walls;
  Vec3 gravity_m_s2 = Vec3::Zero();
  double time_step_s = 0.0;       // 0: time_step_safety x Rayleigh step of the smallest grain
  double time_step_safety = 0.2;  // fraction of the Rayleigh step, (0, 1]
  double skin_fraction = 0.2;     // Verlet skin / largest radius, > 0
  int threads = 1;                // OpenMP threads for the force loop, >= 1
  // On a cell periodic on every axis, each neighbour-list rebuild replaces an edge tilted past
  // half of another by the equivalent lattice vector e_b - k e_a (k the nearest integer to
  // e_b . e_a / |e_a|^2): the same periodic system in a less sheared cell, so simple shear can
  // go on past the strain where the faces would come closer than the neighbour search allows.
  bool reduce_sheared_cell = true;

  void Validate() const;
};

// Rayleigh critical step dt_R = pi r sqrt(rho / G) / (0.1631 nu + 0.8766) (Li, Xu & Thornton 2005,
// Powder Technol. 160, 219; the Rayleigh wave speed approximation of Johnson 1985).
double RayleighTimeStepS(double radius_m, const MaterialParams& material);

class Simulation {
 public:
  // The seed 000 contact law (ContactModel::HertzMindlin) built from params.material.
  Simulation(const SimulationParams& params, Particles particles);
  Simulation(const SimulationParams& params, Particles particles, ContactModel model);

  // One velocity-Verlet step: v += dt/2 a; x += dt v; forces; v += dt/2 a (and omega alike).
  void Step();
  void Run(int steps);

  // Deforms the cell at a constant velocity gradient L (1/s) from the next step on: each step maps
  // the cell edges and the grains by A = I + dt L, seed 000's X_{n+1} = X_n + dX_n spread over
  // steps. The background field also spins the grains with the rotation R of A (polar split
  // A = R U) and turns every contact's stored springs by R, so contact velocities carry only the
  // affine part that is not rigid: (L - (R - I) / dt) (x_i - x_j); a rigid rotation of the cell
  // slides no contact. Velocities and angular velocities in particles() are relative to that
  // background (affine translation, spin). A symmetric L has R = I: the pure-stretch path is the
  // plain affine remap. Needs every axis periodic and no walls (solvers/dem/rve/README.md).
  void SetVelocityGradient(const Eigen::Matrix3d& velocity_gradient_1_s);
  const Eigen::Matrix3d& velocity_gradient_1_s() const { return velocity_gradient_1_s_; }
  // R of the polar split of I + dt L: the background spin of one step (I unless L is skew-free).
  const Eigen::Matrix3d& step_rotation() const { return step_rotation_; }
  const Cell& cell() const { return cell_; }

  // Contact virial W = sum over contacts of (x_i - x_j) (x) f_i (N m), from the last force
  // evaluation (f_i the force on i, x_j the image in contact). A packing in equilibrium carries
  // the Cauchy stress sigma = -W / V (tension positive; seed 000's (1/V) sum d (x) f with d from
  // i to j).
  Eigen::Matrix3d ContactVirialNM() const;
  // sum over contacts of k_n n (x) d (x) n (x) d + k_t (I - n n) (x) d (x) d (seed 000's
  // tangent, both tangent directions; k_t = 0 while sliding), as the 6 x 6 matrix of
  // dsigma/deps in Voigt order xx yy zz yz xz xy with engineering shears, times V (N m).
  Eigen::Matrix<double, 6, 6> ContactStiffnessVoigtNM() const;
  // The contacts' fabric tensor (1/N_c) sum over contacts of n (x) n, n the unit branch vector
  // (Satake 1982): trace 1, I/3 for contact normals spread evenly over directions; its deviatoric
  // part is the packing's anisotropy, which the stress alone does not tell. Zero when there are
  // no contacts.
  Eigen::Matrix3d ContactFabric() const;

  // The whole state (grains, cell, contacts and their history, neighbour list inputs) as bytes.
  // RestoreState on a Simulation built with the same parameters continues bit-identically.
  std::string SaveState() const;
  void RestoreState(const std::string& bytes);

  const Particles& particles() const { return particles_; }
  double time_step_s() const { return time_step_s_; }
  double time_s() const { return time_s_; }
  int rebuild_count() const { return rebuild_count_; }
  // Times the cell edges were replaced by an equivalent, less sheared set (reduce_sheared_cell).
  int cell_reduction_count() const { return cell_reduction_count_; }
  int ContactCount() const;
  // Contacts whose tangential force is at the Coulomb limit at the last force evaluation.
  int SlidingContactCount() const;
  // Mean |net force| over grains / mean |contact force| over contacts (0 when there are none):
  // the usual quasi-static equilibrium measure (e.g. Ng 2006; 1e-3 or below is static).
  double UnbalancedForceRatio() const;

  double KineticEnergyJ() const;        // translational + rotational
  double ElasticNormalEnergyJ() const;  // sum of U(d_n) over contacts and walls
  Vec3 LinearMomentumKgMS() const;
  // About the origin, from unwrapped positions: sum m x (x) v + I omega.
  Vec3 AngularMomentumKgM2S() const;
  // Position plus the cell edges crossed (continuous across periodic wraps).
  Vec3 UnwrappedPositionM(int p) const;

 private:
  void Rebuild();
  // Fills the per-pair constants (r_e, m*) for the current neighbour list.
  void ComputePairConstants();
  // The lattice reduction of reduce_sheared_cell: new edges = edges M, M integer with det 1.
  // Returns M (the identity when nothing changed).
  Eigen::Matrix3i ReduceCellEdges();
  void ComputeForces();
  // Evaluates pair k into its slots; false (slots cleared) when the pair is open.
  bool EvaluatePair(int k);
  void ComputePairForces();
  void ComputeAndSumForcesOneThread();
  void SumParticleForces();
  Vec3 WallForce(int p, int w, Vec3& torque_n_m);
  void HalfKick();
  // Turns every contact's tangential and rolling history by step_rotation_ (the background spin).
  void RotateContactHistories();

  SimulationParams params_;
  Particles particles_;
  ContactModel model_;
  Cell cell_;
  Eigen::Matrix3d velocity_gradient_1_s_ = Eigen::Matrix3d::Zero();
  bool deforming_ = false;
  // The background spin (SetVelocityGradient): R of I + dt L, whether R != I, and the gradient
  // that enters contact velocities, L - (R - I) / dt (= L when R = I).
  Eigen::Matrix3d step_rotation_ = Eigen::Matrix3d::Identity();
  bool spinning_ = false;
  Eigen::Matrix3d contact_velocity_gradient_1_s_ = Eigen::Matrix3d::Zero();
  NeighborList neighbors_;
  double time_step_s_ = 0.0;
  double time_s_ = 0.0;
  int rebuild_count_ = 0;
  int cell_reduction_count_ = 0;
  bool forces_valid_ = false;
  // Per-pair state, aligned with neighbors_.pairs().
  std::vector<double> pair_effective_radius_m_;  // r_i r_j / (r_i + r_j), fixed per list
  std::vector<double> pair_effective_mass_kg_;   // m_i m_j / (m_i + m_j), fixed per list
  std::vector<ContactHistory> pair_history_;
  std::vector<double> pair_overlap_m_;
  std::vector<Vec3> pair_force_on_i_n_;
  std::vector<Vec3> pair_torque_i_n_m_;
  std::vector<Vec3> pair_torque_j_n_m_;
  std::vector<double> pair_normal_stiffness_n_m_;
  std::vector<double> pair_tangential_stiffness_n_m_;  // 0 while sliding
  std::vector<ContactHistory> wall_history_;  // (N x walls)
};

}  // namespace gonogo::dem
