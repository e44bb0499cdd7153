#include "solvers/fe/explicit_solver.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <limits>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"

namespace gonogo::fe {

double RetainedDeviatoricFraction(const Eigen::Matrix3d& stress_n_pa,
                                  const Eigen::Matrix3d& stress_next_pa,
                                  const Eigen::Matrix3d& displacement_gradient_increment,
                                  double shear_modulus_pa) {
  const auto deviator = [](const Eigen::Matrix3d& t) {
    return Eigen::Matrix3d(t - t.trace() / 3.0 * Eigen::Matrix3d::Identity());
  };
  const Eigen::Matrix3d strain_increment =
      0.5 * (displacement_gradient_increment + displacement_gradient_increment.transpose());
  // The rotation of the step leaves the norm unchanged, so the unrotated sum measures the trial.
  const double trial_norm =
      (deviator(stress_n_pa) + 2 * shear_modulus_pa * deviator(strain_increment)).norm();
  const double next_norm = deviator(stress_next_pa).norm();
  if (!(trial_norm > 0)) return 1.0;
  const double fraction = next_norm / trial_norm;
  // Elastic steps differ from 1 only by the second-order rotation error; they keep everything.
  return fraction > 1 - 1e-6 ? 1.0 : std::max(0.0, fraction);
}

void ExplicitOptions::Validate(const std::string& p) const {
  Require(density_kg_m3 > 0 && std::isfinite(density_kg_m3), p + "density_kg_m3",
          "must be positive");
  Require(gravity_m_s2.allFinite(), p + "gravity_m_s2", "must be finite");
  Require(hourglass_coefficient >= 0 && hourglass_coefficient <= 0.15, p + "hourglass_coefficient",
          "must lie in [0, 0.15]");
  Require(hourglass_viscosity >= 0 && hourglass_viscosity <= 0.15, p + "hourglass_viscosity",
          "must lie in [0, 0.15]");
  Require(time_step_safety > 0 && time_step_safety <= 1, p + "time_step_safety",
          "must lie in (0, 1]");
  Require(mass_damping_per_s >= 0, p + "mass_damping_per_s", "must not be negative");
  Require(std::isfinite(mass_scaling) && mass_scaling >= 1, p + "mass_scaling",
          "must be a finite factor >= 1");
  Require(threads >= 1, p + "threads", "must be at least 1");
}

ExplicitSolver::ExplicitSolver(HexMesh mesh,
                               std::shared_ptr<const material::ConstitutiveModel> model,
                               const ExplicitOptions& options)
    : mesh_(std::move(mesh)), model_(std::move(model)), options_(options) {
  options_.Validate("fe.");
  Require(model_ != nullptr, "fe.material", "is missing");
  Require(mesh_.num_elements() > 0, "mesh", "has no elements");
  moduli_ = model_->InitialElasticModuli();
  Require(moduli_.bulk_pa > 0 && moduli_.shear_pa > 0, "fe.material",
          "its initial elastic moduli must be positive");
  const double p_wave_modulus_pa = moduli_.bulk_pa + 4.0 / 3.0 * moduli_.shear_pa;
  // Inertia is that of the scaled density: the wave speed, hence the stable step, and the viscous
  // hourglass coefficient follow it.
  const double inertial_density_kg_m3 = options_.mass_scaling * options_.density_kg_m3;
  const double wave_speed_m_s = std::sqrt(p_wave_modulus_pa / inertial_density_kg_m3);

  const int ne = mesh_.num_elements();
  const int nn = mesh_.num_nodes();
  references_.resize(ne);
  hourglass_stiffness_n_m_.resize(ne);
  hourglass_viscosity_n_s_m_.resize(ne);
  nodal_masses_kg_.assign(nn, 0.0);
  double min_length_m = std::numeric_limits<double>::infinity();
  for (int e = 0; e < ne; ++e) {
    std::array<Vec3, 8> x;
    for (int a = 0; a < 8; ++a) x[a] = mesh_.reference_positions_m[mesh_.elements[e][a]];
    references_[e] = ComputeHex8Reference(x);
    const Hex8Reference& r = references_[e];
    // Stiffness-form hourglass coefficient, kappa = eps_hg (K + 4G/3) V_0 (b_a . b_a) / 3
    // (Flanagan & Belytschko 1981): scales with the element's own P-wave stiffness.
    hourglass_stiffness_n_m_[e] = options_.hourglass_coefficient * p_wave_modulus_pa *
                                  r.volume_m3 * r.gradients_per_m.squaredNorm() / 3.0;
    // Viscous hourglass coefficient, c = Q_hg rho_0 c_d V_0^(2/3) / 4 (Flanagan & Belytschko 1981;
    // LS-DYNA Theory Manual, "Hourglass control", viscous form): resists hourglass velocities only,
    // so it damps the modes the stiffness form leaves free in plastic flow without stiffening
    // slow deformation.
    hourglass_viscosity_n_s_m_[e] = options_.hourglass_viscosity * inertial_density_kg_m3 *
                                    wave_speed_m_s * std::pow(r.volume_m3, 2.0 / 3.0) / 4.0;
    // Lumped mass: an eighth of the element's mass to each of its nodes (row sum of the
    // consistent mass of a parallelepiped).
    for (int a = 0; a < 8; ++a) {
      nodal_masses_kg_[mesh_.elements[e][a]] += inertial_density_kg_m3 * r.volume_m3 / 8.0;
    }
    min_length_m = std::min(min_length_m, r.characteristic_length_m);
  }
  stable_time_step_s_ = options_.time_step_safety * min_length_m / wave_speed_m_s;

  previous_f_.assign(ne, Eigen::Matrix3d::Identity());
  trial_f_.assign(ne, Eigen::Matrix3d::Identity());
  material_points_ = model_->MakePointStore();
  Require(material_points_ != nullptr, "fe.material", "gave no point store");
  element_points_ = material_points_->Create(ne);
  stress_pa_.assign(ne, Eigen::Matrix3d::Zero());
  hourglass_forces_n_.assign(ne, Eigen::Matrix<double, 4, 3>::Zero());
  hourglass_modes_m_.assign(ne, Eigen::Matrix<double, 4, 3>::Zero());
  element_forces_n_.assign(ne, Mat83::Zero());
  increments_.assign(ne, Eigen::Matrix3d::Zero());

  node_element_offsets_.assign(nn + 1, 0);
  for (const auto& element : mesh_.elements) {
    for (int node : element) ++node_element_offsets_[node + 1];
  }
  for (int n = 0; n < nn; ++n) node_element_offsets_[n + 1] += node_element_offsets_[n];
  node_element_slots_.resize(node_element_offsets_[nn]);
  std::vector<int> fill(node_element_offsets_.begin(), node_element_offsets_.end() - 1);
  for (int e = 0; e < ne; ++e) {
    for (int a = 0; a < 8; ++a) node_element_slots_[fill[mesh_.elements[e][a]]++] = 8 * e + a;
  }

  positions_m_ = mesh_.reference_positions_m;
  velocities_m_s_.assign(nn, Vec3::Zero());
  internal_forces_n_.assign(nn, Vec3::Zero());
  external_forces_n_.assign(nn, Vec3::Zero());
  prescribed_.assign(nn, Eigen::Matrix<bool, 3, 1>::Constant(false));
  prescribed_velocity_m_s_.assign(nn, Vec3::Zero());
}

void ExplicitSolver::PrescribeVelocity(int node, int dof, double velocity_m_s) {
  Require(node >= 0 && node < mesh_.num_nodes(), "node", "is out of range");
  Require(dof >= 0 && dof < 3, "dof", "must be 0, 1 or 2");
  prescribed_[node][dof] = true;
  prescribed_velocity_m_s_[node][dof] = velocity_m_s;
  velocities_m_s_[node][dof] = velocity_m_s;
}

void ExplicitSolver::Release(int node, int dof) {
  Require(node >= 0 && node < mesh_.num_nodes(), "node", "is out of range");
  Require(dof >= 0 && dof < 3, "dof", "must be 0, 1 or 2");
  prescribed_[node][dof] = false;
}

StepStatus ExplicitSolver::ComputeInternalForces() {
  const int ne = mesh_.num_elements();
  // 1. Deformation gradients at x_n and the increments since the last committed step.
  bool inverted = false;
#pragma omp parallel for schedule(static) num_threads(options_.threads) reduction(|| : inverted)
  for (int e = 0; e < ne; ++e) {
    std::array<Vec3, 8> x;
    for (int a = 0; a < 8; ++a) x[a] = positions_m_[mesh_.elements[e][a]];
    trial_f_[e] = DeformationGradient(x, references_[e].gradients_per_m);
    if (!(trial_f_[e].determinant() > 0)) inverted = true;
    increments_[e] = trial_f_[e] * previous_f_[e].inverse() - Eigen::Matrix3d::Identity();
  }
  if (inverted) return {false, "an element turned inside out (det F <= 0): the mesh is too "
                               "distorted or the time step too large"};

  // 2. The material answers for the whole mesh in one batch of trial states; they are committed
  //    only when every element answered, so a failed step leaves the committed states intact and
  //    the caller can cut the step.
  const std::vector<material::TrialResponse> responses =
      material_points_->TryUpdate(element_points_, increments_, false);
  for (int e = 0; e < ne; ++e) {
    if (responses[e].status != material::UpdateStatus::kOk) {
      material_points_->Discard(element_points_);
      return {false, "element " + std::to_string(e) + ": " + responses[e].reason};
    }
  }
  material_points_->Commit(element_points_);

  // 3. The committed stresses, and the element forces: f_a = V_0 P b_a with P = F S =
  //    J sigma F^-T, plus the hourglass forces f_a += gamma_alpha,a (Q_alpha + c dq_alpha/dt): Q of
  //    the incremental stiffness form, Q_{n+1} = r (Q_n + kappa (q_{n+1} - q_n)) with r of
  //    RetainedDeviatoricFraction, and the viscous form on the mid-step velocities.
  const double shear_modulus_pa = moduli_.shear_pa;
#pragma omp parallel for schedule(static) num_threads(options_.threads)
  for (int e = 0; e < ne; ++e) {
    const Eigen::Matrix3d previous_stress_pa = stress_pa_[e];
    stress_pa_[e] = responses[e].stress_pa;
    previous_f_[e] = trial_f_[e];
    const Hex8Reference& r = references_[e];
    const Eigen::Matrix3d& f = trial_f_[e];
    const Eigen::Matrix3d first_pk = f.determinant() * stress_pa_[e] * f.inverse().transpose();
    Mat83 forces = r.gradients_per_m * first_pk.transpose() * r.volume_m3;
    if (hourglass_stiffness_n_m_[e] > 0) {
      Mat83 displacements;
      for (int a = 0; a < 8; ++a) {
        const int node = mesh_.elements[e][a];
        displacements.row(a) = (positions_m_[node] - mesh_.reference_positions_m[node]).transpose();
      }
      const Eigen::Matrix<double, 4, 3> modes = r.hourglass_vectors * displacements;
      const double retained = RetainedDeviatoricFraction(
          previous_stress_pa, stress_pa_[e], increments_[e],
          shear_modulus_pa);
      hourglass_forces_n_[e] =
          retained * (hourglass_forces_n_[e] +
                      hourglass_stiffness_n_m_[e] * (modes - hourglass_modes_m_[e]));
      hourglass_modes_m_[e] = modes;
      forces += r.hourglass_vectors.transpose() * hourglass_forces_n_[e];
    }
    if (hourglass_viscosity_n_s_m_[e] > 0) {
      Mat83 velocities;
      for (int a = 0; a < 8; ++a) {
        velocities.row(a) = velocities_m_s_[mesh_.elements[e][a]].transpose();
      }
      forces += hourglass_viscosity_n_s_m_[e] * r.hourglass_vectors.transpose() *
                (r.hourglass_vectors * velocities);
    }
    element_forces_n_[e] = forces;
  }

  // 4. Gather per node in a fixed order, so the sum does not depend on the thread count.
  const int nn = mesh_.num_nodes();
#pragma omp parallel for schedule(static) num_threads(options_.threads)
  for (int n = 0; n < nn; ++n) {
    Vec3 sum = Vec3::Zero();
    for (int k = node_element_offsets_[n]; k < node_element_offsets_[n + 1]; ++k) {
      const int slot = node_element_slots_[k];
      sum += element_forces_n_[slot / 8].row(slot % 8).transpose();
    }
    internal_forces_n_[n] = sum;
  }
  return {};
}

StepStatus ExplicitSolver::Step(double dt_s) {
  Require(dt_s > 0 && std::isfinite(dt_s), "dt_s", "must be positive");
  StepStatus status = ComputeInternalForces();
  if (!status.ok) return status;
  // Central differences (Belytschko, Liu & Moran 2000, Box 6.1) with mass-proportional damping
  // taken at the mid-step velocity:
  //   v_{n+1/2} = ((1 - alpha dt/2) v_{n-1/2} + dt a_n) / (1 + alpha dt/2),  x_{n+1} = x_n + dt v.
  const double damping = 0.5 * options_.mass_damping_per_s * dt_s;
  const double weight_per_inertial_mass = 1.0 / options_.mass_scaling;  // gravity: physical mass
  const int nn = mesh_.num_nodes();
#pragma omp parallel for schedule(static) num_threads(options_.threads)
  for (int n = 0; n < nn; ++n) {
    const Vec3 force = external_forces_n_[n] +
                       weight_per_inertial_mass * nodal_masses_kg_[n] * options_.gravity_m_s2 -
                       internal_forces_n_[n];
    Vec3 v = ((1 - damping) * velocities_m_s_[n] + dt_s * force / nodal_masses_kg_[n]) /
             (1 + damping);
    for (int d = 0; d < 3; ++d) {
      if (prescribed_[n][d]) v[d] = prescribed_velocity_m_s_[n][d];
    }
    velocities_m_s_[n] = v;
    positions_m_[n] += dt_s * v;
  }
  time_s_ += dt_s;
  return {};
}

void ExplicitSolver::SetMassScaling(double mass_scaling) {
  Require(std::isfinite(mass_scaling) && mass_scaling >= 1, "fe.mass_scaling",
          "must be a finite factor >= 1");
  if (time_s_ != 0) throw std::logic_error("fe: mass scaling is set before the first step");
  const double ratio = mass_scaling / options_.mass_scaling;
  for (double& mass : nodal_masses_kg_) mass *= ratio;
  // The viscous hourglass coefficient is rho c_d (x geometry): rho x ratio, c_d / sqrt(ratio).
  for (double& viscosity : hourglass_viscosity_n_s_m_) viscosity *= std::sqrt(ratio);
  stable_time_step_s_ *= std::sqrt(ratio);
  options_.mass_scaling = mass_scaling;
}

void ExplicitSolver::SetInitialPointState(int element, const std::string& state_bytes) {
  if (time_s_ != 0) throw std::logic_error("fe: initial point states are set before the first step");
  material_points_->Restore(element_points_.at(static_cast<std::size_t>(element)), state_bytes);
}

namespace {
constexpr char kSolverStateTag[9] = "GNGFES01";

template <typename Matrix>
void PutMatrices(ByteWriter& out, const std::vector<Matrix>& values) {
  out.Put(static_cast<std::uint64_t>(values.size()));
  for (const Matrix& value : values) {
    for (int k = 0; k < value.size(); ++k) out.Put(value.data()[k]);
  }
}

template <typename Matrix>
void GetMatrices(ByteReader& in, std::vector<Matrix>& values, std::size_t expected) {
  std::uint64_t count = 0;
  in.Get(count);
  Require(count == expected, "state", "saved for another mesh");
  values.resize(expected);
  for (Matrix& value : values) {
    for (int k = 0; k < value.size(); ++k) in.Get(value.data()[k]);
  }
}
}  // namespace

std::string ExplicitSolver::SaveState() const {
  ByteWriter out;
  out.PutTag(kSolverStateTag);
  out.Put(time_s_);
  out.Put(options_.mass_damping_per_s);
  PutMatrices(out, positions_m_);
  PutMatrices(out, velocities_m_s_);
  PutMatrices(out, internal_forces_n_);
  PutMatrices(out, previous_f_);
  PutMatrices(out, stress_pa_);
  PutMatrices(out, hourglass_forces_n_);
  PutMatrices(out, hourglass_modes_m_);
  return out.Take();
}

void ExplicitSolver::RestoreState(const std::string& bytes) {
  const std::size_t nodes = static_cast<std::size_t>(mesh_.num_nodes());
  const std::size_t elements = static_cast<std::size_t>(mesh_.num_elements());
  ByteReader in(bytes);
  in.ExpectTag(kSolverStateTag);
  double time_s = 0, damping = 0;
  in.Get(time_s);
  in.Get(damping);
  std::vector<Vec3> positions, velocities, internal_forces;
  std::vector<Eigen::Matrix3d> previous_f, stress;
  std::vector<Eigen::Matrix<double, 4, 3>> hourglass_forces, hourglass_modes;
  GetMatrices(in, positions, nodes);
  GetMatrices(in, velocities, nodes);
  GetMatrices(in, internal_forces, nodes);
  GetMatrices(in, previous_f, elements);
  GetMatrices(in, stress, elements);
  GetMatrices(in, hourglass_forces, elements);
  GetMatrices(in, hourglass_modes, elements);
  Require(in.AtEnd(), "state", "trailing bytes after the solver state");
  time_s_ = time_s;
  options_.mass_damping_per_s = damping;
  positions_m_ = std::move(positions);
  velocities_m_s_ = std::move(velocities);
  internal_forces_n_ = std::move(internal_forces);
  previous_f_ = std::move(previous_f);
  stress_pa_ = std::move(stress);
  hourglass_forces_n_ = std::move(hourglass_forces);
  hourglass_modes_m_ = std::move(hourglass_modes);
}

double ExplicitSolver::KineticEnergyJ() const {
  double energy = 0;
  for (int n = 0; n < mesh_.num_nodes(); ++n) {
    energy += 0.5 * nodal_masses_kg_[n] * velocities_m_s_[n].squaredNorm();
  }
  return energy;
}

}  // namespace gonogo::fe
