#include "solvers/dem/simulation.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::dem {

namespace {
constexpr double kPi = 3.14159265358979323846;

bool KeyLess(const NeighborPair& a, const NeighborPair& b) {
  return std::tie(a.i, a.j, a.key_shift) < std::tie(b.i, b.j, b.key_shift);
}
}  // namespace

void SimulationParams::Validate() const {
  material.Validate();
  box.Validate();
  for (const Wall& wall : walls) {
    Require(wall.point_m.allFinite() && std::abs(wall.normal.norm() - 1.0) < 1e-9, "walls",
            "each wall needs a finite point and a unit normal");
  }
  Require(gravity_m_s2.allFinite(), "gravity_m_s2", "must be finite");
  Require(std::isfinite(time_step_s) && time_step_s >= 0.0, "time_step_s", "must be >= 0");
  Require(time_step_safety > 0.0 && time_step_safety <= 1.0, "time_step_safety",
          "must be in (0, 1]");
  Require(std::isfinite(skin_fraction) && skin_fraction > 0.0, "skin_fraction", "must be positive");
  Require(threads >= 1, "threads", "must be >= 1");
}

double RayleighTimeStepS(double radius_m, const MaterialParams& material) {
  return kPi * radius_m * std::sqrt(material.density_kg_m3 / material.ShearModulusPa()) /
         (0.1631 * material.poisson_ratio + 0.8766);
}

Simulation::Simulation(const SimulationParams& params, Particles particles)
    : Simulation(params, std::move(particles), ContactModel::HertzMindlin(params.material)) {}

Simulation::Simulation(const SimulationParams& params, Particles particles, ContactModel model)
    : params_(params), particles_(std::move(particles)), model_(std::move(model)) {
  params_.Validate();
  Require(particles_.size() > 0, "particles", "at least one grain is needed");
  const double min_radius_m =
      *std::min_element(particles_.radius_m.begin(), particles_.radius_m.end());
  time_step_s_ = params_.time_step_s > 0.0
                     ? params_.time_step_s
                     : params_.time_step_safety * RayleighTimeStepS(min_radius_m, params_.material);
  wall_history_.assign(particles_.size() * params_.walls.size(), ContactHistory{});
}

void Simulation::Rebuild() {
  // Wrap positions into periodic axes and count the box lengths crossed.
  const Vec3 length = params_.box.LengthM();
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    for (int d = 0; d < 3; ++d) {
      if (!params_.box.periodic[d]) continue;
      const int crossed = static_cast<int>(
          std::floor((particles_.position_m[p][d] - params_.box.lo_m[d]) / length[d]));
      particles_.position_m[p][d] -= crossed * length[d];
      particles_.image[p][d] += crossed;
    }
  }
  const std::vector<NeighborPair> old_pairs = neighbors_.pairs();
  std::vector<ContactHistory> old_history = std::move(pair_history_);
  const double max_radius_m =
      *std::max_element(particles_.radius_m.begin(), particles_.radius_m.end());
  neighbors_.Build(particles_, params_.box, params_.skin_fraction * max_radius_m, params_.threads);
  ++rebuild_count_;

  // Carry history: both lists are sorted by (i, j, key_shift), so one merge pass finds matches.
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  pair_history_.assign(pairs.size(), ContactHistory{});
  std::size_t k_old = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    while (k_old < old_pairs.size() && KeyLess(old_pairs[k_old], pairs[k])) ++k_old;
    if (k_old < old_pairs.size() && !KeyLess(pairs[k], old_pairs[k_old])) {
      pair_history_[k] = old_history[k_old];
    }
  }
  pair_overlap_m_.assign(pairs.size(), 0.0);
  pair_force_on_i_n_.assign(pairs.size(), Vec3::Zero());
  pair_torque_i_n_m_.assign(pairs.size(), Vec3::Zero());
  pair_torque_j_n_m_.assign(pairs.size(), Vec3::Zero());
}

