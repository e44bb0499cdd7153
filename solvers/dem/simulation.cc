#include "solvers/dem/simulation.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/common/byte_stream.h"

namespace gonogo::dem {

namespace {
using units::kPi;

bool KeyLess(const NeighborPair& a, const NeighborPair& b) {
  return std::tie(a.i, a.j, a.key_shift) < std::tie(b.i, b.j, b.key_shift);
}

// R of the polar decomposition A = R U (A with det > 0, here near the identity): Newton's
// iteration R <- (R + R^-T) / 2 (Higham 1986, SIAM J. Sci. Stat. Comput. 7, 1160), quadratic
// from A; a handful of iterations reach round-off.
Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& a) {
  Eigen::Matrix3d rotation = a;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Matrix3d next = 0.5 * (rotation + rotation.inverse().transpose());
    const double change = (next - rotation).norm();
    rotation = next;
    if (change <= 1e-15) break;
  }
  return rotation;
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
  cell_ = Cell::FromBox(params_.box);
}

void Simulation::SetVelocityGradient(const Eigen::Matrix3d& velocity_gradient_1_s) {
  Require(velocity_gradient_1_s.allFinite(), "velocity_gradient_1_s", "must be finite");
  const bool deforming = !velocity_gradient_1_s.isZero(0.0);
  if (deforming) {
    Require(cell_.periodic[0] && cell_.periodic[1] && cell_.periodic[2] && params_.walls.empty(),
            "velocity_gradient_1_s", "a deforming cell must be periodic on every axis, with no walls");
  }
  velocity_gradient_1_s_ = velocity_gradient_1_s;
  deforming_ = deforming;
  // The background spin of one step is the rotation of A = I + dt L. A symmetric L (every
  // stretch path, and no deformation) has R = I exactly; it is left alone, so those paths keep
  // the plain affine remap bit for bit.
  spinning_ = deforming && velocity_gradient_1_s != velocity_gradient_1_s.transpose();
  if (spinning_) {
    const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
    step_rotation_ = PolarRotation(identity + time_step_s_ * velocity_gradient_1_s);
    contact_velocity_gradient_1_s_ =
        velocity_gradient_1_s - (step_rotation_ - identity) / time_step_s_;
  } else {
    step_rotation_.setIdentity();
    contact_velocity_gradient_1_s_ = velocity_gradient_1_s;
  }
}

Eigen::Matrix3i Simulation::ReduceCellEdges() {
  Eigen::Matrix3i basis = Eigen::Matrix3i::Identity();
  Eigen::Matrix3d& edges = cell_.edges_m;
  // Pairwise (Lagrange-Gauss) reduction: e_b -= k e_a with k = round(e_b . e_a / |e_a|^2), done
  // only when |e_b . e_a| > (1/2 + 1e-9) |e_a|^2, which shortens e_b strictly; the sum of squared
  // edge lengths falls at every change, so the loop ends. Each change is a shear of the basis
  // (det 1): same lattice, same volume and orientation.
  for (bool changed = true; changed;) {
    changed = false;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        const double ratio = edges.col(b).dot(edges.col(a)) / edges.col(a).squaredNorm();
        if (std::abs(ratio) <= 0.5 + 1e-9) continue;
        const int k = static_cast<int>(std::lround(ratio));
        edges.col(b) -= k * edges.col(a);
        basis.col(b) -= k * basis.col(a);
        changed = true;
      }
    }
  }
  return basis;
}

