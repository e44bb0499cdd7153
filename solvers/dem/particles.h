// Spheres stored as a structure of arrays: one std::vector per quantity, indexed by particle.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <vector>

namespace gonogo::dem {

using Vec3 = Eigen::Vector3d;

struct Particles {
  std::vector<Vec3> position_m;                 // (N x 3), wrapped into a periodic box at rebuilds
  std::vector<Vec3> velocity_m_s;               // (N x 3)
  std::vector<Vec3> angular_velocity_rad_s;     // (N x 3)
  std::vector<Vec3> force_n;                    // (N x 3), total of the last force evaluation
  std::vector<Vec3> torque_n_m;                 // (N x 3)
  std::vector<double> radius_m;                 // (N)
  std::vector<double> mass_kg;                  // (N)
  std::vector<double> inverse_inertia_1_kg_m2;  // (N), solid sphere: I = 2/5 m r^2
  std::vector<std::array<int, 3>> image;        // (N x 3), box lengths crossed by wrapping

  std::size_t size() const { return radius_m.size(); }

  // Appends a solid sphere of the given radius and density; returns its index.
  std::size_t Add(const Vec3& position_m_in, const Vec3& velocity_m_s_in, double radius_m_in,
                  double density_kg_m3);
};

}  // namespace gonogo::dem