void Simulation::ComputePairForces() {
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  const int pair_count = static_cast<int>(pairs.size());
  const Particles& g = particles_;
  // Each pair is computed on its own and written to its own slot: no races, no atomics.
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int k = 0; k < pair_count; ++k) {
    const int i = pairs[k].i;
    const int j = pairs[k].j;
    const Vec3 separation = g.position_m[i] - (g.position_m[j] + pairs[k].shift_m);
    const double distance_m = separation.norm();
    const double overlap_m = g.radius_m[i] + g.radius_m[j] - distance_m;
    pair_overlap_m_[k] = std::max(overlap_m, 0.0);
    if (overlap_m <= 0.0 || distance_m == 0.0) {
      // Out of contact: forces vanish and the history is forgotten.
      pair_history_[k] = ContactHistory{};
      pair_force_on_i_n_[k].setZero();
      pair_torque_i_n_m_[k].setZero();
      pair_torque_j_n_m_[k].setZero();
      continue;
    }
    ContactKinematics kin;
    kin.normal = separation / distance_m;
    kin.overlap_m = overlap_m;
    kin.effective_radius_m = g.radius_m[i] * g.radius_m[j] / (g.radius_m[i] + g.radius_m[j]);
    kin.effective_mass_kg = g.mass_kg[i] * g.mass_kg[j] / (g.mass_kg[i] + g.mass_kg[j]);
    // Contact point in the middle of the overlap, so the arms add up to the centre distance and
    // the pair conserves angular momentum exactly.
    kin.arm_i_m = g.radius_m[i] - 0.5 * overlap_m;
    kin.arm_j_m = g.radius_m[j] - 0.5 * overlap_m;
    kin.contact_velocity_m_s =
        g.velocity_m_s[i] - g.velocity_m_s[j] -
        (kin.arm_i_m * g.angular_velocity_rad_s[i] + kin.arm_j_m * g.angular_velocity_rad_s[j])
            .cross(kin.normal);
    kin.relative_spin_rad_s = g.angular_velocity_rad_s[i] - g.angular_velocity_rad_s[j];
    const ContactResult result = model_.Evaluate(kin, time_step_s_, pair_history_[k]);
    pair_force_on_i_n_[k] = result.force_on_i_n;
    pair_torque_i_n_m_[k] = result.torque_on_i_n_m;
    pair_torque_j_n_m_[k] = result.torque_on_j_n_m;
  }
}

Vec3 Simulation::WallForce(int p, int w, Vec3& torque_n_m) {
  const Wall& wall = params_.walls[w];
  const double gap_m = (particles_.position_m[p] - wall.point_m).dot(wall.normal);
  const double overlap_m = particles_.radius_m[p] - gap_m;
  ContactHistory& history = wall_history_[p * params_.walls.size() + w];
  if (overlap_m <= 0.0) {
    history = ContactHistory{};
    return Vec3::Zero();
  }
  // Sphere-plane: r_e = r, m* = m, contact point on the plane (arm = gap).
  ContactKinematics kin;
  kin.normal = wall.normal;
  kin.overlap_m = overlap_m;
  kin.effective_radius_m = particles_.radius_m[p];
  kin.effective_mass_kg = particles_.mass_kg[p];
  kin.arm_i_m = gap_m;
  kin.arm_j_m = 0.0;
  kin.contact_velocity_m_s =
      particles_.velocity_m_s[p] - gap_m * particles_.angular_velocity_rad_s[p].cross(wall.normal);
  kin.relative_spin_rad_s = particles_.angular_velocity_rad_s[p];
  const ContactResult result = model_.Evaluate(kin, time_step_s_, history);
  torque_n_m += result.torque_on_i_n_m;
  return result.force_on_i_n;
}

