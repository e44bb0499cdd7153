#include "solvers/dem/particles.h"

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::dem {

std::size_t Particles::Add(const Vec3& position_m_in, const Vec3& velocity_m_s_in,
                           double radius_m_in, double density_kg_m3) {
  Require(std::isfinite(radius_m_in) && radius_m_in > 0.0, "radius_m", "must be positive");
  Require(std::isfinite(density_kg_m3) && density_kg_m3 > 0.0, "density_kg_m3", "must be positive");
  Require(position_m_in.allFinite() && velocity_m_s_in.allFinite(), "position_m",
          "position and velocity must be finite");
  const double mass =
      density_kg_m3 * 4.0 / 3.0 * units::kPi * radius_m_in * radius_m_in * radius_m_in;
  position_m.push_back(position_m_in);
  velocity_m_s.push_back(velocity_m_s_in);
  angular_velocity_rad_s.push_back(Vec3::Zero());
  force_n.push_back(Vec3::Zero());
  torque_n_m.push_back(Vec3::Zero());
  radius_m.push_back(radius_m_in);
  mass_kg.push_back(mass);
  inverse_inertia_1_kg_m2.push_back(1.0 / (0.4 * mass * radius_m_in * radius_m_in));
  image.push_back({0, 0, 0});
  return radius_m.size() - 1;
}

}  // namespace gonogo::dem