void Simulation::Rebuild() {
  std::vector<NeighborPair> old_pairs = neighbors_.pairs();
  std::vector<ContactHistory> old_history = std::move(pair_history_);
  if (params_.reduce_sheared_cell && cell_.periodic[0] && cell_.periodic[1] && cell_.periodic[2]) {
    const Eigen::Matrix3i basis = ReduceCellEdges();
    if (basis != Eigen::Matrix3i::Identity()) {
      ++cell_reduction_count_;
      // Lattice offsets counted in old edges, n, are M^-1 n in the new ones (E n = E M M^-1 n):
      // the grains' wrap counts and the contacts' keys, so history and unwrapped positions carry
      // over. M^-1 is an integer matrix (det M = 1).
      const Eigen::Matrix3i inverse = basis.cast<double>().inverse().array().round().cast<int>();
      auto to_new = [&](std::array<int, 3>& offset) {
        const Eigen::Vector3i moved = inverse * Eigen::Vector3i(offset[0], offset[1], offset[2]);
        offset = {moved[0], moved[1], moved[2]};
      };
      for (std::array<int, 3>& image : particles_.image) to_new(image);
      for (NeighborPair& pair : old_pairs) to_new(pair.key_shift);
      // The merge below needs the old list in key order again.
      std::vector<std::size_t> order(old_pairs.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
      std::sort(order.begin(), order.end(),
                [&](std::size_t x, std::size_t y) { return KeyLess(old_pairs[x], old_pairs[y]); });
      std::vector<NeighborPair> sorted_pairs(old_pairs.size());
      std::vector<ContactHistory> sorted_history(old_history.size());
      for (std::size_t k = 0; k < order.size(); ++k) {
        sorted_pairs[k] = old_pairs[order[k]];
        sorted_history[k] = old_history[order[k]];
      }
      old_pairs = std::move(sorted_pairs);
      old_history = std::move(sorted_history);
    }
  }
  // Wrap positions into the cell (fractional coordinates in [0, 1) on periodic axes) and count
  // the cell edges crossed.
  const Eigen::Matrix3d to_fraction = cell_.edges_m.inverse();
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    const Vec3 fraction = to_fraction * (particles_.position_m[p] - cell_.origin_m);
    Vec3 crossed_edges = Vec3::Zero();
    for (int d = 0; d < 3; ++d) {
      if (!cell_.periodic[d]) continue;
      const int crossed = static_cast<int>(std::floor(fraction[d]));
      crossed_edges[d] = crossed;
      particles_.image[p][d] += crossed;
    }
    if (!crossed_edges.isZero(0.0)) particles_.position_m[p] -= cell_.edges_m * crossed_edges;
  }
  const double max_radius_m =
      *std::max_element(particles_.radius_m.begin(), particles_.radius_m.end());
  neighbors_.Build(particles_, cell_, params_.skin_fraction * max_radius_m, params_.threads);
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
  pair_overlap_m_.assign(pairs.size(), -1.0);  // "not yet evaluated": cleared if open
  pair_force_on_i_n_.assign(pairs.size(), Vec3::Zero());
  pair_torque_i_n_m_.assign(pairs.size(), Vec3::Zero());
  pair_torque_j_n_m_.assign(pairs.size(), Vec3::Zero());
  pair_normal_stiffness_n_m_.assign(pairs.size(), 0.0);
  pair_tangential_stiffness_n_m_.assign(pairs.size(), 0.0);
  ComputePairConstants();
}

void Simulation::ComputePairConstants() {
  // Radii and masses never change within a simulation, so the two quotients of every contact
  // are taken once per list rather than at every step.
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  pair_effective_radius_m_.resize(pairs.size());
  pair_effective_mass_kg_.resize(pairs.size());
  const Particles& g = particles_;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const int i = pairs[k].i;
    const int j = pairs[k].j;
    pair_effective_radius_m_[k] = g.radius_m[i] * g.radius_m[j] / (g.radius_m[i] + g.radius_m[j]);
    pair_effective_mass_kg_[k] = g.mass_kg[i] * g.mass_kg[j] / (g.mass_kg[i] + g.mass_kg[j]);
  }
}