void Simulation::SumParticleForces() {
  const int n = static_cast<int>(particles_.size());
  const int walls = static_cast<int>(params_.walls.size());
  const std::vector<std::int64_t>& start = neighbors_.incident_start();
  const std::vector<int>& incident = neighbors_.incident_pairs();
  const std::vector<std::int8_t>& is_i = neighbors_.incident_is_i();
  // Per particle, in ascending pair order: the same additions in the same order on any thread.
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int p = 0; p < n; ++p) {
    Vec3 force = particles_.mass_kg[p] * params_.gravity_m_s2;
    Vec3 torque = Vec3::Zero();
    for (std::int64_t s = start[p]; s < start[p + 1]; ++s) {
      const int k = incident[s];
      if (is_i[s]) {
        force += pair_force_on_i_n_[k];
        torque += pair_torque_i_n_m_[k];
      } else {
        force -= pair_force_on_i_n_[k];
        torque += pair_torque_j_n_m_[k];
      }
    }
    for (int w = 0; w < walls; ++w) force += WallForce(p, w, torque);
    particles_.force_n[p] = force;
    particles_.torque_n_m[p] = torque;
  }
}

void Simulation::ComputeForces() {
  if (neighbors_.NeedsRebuild(particles_, params_.threads)) Rebuild();
  ComputePairForces();
  SumParticleForces();
  forces_valid_ = true;
}

void Simulation::HalfKick() {
  const int n = static_cast<int>(particles_.size());
  const double half_dt = 0.5 * time_step_s_;
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int p = 0; p < n; ++p) {
    particles_.velocity_m_s[p] += half_dt / particles_.mass_kg[p] * particles_.force_n[p];
    particles_.angular_velocity_rad_s[p] +=
        half_dt * particles_.inverse_inertia_1_kg_m2[p] * particles_.torque_n_m[p];
  }
}

void Simulation::Step() {
  if (!forces_valid_) ComputeForces();
  HalfKick();
  const int n = static_cast<int>(particles_.size());
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int p = 0; p < n; ++p) particles_.position_m[p] += time_step_s_ * particles_.velocity_m_s[p];
  ComputeForces();
  HalfKick();
  time_s_ += time_step_s_;
}

void Simulation::Run(int steps) {
  for (int s = 0; s < steps; ++s) Step();
}

int Simulation::ContactCount() const {
  int count = 0;
  for (double overlap : pair_overlap_m_) count += overlap > 0.0 ? 1 : 0;
  return count;
}

double Simulation::KineticEnergyJ() const {
  double energy_j = 0.0;
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    energy_j += 0.5 * particles_.mass_kg[p] * particles_.velocity_m_s[p].squaredNorm() +
                0.5 * particles_.angular_velocity_rad_s[p].squaredNorm() /
                    particles_.inverse_inertia_1_kg_m2[p];
  }
  return energy_j;
}

double Simulation::ElasticNormalEnergyJ() const {
  double energy_j = 0.0;
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    const double r_i = particles_.radius_m[pairs[k].i];
    const double r_j = particles_.radius_m[pairs[k].j];
    energy_j += model_.normal().ElasticEnergyJ(pair_overlap_m_[k], r_i * r_j / (r_i + r_j));
  }
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    for (const Wall& wall : params_.walls) {
      const double overlap_m =
          particles_.radius_m[p] - (particles_.position_m[p] - wall.point_m).dot(wall.normal);
      if (overlap_m > 0.0) {
        energy_j += model_.normal().ElasticEnergyJ(overlap_m, particles_.radius_m[p]);
      }
    }
  }
  return energy_j;
}

Vec3 Simulation::UnwrappedPositionM(int p) const {
  const Vec3 length = params_.box.LengthM();
  Vec3 position = particles_.position_m[p];
  for (int d = 0; d < 3; ++d) position[d] += particles_.image[p][d] * length[d];
  return position;
}

Vec3 Simulation::LinearMomentumKgMS() const {
  Vec3 momentum = Vec3::Zero();
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    momentum += particles_.mass_kg[p] * particles_.velocity_m_s[p];
  }
  return momentum;
}

Vec3 Simulation::AngularMomentumKgM2S() const {
  Vec3 momentum = Vec3::Zero();
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    momentum += particles_.mass_kg[p] *
                    UnwrappedPositionM(static_cast<int>(p)).cross(particles_.velocity_m_s[p]) +
                particles_.angular_velocity_rad_s[p] / particles_.inverse_inertia_1_kg_m2[p];
  }
  return momentum;
}

}  // namespace gonogo::dem
