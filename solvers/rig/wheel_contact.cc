#include "solvers/rig/wheel_contact.h"

#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::rig {

void WheelContactParams::Validate(const std::string& p) const {
  Require(radius_m > 0 && std::isfinite(radius_m), p + "radius_m", "must be positive");
  Require(width_m > 0 && std::isfinite(width_m), p + "width_m", "must be positive");
  Require(friction_coefficient >= 0, p + "friction_coefficient", "must not be negative");
  Require(adhesion_pa >= 0, p + "adhesion_pa", "must not be negative");
  Require(normal_stiffness_n_m > 0, p + "normal_stiffness_n_m", "must be positive");
  Require(tangential_stiffness_n_m > 0, p + "tangential_stiffness_n_m", "must be positive");
  Require(normal_damping_ratio >= 0 && normal_damping_ratio <= 1, p + "normal_damping_ratio",
          "must lie in [0, 1]");
}

WheelContact::WheelContact(const WheelContactParams& params, std::vector<int> surface_nodes,
                           std::vector<double> node_areas_m2)
    : params_(params),
      surface_nodes_(std::move(surface_nodes)),
      node_areas_m2_(std::move(node_areas_m2)),
      slip_history_m_(surface_nodes_.size(), Vec3::Zero()) {
  params_.Validate("wheel.");
  Require(surface_nodes_.size() == node_areas_m2_.size(), "wheel.surface_nodes",
          "needs one tributary area per node");
}

void WheelContact::RestoreSlipHistory(std::vector<Vec3> slip_history_m) {
  Require(slip_history_m.size() == surface_nodes_.size(), "state",
          "slip histories saved for another surface");
  slip_history_m_ = std::move(slip_history_m);
}

WheelLoad WheelContact::Apply(const WheelMotion& wheel, fe::ExplicitSolver& solver, double dt_s) {
  const auto& x = solver.positions_m();
  const auto& v = solver.velocities_m_s();
  const auto& m = solver.nodal_masses_kg();
  auto& f_ext = solver.external_forces_n();
  const double radius = params_.radius_m;
  const Vec3 spin(0, wheel.angular_velocity_rad_s, 0);
  WheelLoad load;
  for (size_t k = 0; k < surface_nodes_.size(); ++k) {
    const int node = surface_nodes_[k];
    Vec3 arm = x[node] - wheel.centre_m;
    const bool across = std::abs(arm.y()) <= 0.5 * params_.width_m;
    arm.y() = 0;
    const double distance = arm.norm();
    if (!across || distance >= radius || distance == 0) {
      slip_history_m_[k].setZero();
      continue;
    }
    const Vec3 normal = arm / distance;
    const Vec3 rim_point = wheel.centre_m + radius * normal;
    const Vec3 rim_velocity = wheel.velocity_m_s + spin.cross(rim_point - wheel.centre_m);
    const Vec3 relative = v[node] - rim_velocity;
    // Normal: penalty plus a dashpot that never pulls.
    const double damping = 2 * params_.normal_damping_ratio *
                           std::sqrt(params_.normal_stiffness_n_m * m[node]);
    const double normal_force =
        std::max(0.0, params_.normal_stiffness_n_m * (radius - distance) -
                          damping * relative.dot(normal));
    // Tangential: the history stays in the current tangent plane (rotated with the contact,
    // length kept), grows by the relative sliding, and is capped at the Coulomb limit.
    Vec3& xi = slip_history_m_[k];
    const double length = xi.norm();
    xi -= xi.dot(normal) * normal;
    if (xi.norm() > 0) xi *= length / xi.norm();
    xi += (relative - relative.dot(normal) * normal) * dt_s;
    Vec3 tangential = -params_.tangential_stiffness_n_m * xi;
    const double limit = params_.friction_coefficient * normal_force +
                         params_.adhesion_pa * node_areas_m2_[k];
    if (tangential.norm() > limit) {
      tangential *= limit / tangential.norm();
      xi = -tangential / params_.tangential_stiffness_n_m;
    }
    const Vec3 force = normal_force * normal + tangential;
    f_ext[node] += force;
    load.force_n -= force;
    load.moment_y_nm -= (rim_point - wheel.centre_m).cross(force).y();
    ++load.nodes_in_contact;
  }
  return load;
}

void TopSurfaceNodes(const fe::HexMesh& mesh, std::vector<int>* nodes,
                     std::vector<double>* areas_m2) {
  const auto& xs = mesh.x_lines_m;
  const auto& ys = mesh.y_lines_m;
  const int nx = static_cast<int>(xs.size());
  const int ny = static_cast<int>(ys.size());
  const int top = static_cast<int>(mesh.z_lines_m.size()) - 1;
  auto half_span = [](const std::vector<double>& lines, int i) {
    const double left = i > 0 ? lines[i] - lines[i - 1] : 0;
    const double right = i + 1 < static_cast<int>(lines.size()) ? lines[i + 1] - lines[i] : 0;
    return 0.5 * (left + right);
  };
  nodes->clear();
  areas_m2->clear();
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      nodes->push_back(mesh.GridNode(i, j, top));
      areas_m2->push_back(half_span(xs, i) * half_span(ys, j));
    }
  }
}

}  // namespace gonogo::rig
