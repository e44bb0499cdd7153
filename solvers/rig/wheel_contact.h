// A rigid wheel in penalty contact with Coulomb friction against the surface nodes of an FE soil
// (the wheel contact of the FE soil bin, fe_soil_bin.h).
//
// The wheel is a cylinder of radius R and width b with its axle along y. A surface node at x inside
// the cylinder (distance d < R from the axle in the x-z plane, |y - y_c| <= b/2) is pushed out
// along n = (x - c)_xz / d with
//   F_n = k_n (R - d) - c_n (v_rel . n)       (never pulling; c_n damps the node-wheel chatter)
// and carries a tangential force from an elastic-slip history xi (the stick-slip spring of
// Cundall & Strack 1979, the same scheme as the DE engine's tangential contact):
//   xi += v_rel,t dt,   F_t = -k_t xi,   |F_t| <= mu F_n + c_a A_node   (Coulomb with adhesion)
// where v_rel = v_node - (V + omega e_y x (x - c)) is the node's velocity relative to the wheel rim.
// With omega > 0 about +y the wheel rolls towards +x. The wheel receives minus the sum.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "solvers/fe/explicit_solver.h"
#include "solvers/rig/soil_bin.h"

namespace gonogo::rig {

// WheelMotion and WheelLoad: soil_bin.h.
struct WheelContactParams {
  double radius_m = 0;
  double width_m = 0;
  double friction_coefficient = 0;   // mu, -
  double adhesion_pa = 0;            // c_a, Pa
  double normal_stiffness_n_m = 0;   // k_n per node
  double tangential_stiffness_n_m = 0;  // k_t per node
  double normal_damping_ratio = 0.2;    // c_n = 2 zeta sqrt(k_n m_node)

  void Validate(const std::string& field_prefix) const;
};

class WheelContact {
 public:
  // `surface_nodes` are the candidate nodes, `node_areas_m2` their tributary areas (for the
  // adhesion); both index the solver's mesh.
  WheelContact(const WheelContactParams& params, std::vector<int> surface_nodes,
               std::vector<double> node_areas_m2);

  // Adds the contact forces to solver.external_forces_n() (which the caller zeroed for these
  // nodes) and returns their reaction on the wheel. `dt_s` advances the slip histories.
  WheelLoad Apply(const WheelMotion& wheel, fe::ExplicitSolver& solver, double dt_s);

  const WheelContactParams& params() const { return params_; }
  const std::vector<int>& surface_nodes() const { return surface_nodes_; }
  // The slip histories, for checkpoints; restoring a count that does not match throws
  // InputError.
  const std::vector<Vec3>& slip_history_m() const { return slip_history_m_; }
  void RestoreSlipHistory(std::vector<Vec3> slip_history_m);

 private:
  WheelContactParams params_;
  std::vector<int> surface_nodes_;
  std::vector<double> node_areas_m2_;
  std::vector<Vec3> slip_history_m_;  // xi per surface node, zero when out of contact
};

// Tributary area of every node of the top surface z = 0 of a structured mesh (half the spacing to
// each neighbour in x and y), indexed like the returned node list.
void TopSurfaceNodes(const fe::HexMesh& mesh, std::vector<int>* nodes,
                     std::vector<double>* areas_m2);

}  // namespace gonogo::rig