inline bool Simulation::EvaluatePair(int k) {
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  const Particles& g = particles_;
  const int i = pairs[k].i;
  const int j = pairs[k].j;
  const std::array<int, 3>& image = pairs[k].image;
  const Vec3 separation =
      (image[0] | image[1] | image[2]) == 0
          ? Vec3(g.position_m[i] - g.position_m[j])
          : Vec3(g.position_m[i] - (g.position_m[j] + pairs[k].ShiftM(cell_.edges_m)));
  const double reach_m = g.radius_m[i] + g.radius_m[j];
  const double distance_sq = separation.squaredNorm();
  const double distance_m = distance_sq < reach_m * reach_m ? std::sqrt(distance_sq) : reach_m;
  const double overlap_m = reach_m - distance_m;
  if (overlap_m <= 0.0 || distance_sq == 0.0) {
    // Out of contact: forces vanish and the history is forgotten. A pair already cleared (its
    // overlap slot is exactly 0; a rebuild marks every slot -1) needs no writes.
    if (pair_overlap_m_[k] != 0.0) {
      pair_overlap_m_[k] = 0.0;
      pair_history_[k] = ContactHistory{};
      pair_force_on_i_n_[k].setZero();
      pair_torque_i_n_m_[k].setZero();
      pair_torque_j_n_m_[k].setZero();
      pair_normal_stiffness_n_m_[k] = 0.0;
      pair_tangential_stiffness_n_m_[k] = 0.0;
    }
    return false;
  }
  pair_overlap_m_[k] = overlap_m;
  ContactKinematics kin;
  kin.normal = separation * (1.0 / distance_m);
  kin.overlap_m = overlap_m;
  kin.effective_radius_m = pair_effective_radius_m_[k];
  kin.effective_mass_kg = pair_effective_mass_kg_[k];
  // Contact point in the middle of the overlap, so the arms add up to the centre distance and
  // the pair conserves angular momentum exactly.
  kin.arm_i_m = g.radius_m[i] - 0.5 * overlap_m;
  kin.arm_j_m = g.radius_m[j] - 0.5 * overlap_m;
  kin.contact_velocity_m_s =
      g.velocity_m_s[i] - g.velocity_m_s[j] -
      (kin.arm_i_m * g.angular_velocity_rad_s[i] + kin.arm_j_m * g.angular_velocity_rad_s[j])
          .cross(kin.normal);
  // In a deforming cell the images move apart with the affine field as well, less the rigid
  // turn of the pair that the background spin of both grains follows (SetVelocityGradient):
  // with a_i + a_j = |x_i - x_j|, -(a_i w + a_j w) x n = -w x (x_i - x_j) cancels the spin.
  if (deforming_) kin.contact_velocity_m_s += contact_velocity_gradient_1_s_ * separation;
  kin.relative_spin_rad_s = g.angular_velocity_rad_s[i] - g.angular_velocity_rad_s[j];
  const ContactResult result = model_.Evaluate(kin, time_step_s_, pair_history_[k]);
  pair_normal_stiffness_n_m_[k] = result.normal_stiffness_n_m;
  pair_tangential_stiffness_n_m_[k] = result.sliding ? 0.0 : result.tangential_stiffness_n_m;
  pair_force_on_i_n_[k] = result.force_on_i_n;
  pair_torque_i_n_m_[k] = result.torque_on_i_n_m;
  pair_torque_j_n_m_[k] = result.torque_on_j_n_m;
  return true;
}

void Simulation::ComputePairForces() {
  const int pair_count = static_cast<int>(neighbors_.pairs().size());
  // Each pair is computed on its own and written to its own slot: no races, no atomics.
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int k = 0; k < pair_count; ++k) EvaluatePair(k);
}

