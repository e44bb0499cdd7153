#include "solvers/dem/contact_model.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::dem {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

void MaterialParams::Validate() const {
  Require(std::isfinite(youngs_modulus_pa) && youngs_modulus_pa > 0.0, "youngs_modulus_pa",
          "must be positive");
  Require(poisson_ratio >= 0.0 && poisson_ratio < 0.5, "poisson_ratio", "must be in [0, 0.5)");
  Require(std::isfinite(density_kg_m3) && density_kg_m3 > 0.0, "density_kg_m3", "must be positive");
  Require(friction >= 0.0 && std::isfinite(friction), "friction", "must be >= 0");
  Require(rolling_stiffness >= 0.0 && std::isfinite(rolling_stiffness), "rolling_stiffness",
          "must be >= 0");
  Require(rolling_limit >= 0.0 && std::isfinite(rolling_limit), "rolling_limit", "must be >= 0");
  Require(restitution > 0.0 && restitution <= 1.0, "restitution", "must be in (0, 1]");
}

void ProjectOntoContactPlane(const Vec3& normal, Vec3& stored) {
  const double normal_part = stored.dot(normal);
  if (normal_part == 0.0) return;
  const double length_sq_before = stored.squaredNorm();
  stored -= normal_part * normal;
  const double length_sq_after = stored.squaredNorm();
  if (length_sq_after > 0.0) stored *= std::sqrt(length_sq_before / length_sq_after);
}

HertzNormal::HertzNormal(const MaterialParams& material)
    : effective_modulus_pa_(material.EffectiveModulusPa()) {}

NormalResponse HertzNormal::Evaluate(double overlap_m, double effective_radius_m) const {
  // F_n = 4/3 E* sqrt(r_e) d^{3/2}, k_n = 2 E* sqrt(r_e d) (Johnson 1985, sec. 4.2).
  const double sqrt_rd = std::sqrt(effective_radius_m * overlap_m);
  return {4.0 / 3.0 * effective_modulus_pa_ * sqrt_rd * overlap_m,
          2.0 * effective_modulus_pa_ * sqrt_rd};
}

double HertzNormal::ElasticEnergyJ(double overlap_m, double effective_radius_m) const {
  // U = 8/15 E* sqrt(r_e) d^{5/2}.
  return 8.0 / 15.0 * effective_modulus_pa_ * std::sqrt(effective_radius_m) *
         std::pow(overlap_m, 2.5);
}

RestitutionDamping::RestitutionDamping(double restitution, bool tangential)
    : beta_(BetaFromRestitution(restitution)), tangential_(tangential) {}

double RestitutionDamping::BetaFromRestitution(double restitution) {
  Require(restitution > 0.0 && restitution <= 1.0, "restitution", "must be in (0, 1]");
  const double log_e = std::log(restitution);
  return log_e / std::sqrt(log_e * log_e + kPi * kPi);
}

double RestitutionDamping::NormalCoefficient(double normal_stiffness_n_m,
                                             double effective_mass_kg) const {
  // gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*) with S_n = k_n (LIGGGHTS normal_model_hertz.h).
  return -2.0 * std::sqrt(5.0 / 6.0) * beta_ * std::sqrt(normal_stiffness_n_m * effective_mass_kg);
}

double RestitutionDamping::TangentialCoefficient(double tangential_stiffness_n_m,
                                                 double effective_mass_kg) const {
  if (!tangential_) return 0.0;
  return -2.0 * std::sqrt(5.0 / 6.0) * beta_ *
         std::sqrt(tangential_stiffness_n_m * effective_mass_kg);
}

MindlinTangential::MindlinTangential(const MaterialParams& material)
    : shear_modulus_pa_(material.ShearModulusPa()),
      poisson_ratio_(material.poisson_ratio),
      friction_(material.friction) {}

double MindlinTangential::Stiffness(double overlap_m, double effective_radius_m) const {
  // k_t = 4 G sqrt(r_e d_n) / (2 - nu) (seed 000; = 8 G* sqrt(r_e d_n), Mindlin 1949).
  return 4.0 * shear_modulus_pa_ * std::sqrt(effective_radius_m * overlap_m) /
         (2.0 - poisson_ratio_);
}

ElasticPlasticRolling::ElasticPlasticRolling(double rolling_stiffness, double rolling_limit)
    : beta_(rolling_stiffness), eta_(rolling_limit) {}

double ElasticPlasticRolling::StiffnessNmRad(double normal_stiffness_n_m,
                                             double effective_radius_m) const {
  // k_r = beta k_n eta^2 r_e^2 (Ai et al. 2011 with beta = 2.25 in 3D; LIGGGHTS epsd3).
  return beta_ * normal_stiffness_n_m * eta_ * eta_ * effective_radius_m * effective_radius_m;
}