void Simulation::ComputeAndSumForcesOneThread() {
  // What ComputePairForces then SumParticleForces give, in one pass: every grain still starts
  // from its weight and adds its pairs in ascending pair order, then its walls, so the sums are
  // the same bit for bit, without the second pass over the incident lists.
  const int n = static_cast<int>(particles_.size());
  const int walls = static_cast<int>(params_.walls.size());
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  const int pair_count = static_cast<int>(pairs.size());
  for (int p = 0; p < n; ++p) {
    particles_.force_n[p] = particles_.mass_kg[p] * params_.gravity_m_s2;
    particles_.torque_n_m[p].setZero();
  }
  for (int k = 0; k < pair_count; ++k) {
    if (!EvaluatePair(k)) continue;
    const int i = pairs[k].i;
    const int j = pairs[k].j;
    particles_.force_n[i] += pair_force_on_i_n_[k];
    particles_.torque_n_m[i] += pair_torque_i_n_m_[k];
    particles_.force_n[j] -= pair_force_on_i_n_[k];
    particles_.torque_n_m[j] += pair_torque_j_n_m_[k];
  }
  for (int p = 0; p < n; ++p) {
    for (int w = 0; w < walls; ++w) {
      particles_.force_n[p] += WallForce(p, w, particles_.torque_n_m[p]);
    }
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
      if (pair_overlap_m_[k] <= 0.0) continue;  // open pair: its slots are zero
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
  if (neighbors_.NeedsRebuild(particles_, cell_, params_.threads)) Rebuild();
  if (params_.threads == 1) {
    ComputeAndSumForcesOneThread();
  } else {
    ComputePairForces();
    SumParticleForces();
  }
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

void Simulation::RotateContactHistories() {
  const int pair_count = static_cast<int>(pair_history_.size());
  const Eigen::Matrix3d& rotation = step_rotation_;
  // Each pair on its own: no races, the same result on any thread count.
#pragma omp parallel for schedule(static) num_threads(params_.threads)
  for (int k = 0; k < pair_count; ++k) {
    if (pair_overlap_m_[k] == 0.0) continue;  // a cleared pair carries no history
    ContactHistory& history = pair_history_[k];
    history.tangential_displacement_m = rotation * history.tangential_displacement_m;
    history.rolling_angle_rad = rotation * history.rolling_angle_rad;
  }
}

void Simulation::Step() {
  if (!forces_valid_) ComputeForces();
  HalfKick();
  const int n = static_cast<int>(particles_.size());
  if (deforming_) {
    // Affine map of the cell and the grains by (I + dt L) about the cell's corner, then the
    // fluctuating drift.
    const Eigen::Matrix3d increment = time_step_s_ * velocity_gradient_1_s_;
    cell_.edges_m += increment * cell_.edges_m;
    // The grains turn with the background spin, and their contacts' springs with them.
    if (spinning_) RotateContactHistories();
#pragma omp parallel for schedule(static) num_threads(params_.threads)
    for (int p = 0; p < n; ++p) {
      particles_.position_m[p] += increment * (particles_.position_m[p] - cell_.origin_m) +
                                  time_step_s_ * particles_.velocity_m_s[p];
    }
  } else {
#pragma omp parallel for schedule(static) num_threads(params_.threads)
    for (int p = 0; p < n; ++p) {
      particles_.position_m[p] += time_step_s_ * particles_.velocity_m_s[p];
    }
  }
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

int Simulation::SlidingContactCount() const {
  int count = 0;
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    count += pair_overlap_m_[k] > 0.0 && pair_tangential_stiffness_n_m_[k] == 0.0 ? 1 : 0;
  }
  return count;
}

double Simulation::UnbalancedForceRatio() const {
  double contact_sum_n = 0.0;
  int contacts = 0;
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    contact_sum_n += pair_force_on_i_n_[k].norm();
    ++contacts;
  }
  if (contacts == 0 || contact_sum_n == 0.0) return 0.0;
  double net_sum_n = 0.0;
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    net_sum_n += (particles_.force_n[p] - particles_.mass_kg[p] * params_.gravity_m_s2).norm();
  }
  return (net_sum_n / particles_.size()) / (contact_sum_n / contacts);
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
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    energy_j += model_.normal().ElasticEnergyWithHistoryJ(
        pair_overlap_m_[k], pair_effective_radius_m_[k], pair_history_[k]);
  }
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    for (std::size_t w = 0; w < params_.walls.size(); ++w) {
      const Wall& wall = params_.walls[w];
      const double overlap_m =
          particles_.radius_m[p] - (particles_.position_m[p] - wall.point_m).dot(wall.normal);
      if (overlap_m > 0.0) {
        energy_j += model_.normal().ElasticEnergyWithHistoryJ(
            overlap_m, particles_.radius_m[p], wall_history_[p * params_.walls.size() + w]);
      }
    }
  }
  return energy_j;
}

Vec3 Simulation::UnwrappedPositionM(int p) const {
  const std::array<int, 3>& image = particles_.image[p];
  return particles_.position_m[p] + cell_.edges_m * Vec3(image[0], image[1], image[2]);
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

Eigen::Matrix3d Simulation::ContactVirialNM() const {
  Eigen::Matrix3d virial = Eigen::Matrix3d::Zero();
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    const Vec3 branch = particles_.position_m[pairs[k].i] -
                        (particles_.position_m[pairs[k].j] + pairs[k].ShiftM(cell_.edges_m));
    virial += branch * pair_force_on_i_n_[k].transpose();
  }
  return virial;
}

Eigen::Matrix3d Simulation::ContactFabric() const {
  Eigen::Matrix3d fabric = Eigen::Matrix3d::Zero();
  int contacts = 0;
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    const Vec3 normal = (particles_.position_m[pairs[k].i] -
                         (particles_.position_m[pairs[k].j] + pairs[k].ShiftM(cell_.edges_m)))
                            .normalized();
    fabric += normal * normal.transpose();
    ++contacts;
  }
  return contacts > 0 ? Eigen::Matrix3d(fabric / contacts) : fabric;
}