Vec3 ElasticPlasticRolling::Torque(const ContactKinematics& kin, double normal_stiffness_n_m,
                                   double normal_force_n, double dt_s,
                                   ContactHistory& history) const {
  Vec3& theta = history.rolling_angle_rad;
  // Only the rolling part of the relative rotation loads the spring (no twisting resistance).
  ProjectOntoContactPlane(kin.normal, theta);
  const Vec3 spin = kin.relative_spin_rad_s - kin.relative_spin_rad_s.dot(kin.normal) * kin.normal;
  theta += spin * dt_s;
  const double k_r = StiffnessNmRad(normal_stiffness_n_m, kin.effective_radius_m);
  Vec3 torque = -k_r * theta;
  // Full mobilisation: |M_r| <= eta F_n r_e; the spring is reset to the limit (plastic).
  const double limit = eta_ * std::max(normal_force_n, 0.0) * kin.effective_radius_m;
  const double magnitude = torque.norm();
  if (magnitude > limit) {
    torque *= (magnitude > 0.0 ? limit / magnitude : 0.0);
    theta = k_r > 0.0 ? Vec3(-torque / k_r) : Vec3::Zero();
  }
  return torque;
}

ContactModel::ContactModel(std::shared_ptr<const NormalModel> normal,
                           std::shared_ptr<const DampingModel> damping,
                           std::shared_ptr<const TangentialModel> tangential,
                           std::shared_ptr<const RollingModel> rolling)
    : normal_(std::move(normal)),
      damping_(std::move(damping)),
      tangential_(std::move(tangential)),
      rolling_(std::move(rolling)) {
  Require(normal_ && damping_ && tangential_ && rolling_, "contact_model",
          "every sub-model must be set");
}

ContactModel ContactModel::HertzMindlin(const MaterialParams& material) {
  material.Validate();
  std::shared_ptr<const DampingModel> damping;
  if (material.restitution < 1.0) {
    damping = std::make_shared<RestitutionDamping>(material.restitution, true);
  } else {
    damping = std::make_shared<ZeroDamping>();
  }
  std::shared_ptr<const RollingModel> rolling;
  if (material.rolling_stiffness > 0.0 && material.rolling_limit > 0.0) {
    rolling =
        std::make_shared<ElasticPlasticRolling>(material.rolling_stiffness, material.rolling_limit);
  } else {
    rolling = std::make_shared<NoRolling>();
  }
  return ContactModel(std::make_shared<HertzNormal>(material), damping,
                      std::make_shared<MindlinTangential>(material), rolling);
}

ContactResult ContactModel::Evaluate(const ContactKinematics& kin, double dt_s,
                                     ContactHistory& history) const {
  ContactResult result;
  const Vec3& n = kin.normal;
  const double m_eff = kin.effective_mass_kg;

  // Normal: elastic spring plus dashpot on the normal relative velocity v_n (< 0 approaching).
  const NormalResponse spring = normal_->Evaluate(kin.overlap_m, kin.effective_radius_m);
  const double v_n = kin.contact_velocity_m_s.dot(n);
  const double gamma_n = damping_->NormalCoefficient(spring.stiffness_n_m, m_eff);
  const double f_n = spring.force_n - gamma_n * v_n;
  result.normal_force_n = f_n;
  result.normal_stiffness_n_m = spring.stiffness_n_m;

  // Tangential: rotate xi onto the current plane, add v_t dt, then Coulomb cap (LAMMPS
  // pair gran/hertz/history): when sliding, xi is reset so that the spring carries the cap.
  const Vec3 v_t = kin.contact_velocity_m_s - v_n * n;
  Vec3& xi = history.tangential_displacement_m;
  ProjectOntoContactPlane(n, xi);
  xi += v_t * dt_s;
  const double k_t = tangential_->Stiffness(kin.overlap_m, kin.effective_radius_m);
  const double gamma_t = damping_->TangentialCoefficient(k_t, m_eff);
  Vec3 f_t = -k_t * xi - gamma_t * v_t;
  const double f_t_limit = tangential_->Friction() * std::max(f_n, 0.0);
  const double f_t_magnitude = f_t.norm();
  if (f_t_magnitude > f_t_limit) {
    f_t *= (f_t_magnitude > 0.0 ? f_t_limit / f_t_magnitude : 0.0);
    xi = k_t > 0.0 ? Vec3(-(f_t + gamma_t * v_t) / k_t) : Vec3::Zero();
    result.sliding = true;
  }
  result.tangential_stiffness_n_m = k_t;

  result.force_on_i_n = f_n * n + f_t;
  // Tangential force acts at the contact point: arm -a_i n from i, +a_j n from j.
  const Vec3 n_cross_ft = n.cross(f_t);
  const Vec3 rolling_torque = rolling_->Torque(kin, spring.stiffness_n_m, f_n, dt_s, history);
  result.torque_on_i_n_m = -kin.arm_i_m * n_cross_ft + rolling_torque;
  result.torque_on_j_n_m = -kin.arm_j_m * n_cross_ft - rolling_torque;
  return result;
}

}  // namespace gonogo::dem