Eigen::Matrix<double, 6, 6> Simulation::ContactStiffnessVoigtNM() const {
  // Voigt index -> tensor indices, xx yy zz yz xz xy.
  static constexpr int kFirst[6] = {0, 1, 2, 1, 0, 0};
  static constexpr int kSecond[6] = {0, 1, 2, 2, 2, 1};
  Eigen::Matrix<double, 6, 6> stiffness = Eigen::Matrix<double, 6, 6>::Zero();
  const std::vector<NeighborPair>& pairs = neighbors_.pairs();
  for (std::size_t k = 0; k < pair_overlap_m_.size(); ++k) {
    if (pair_overlap_m_[k] <= 0.0) continue;
    const Vec3 branch = particles_.position_m[pairs[k].i] -
                        (particles_.position_m[pairs[k].j] + pairs[k].ShiftM(cell_.edges_m));
    const Vec3 normal = branch.normalized();
    const double k_n = pair_normal_stiffness_n_m_[k];
    const double k_t = pair_tangential_stiffness_n_m_[k];
    // C_ijkl = k_n n_i d_j n_k d_l + k_t (delta_ik - n_i n_k) d_j d_l, symmetrised in (ij) and
    // (kl) so it maps symmetric strain to symmetric stress.
    auto component = [&](int i, int j, int a, int b) {
      const double delta = i == a ? 1.0 : 0.0;
      return k_n * normal[i] * branch[j] * normal[a] * branch[b] +
             k_t * (delta - normal[i] * normal[a]) * branch[j] * branch[b];
    };
    for (int row = 0; row < 6; ++row) {
      const int i = kFirst[row], j = kSecond[row];
      for (int col = 0; col < 6; ++col) {
        const int a = kFirst[col], b = kSecond[col];
        // A shear column multiplies gamma_ab = 2 eps_ab, which carries both eps_ab and eps_ba,
        // so the symmetrised component is the Voigt entry for every column.
        stiffness(row, col) += 0.25 * (component(i, j, a, b) + component(j, i, a, b) +
                                       component(i, j, b, a) + component(j, i, b, a));
      }
    }
  }
  return stiffness;
}

namespace {
// 02: contact history carries the EEPA line overlap (line_max_overlap_m).
constexpr char kStateTag[9] = "GNGDEM02";

void PutHistory(ByteWriter& out, const ContactHistory& history) {
  out.Put(history.tangential_displacement_m);
  out.Put(history.rolling_angle_rad);
  out.Put(history.max_overlap_m);
  out.Put(history.line_max_overlap_m);
}
void GetHistory(ByteReader& in, ContactHistory& history) {
  in.Get(history.tangential_displacement_m);
  in.Get(history.rolling_angle_rad);
  in.Get(history.max_overlap_m);
  in.Get(history.line_max_overlap_m);
}
}  // namespace

std::string Simulation::SaveState() const {
  ByteWriter out;
  out.PutTag(kStateTag);
  out.Put(static_cast<std::uint32_t>(0x01020304));  // byte-order check
  const std::uint64_t n = particles_.size();
  out.Put(n);
  out.Put(time_s_);
  out.Put(time_step_s_);
  out.Put(static_cast<std::int32_t>(rebuild_count_));
  out.Put(cell_.origin_m);
  out.Put(cell_.edges_m);
  out.Put(velocity_gradient_1_s_);
  out.PutVector(particles_.position_m);
  out.PutVector(particles_.velocity_m_s);
  out.PutVector(particles_.angular_velocity_rad_s);
  out.PutVector(particles_.force_n);
  out.PutVector(particles_.torque_n_m);
  out.PutVector(particles_.radius_m);
  out.PutVector(particles_.mass_kg);
  out.PutVector(particles_.inverse_inertia_1_kg_m2);
  out.PutVector(particles_.image);
  out.Put(static_cast<std::uint8_t>(forces_valid_ && neighbors_.built()));
  if (forces_valid_ && neighbors_.built()) {
    // The list is rebuilt from what its last build saw; the per-pair state follows it.
    out.PutVector(neighbors_.position_at_build_m());
    out.Put(neighbors_.cell_at_build().edges_m);
    out.Put(static_cast<std::uint64_t>(pair_history_.size()));
    for (std::size_t k = 0; k < pair_history_.size(); ++k) {
      // Open pairs carry nothing; only contacts (and pairs with history) are written.
      const bool active = pair_overlap_m_[k] > 0.0;
      out.Put(static_cast<std::uint8_t>(active));
      if (!active) continue;
      PutHistory(out, pair_history_[k]);
      out.Put(pair_overlap_m_[k]);
      out.Put(pair_force_on_i_n_[k]);
      out.Put(pair_torque_i_n_m_[k]);
      out.Put(pair_torque_j_n_m_[k]);
      out.Put(pair_normal_stiffness_n_m_[k]);
      out.Put(pair_tangential_stiffness_n_m_[k]);
    }
    out.Put(static_cast<std::uint64_t>(wall_history_.size()));
    for (const ContactHistory& history : wall_history_) PutHistory(out, history);
  }
  return out.Take();
}

void Simulation::RestoreState(const std::string& bytes) {
  ByteReader in(bytes);
  in.ExpectTag(kStateTag);
  std::uint32_t order = 0;
  in.Get(order);
  Require(order == 0x01020304, "state", "saved on a machine of the other byte order");
  std::uint64_t n = 0;
  in.Get(n);
  Require(n > 0 && n < (1ull << 31), "state", "grain count out of range");
  Particles restored;
  double time_s = 0.0, time_step_s = 0.0;
  std::int32_t rebuild_count = 0;
  Cell cell = Cell::FromBox(params_.box);
  Eigen::Matrix3d velocity_gradient_1_s;
  in.Get(time_s);
  in.Get(time_step_s);
  in.Get(rebuild_count);
  in.Get(cell.origin_m);
  in.Get(cell.edges_m);
  in.Get(velocity_gradient_1_s);
  in.GetVector(restored.position_m, n);
  in.GetVector(restored.velocity_m_s, n);
  in.GetVector(restored.angular_velocity_rad_s, n);
  in.GetVector(restored.force_n, n);
  in.GetVector(restored.torque_n_m, n);
  in.GetVector(restored.radius_m, n);
  in.GetVector(restored.mass_kg, n);
  in.GetVector(restored.inverse_inertia_1_kg_m2, n);
  in.GetVector(restored.image, n);
  std::uint8_t has_contacts = 0;
  in.Get(has_contacts);
  NeighborList neighbors;
  std::vector<ContactHistory> pair_history;
  std::vector<double> overlap, k_n, k_t;
  std::vector<Vec3> force, torque_i, torque_j;
  std::vector<ContactHistory> wall_history(n * params_.walls.size());
  if (has_contacts) {
    Particles at_build = restored;
    in.GetVector(at_build.position_m, n);
    Cell cell_at_build = cell;
    in.Get(cell_at_build.edges_m);
    const double max_radius_m = *std::max_element(restored.radius_m.begin(), restored.radius_m.end());
    neighbors.Build(at_build, cell_at_build, params_.skin_fraction * max_radius_m, params_.threads);
    std::uint64_t pair_count = 0;
    in.Get(pair_count);
    Require(pair_count == neighbors.pairs().size(), "state",
            "the saved contacts do not match the rebuilt neighbour list (different parameters?)");
    pair_history.assign(pair_count, ContactHistory{});
    overlap.assign(pair_count, 0.0);
    k_n.assign(pair_count, 0.0);
    k_t.assign(pair_count, 0.0);
    force.assign(pair_count, Vec3::Zero());
    torque_i.assign(pair_count, Vec3::Zero());
    torque_j.assign(pair_count, Vec3::Zero());
    for (std::uint64_t k = 0; k < pair_count; ++k) {
      std::uint8_t active = 0;
      in.Get(active);
      if (!active) continue;
      GetHistory(in, pair_history[k]);
      in.Get(overlap[k]);
      in.Get(force[k]);
      in.Get(torque_i[k]);
      in.Get(torque_j[k]);
      in.Get(k_n[k]);
      in.Get(k_t[k]);
    }
    std::uint64_t wall_count = 0;
    in.Get(wall_count);
    Require(wall_count == wall_history.size(), "state", "wall count does not match the parameters");
    for (ContactHistory& history : wall_history) GetHistory(in, history);
  }
  Require(in.AtEnd(), "state", "trailing bytes after the saved state");

  // Everything read: commit.
  particles_ = std::move(restored);
  time_s_ = time_s;
  time_step_s_ = time_step_s;
  rebuild_count_ = rebuild_count;
  cell_ = cell;
  neighbors_ = std::move(neighbors);
  pair_history_ = std::move(pair_history);
  pair_overlap_m_ = std::move(overlap);
  pair_force_on_i_n_ = std::move(force);
  pair_torque_i_n_m_ = std::move(torque_i);
  pair_torque_j_n_m_ = std::move(torque_j);
  pair_normal_stiffness_n_m_ = std::move(k_n);
  pair_tangential_stiffness_n_m_ = std::move(k_t);
  wall_history_ = std::move(wall_history);
  ComputePairConstants();
  forces_valid_ = has_contacts != 0;
  SetVelocityGradient(velocity_gradient_1_s);
}

}  // namespace gonogo::dem
