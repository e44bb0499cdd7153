#include "solvers/dem/contact_model.h"

#include <algorithm>
#include <cmath>
#include <typeinfo>
#include <utility>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::dem {

namespace {
using units::kPi;

// x^e for x >= 0, with fast paths for the exponents EEPA is used with (1, 1.5, 2).
double Power(double x, double e) {
  if (e == 1.5) return x * std::sqrt(x);
  if (e == 1.0) return x;
  if (e == 2.0) return x * x;
  return std::pow(x, e);
}
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

HertzNormal::HertzNormal(const MaterialParams& material)
    : effective_modulus_pa_(material.EffectiveModulusPa()) {}

NormalResponse HertzNormal::Evaluate(double overlap_m, double effective_radius_m) const {
  // F_n = 4/3 E* sqrt(r_e) d^{3/2}, k_n = 2 E* sqrt(r_e d) (Johnson 1985, sec. 4.2).
  const double sqrt_rd = std::sqrt(effective_radius_m * overlap_m);
  const double stiffness_n_m = 2.0 * effective_modulus_pa_ * sqrt_rd;
  return {4.0 / 3.0 * effective_modulus_pa_ * sqrt_rd * overlap_m, stiffness_n_m, stiffness_n_m};
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

void EepaParams::Validate() const {
  Require(std::isfinite(shear_modulus_pa) && shear_modulus_pa > 0.0, "shear_modulus_pa",
          "must be positive");
  Require(poisson_ratio >= 0.0 && poisson_ratio < 0.5, "poisson_ratio", "must be in [0, 0.5)");
  Require(std::isfinite(density_kg_m3) && density_kg_m3 > 0.0, "density_kg_m3", "must be positive");
  Require(restitution > 0.0 && restitution <= 1.0, "restitution", "must be in (0, 1]");
  Require(friction >= 0.0 && std::isfinite(friction), "friction", "must be >= 0");
  Require(rolling_friction >= 0.0 && std::isfinite(rolling_friction), "rolling_friction",
          "must be >= 0");
  Require(rolling_stiffness >= 0.0 && std::isfinite(rolling_stiffness), "rolling_stiffness",
          "must be >= 0");
  Require(pull_off_force_n <= 0.0 && std::isfinite(pull_off_force_n), "pull_off_force_n",
          "must be <= 0 (an attraction, EDEM's sign)");
  Require(surface_energy_j_m2 >= 0.0 && std::isfinite(surface_energy_j_m2), "surface_energy_j_m2",
          "must be >= 0");
  Require(plasticity_ratio >= 0.0 && plasticity_ratio < 1.0, "plasticity_ratio",
          "must be in [0, 1)");
  // Exponents below 1 would make the branch stiffness infinite at d = 0.
  Require(slope_exponent >= 1.0 && std::isfinite(slope_exponent), "slope_exponent", "must be >= 1");
  Require(tensile_exponent >= 1.0 && std::isfinite(tensile_exponent), "tensile_exponent",
          "must be >= 1");
  Require(tangential_stiffness_multiplier > 0.0 && std::isfinite(tangential_stiffness_multiplier),
          "tangential_stiffness_multiplier", "must be positive");
  Require(loading_stiffness_n_m_pow_n >= 0.0 && std::isfinite(loading_stiffness_n_m_pow_n),
          "loading_stiffness_n_m_pow_n", "must be >= 0 (0 = from shear_modulus_pa)");
  // The Hertz-equivalent k1 = 4/3 E* sqrt(r_e) has the units of k1 only for n = 3/2.
  Require(loading_stiffness_n_m_pow_n > 0.0 || slope_exponent == 1.5, "slope_exponent",
          "must be 1.5 when k1 comes from shear_modulus_pa; else set loading_stiffness_n_m_pow_n");
}

MaterialParams EepaParams::Material() const {
  MaterialParams material;
  material.youngs_modulus_pa = YoungsModulusPa();
  material.poisson_ratio = poisson_ratio;
  material.density_kg_m3 = density_kg_m3;
  material.friction = friction;
  material.rolling_stiffness = rolling_stiffness;
  material.rolling_limit = rolling_friction;
  material.restitution = restitution;
  return material;
}

EepaParams Seed001EepaSoil(const std::string& name) {
  // Seed 001 Table 3 ("Input simulation parameters of soil models"; also
  // shared/reference/soils_dem_eepa.csv). Particle size 10 mm in both soils.
  EepaParams soil;
  if (name == "2NS_sand") {
    soil.density_kg_m3 = 2500.0;
    soil.shear_modulus_pa = 5.0e6;
    soil.poisson_ratio = 0.4;
    soil.restitution = 0.6;
    soil.friction = 0.5;
    soil.rolling_friction = 0.01;
    soil.pull_off_force_n = -60.0;
    soil.surface_energy_j_m2 = 0.0;
    soil.plasticity_ratio = 0.5;
    soil.slope_exponent = 1.5;
    soil.tensile_exponent = 1.5;
    soil.tangential_stiffness_multiplier = 0.67;
  } else if (name == "FGS") {
    soil.density_kg_m3 = 2500.0;
    soil.shear_modulus_pa = 5.0e8;
    soil.poisson_ratio = 0.25;
    soil.restitution = 0.6;
    soil.friction = 0.5;
    soil.rolling_friction = 0.01;
    soil.pull_off_force_n = -2.0;
    soil.surface_energy_j_m2 = 7.0;
    soil.plasticity_ratio = 0.9;
    soil.slope_exponent = 1.5;
    soil.tensile_exponent = 1.5;
    soil.tangential_stiffness_multiplier = 0.67;
  } else {
    throw InputError("soil", "unknown seed 001 soil '" + name + "' (2NS_sand, FGS)");
  }
  soil.rolling_stiffness = 2.25;         // not in Table 3: Ai et al. (2011) 3D prefactor
  soil.loading_stiffness_n_m_pow_n = 0;  // k1 from G and nu (Hertz-equivalent)
  return soil;
}

EepaNormal::EepaNormal(const EepaParams& params)
    : params_(params),
      plastic_overlap_factor_(std::pow(params.plasticity_ratio, 1.0 / params.slope_exponent)) {
  params_.Validate();
}

double EepaNormal::LoadingStiffness(double effective_radius_m) const {
  // EDEM sets k1 from G and nu as Hertz does: F = 4/3 E* sqrt(r_e) d^{3/2} on first loading.
  if (params_.loading_stiffness_n_m_pow_n > 0.0) return params_.loading_stiffness_n_m_pow_n;
  return 4.0 / 3.0 * params_.EffectiveModulusPa() * std::sqrt(effective_radius_m);
}

double EepaNormal::LoadingBranchStiffness(double overlap_m, double effective_radius_m) const {
  if (overlap_m <= 0.0) return 0.0;
  const double n = params_.slope_exponent;
  return n * LoadingStiffness(effective_radius_m) * Power(overlap_m, n) / overlap_m;
}

EepaNormal::Branches EepaNormal::BranchesFor(double max_overlap_m,
                                             double effective_radius_m) const {
  Branches b;
  const double n = params_.slope_exponent;
  b.k1 = LoadingStiffness(effective_radius_m);
  b.k2 = b.k1 / (1.0 - params_.plasticity_ratio);  // lambda_p = 1 - k1/k2
  // d_p = (1 - k1/k2)^{1/n} d_max, so d_p^n = lambda_p d_max^n.
  b.plastic_overlap_pow_n = params_.plasticity_ratio * Power(max_overlap_m, n);
  // (E5) Pull below f0, 3/2 pi Delta_gamma a_p, a_p the radius of the circle in which the two
  // undeformed spheres meet at the plastic overlap d_p: a_p^2 = 2 r_e d_p to first order in
  // d_p / r (LIGGGHTS normal_model_edinburgh.h takes it exactly from r_i and r_j).
  const double plastic_overlap_m = plastic_overlap_factor_ * max_overlap_m;
  double pull_n = 1.5 * kPi * params_.surface_energy_j_m2 *
                  std::sqrt(2.0 * effective_radius_m * plastic_overlap_m);
  // (E6) The unloading line reaches f_min = f0 - pull at d_min^n = d_p^n - pull / k2; a pull
  // above half of the line's pull at separation, k2 d_p^n / 2, is capped there with d_min = d_p / 2
  // (as LIGGGHTS does), so d_min > 0 always.
  const double pull_cap_n = 0.5 * b.k2 * b.plastic_overlap_pow_n;
  b.pull_capped = pull_n > pull_cap_n;
  if (b.pull_capped) {
    pull_n = pull_cap_n;
    b.min_overlap_pow_n = Power(0.5 * plastic_overlap_m, n);
  } else {
    b.min_overlap_pow_n = b.plastic_overlap_pow_n - pull_n / b.k2;
  }
  // (E7) The adhesive branch f0 - k_adh d^chi passes through (d_min, f0 - pull).
  b.k_adh = pull_n > 0.0 ? pull_n / Power(b.min_overlap_pow_n, params_.tensile_exponent / n) : 0.0;
  return b;
}

NormalResponse EepaNormal::Force(double overlap_m, double max_overlap_m,
                                 double effective_radius_m) const {
  return Force(overlap_m, max_overlap_m, max_overlap_m, effective_radius_m);
}

NormalResponse EepaNormal::Force(double overlap_m, double max_overlap_m, double line_max_overlap_m,
                                 double effective_radius_m) const {
  return ForceOnBranch(overlap_m, max_overlap_m, line_max_overlap_m, effective_radius_m).response;
}

EepaNormal::BranchResponse EepaNormal::ForceOnBranch(double overlap_m, double max_overlap_m,
                                                     double line_max_overlap_m,
                                                     double effective_radius_m) const {
  if (overlap_m <= 0.0) return {{}, Branch::kLoading};
  const double n = params_.slope_exponent, chi = params_.tensile_exponent;
  const double f0 = params_.pull_off_force_n;
  max_overlap_m = std::max(max_overlap_m, overlap_m);
  line_max_overlap_m = std::min(line_max_overlap_m, max_overlap_m);
  // The adhesive branch belongs to the largest flattening, d_max; the k2 line to d_L.
  const Branches b = BranchesFor(max_overlap_m, effective_radius_m);
  const double line_plastic_pow_n = params_.plasticity_ratio * Power(line_max_overlap_m, n);
  const double d_pow_n = Power(overlap_m, n);
  const double loading_stiffness_n_m = n * b.k1 * d_pow_n / overlap_m;
  // Loading f0 + k1 d^n: on the virgin curve (d >= d_L) or above the k2 line.
  const double loading_n = b.k1 * d_pow_n;
  const double unloading_n = b.k2 * (d_pow_n - line_plastic_pow_n);
  if (overlap_m >= line_max_overlap_m || loading_n <= unloading_n) {
    return {{f0 + loading_n, loading_stiffness_n_m, loading_stiffness_n_m}, Branch::kLoading};
  }
  // Unloading/reloading f0 + k2 (d^n - d_p^n) down to the adhesive branch f0 - k_adh d^chi.
  const double d_pow_chi = Power(overlap_m, chi);
  const double adhesive_n = -b.k_adh * d_pow_chi;
  if (unloading_n >= adhesive_n) {
    return {{f0 + unloading_n, n * b.k2 * d_pow_n / overlap_m, loading_stiffness_n_m},
            Branch::kLine};
  }
  return {{f0 + adhesive_n, -chi * b.k_adh * d_pow_chi / overlap_m, loading_stiffness_n_m},
          Branch::kAdhesive};
}

double EepaNormal::UnloadingEnergyJ(double overlap_m, double max_overlap_m,
                                    double effective_radius_m) const {
  return UnloadingEnergyJ(overlap_m, max_overlap_m, max_overlap_m, effective_radius_m);
}

double EepaNormal::UnloadingEnergyJ(double overlap_m, double max_overlap_m,
                                    double line_max_overlap_m, double effective_radius_m) const {
  if (overlap_m <= 0.0) return 0.0;
  const double n = params_.slope_exponent, chi = params_.tensile_exponent;
  const double f0 = params_.pull_off_force_n;
  max_overlap_m = std::max(max_overlap_m, overlap_m);
  line_max_overlap_m = std::clamp(line_max_overlap_m, overlap_m, max_overlap_m);
  const Branches b = BranchesFor(max_overlap_m, effective_radius_m);
  const double line_plastic_pow_n = params_.plasticity_ratio * Power(line_max_overlap_m, n);
  // Antiderivative of the unloading line k2 (s^n - d_p^n).
  auto unloading_j = [&](double s) {
    return b.k2 * (Power(s, n + 1.0) / (n + 1.0) - line_plastic_pow_n * s);
  };
  // Adhesive branch -k_adh s^chi below the crossing s_x, the line above it.
  const double crossing_m =
      CrossingOverlapM(b, line_plastic_pow_n, line_max_overlap_m < max_overlap_m);
  const double s = std::min(overlap_m, crossing_m);
  double energy_j = f0 * overlap_m - b.k_adh * Power(s, chi + 1.0) / (chi + 1.0);
  if (overlap_m > crossing_m) energy_j += unloading_j(overlap_m) - unloading_j(crossing_m);
  return energy_j;
}

double EepaNormal::CrossingOverlapM(const Branches& b, double line_plastic_pow_n,
                                    bool lower_line) const {
  const double n = params_.slope_exponent, chi = params_.tensile_exponent;
  // On the line of d_max with an uncapped pull the two meet at d_min by construction (E6, E7).
  if (!lower_line && !b.pull_capped) return std::pow(b.min_overlap_pow_n, 1.0 / n);
  // Otherwise s_x solves k2 (s^n - d_p^n) + k_adh s^chi = 0, whose left side rises with s from
  // -k2 d_p^n <= 0 at s = 0 to k_adh d_p^chi >= 0 at s = d_p (bisection).
  double low_m = 0.0, high_m = std::pow(line_plastic_pow_n, 1.0 / n);
  for (int i = 0; i < 200 && high_m - low_m > 1e-15 * high_m; ++i) {
    const double mid_m = 0.5 * (low_m + high_m);
    const double gap_n =
        b.k2 * (Power(mid_m, n) - line_plastic_pow_n) + b.k_adh * Power(mid_m, chi);
    (gap_n < 0.0 ? low_m : high_m) = mid_m;
  }
  return 0.5 * (low_m + high_m);
}

double EepaNormal::MinimumForceN(double max_overlap_m, double effective_radius_m) const {
  const Branches b = BranchesFor(max_overlap_m, effective_radius_m);
  // F = f0 + max(rising line, falling adhesive branch) is lowest where they cross: at d_min,
  // f0 - pull, unless the pull was capped (then the line crosses the branch above d_min).
  const double crossing_m = CrossingOverlapM(b, b.plastic_overlap_pow_n, false);
  return params_.pull_off_force_n - b.k_adh * Power(crossing_m, params_.tensile_exponent);
}

NormalResponse EepaNormal::Evaluate(double overlap_m, double effective_radius_m) const {
  return Force(overlap_m, overlap_m, effective_radius_m);
}

double EepaNormal::ElasticEnergyJ(double overlap_m, double effective_radius_m) const {
  return UnloadingEnergyJ(overlap_m, overlap_m, effective_radius_m);
}

NormalResponse EepaNormal::EvaluateWithHistory(double overlap_m, double effective_radius_m,
                                               ContactHistory& history) const {
  history.max_overlap_m = std::max(history.max_overlap_m, overlap_m);
  double& line_max_overlap_m = history.line_max_overlap_m;
  const BranchResponse r =
      ForceOnBranch(overlap_m, history.max_overlap_m, line_max_overlap_m, effective_radius_m);
  if (r.branch == Branch::kLoading) {
    line_max_overlap_m = std::max(line_max_overlap_m, overlap_m);
  } else if (r.branch == Branch::kAdhesive && r.response.force_n < params_.pull_off_force_n) {
    // Reloading from here follows the k2 line through (d, F), parallel to the first (seed 001
    // sec. 5.2): k2 (d^n - lambda_p d_L^n) = -k_adh d^chi, so
    // d_L^n = (d^n + (f0 - F) / k2) / lambda_p. The pull f0 - F > 0 implies lambda_p > 0.
    const double n = params_.slope_exponent;
    const double k2 = LoadingStiffness(effective_radius_m) / (1.0 - params_.plasticity_ratio);
    const double line_pow_n =
        (Power(overlap_m, n) + (params_.pull_off_force_n - r.response.force_n) / k2) /
        params_.plasticity_ratio;
    line_max_overlap_m = std::min(line_max_overlap_m, std::pow(line_pow_n, 1.0 / n));
  }
  return r.response;
}

double EepaNormal::ElasticEnergyWithHistoryJ(double overlap_m, double effective_radius_m,
                                             const ContactHistory& history) const {
  return UnloadingEnergyJ(overlap_m, history.max_overlap_m,
                          std::max(history.line_max_overlap_m, overlap_m), effective_radius_m);
}

EepaTangential::EepaTangential(const EepaParams& params)
    : normal_(params),
      multiplier_(params.tangential_stiffness_multiplier),
      friction_(params.friction) {}

double EepaTangential::Stiffness(double overlap_m, double effective_radius_m) const {
  // k_t = m_t n k1 d^{n-1}: the multiplier times the loading-branch stiffness.
  if (overlap_m <= 0.0) return 0.0;
  return multiplier_ * normal_.LoadingBranchStiffness(overlap_m, effective_radius_m);
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
  // The seed 000 set gets the fused path (exact types only: a subclass may change the law).
  const auto* hertz = dynamic_cast<const HertzNormal*>(normal_.get());
  const auto* restitution = dynamic_cast<const RestitutionDamping*>(damping_.get());
  const bool undamped = dynamic_cast<const ZeroDamping*>(damping_.get()) != nullptr;
  const auto* mindlin = dynamic_cast<const MindlinTangential*>(tangential_.get());
  const auto* spring = dynamic_cast<const ElasticPlasticRolling*>(rolling_.get());
  const bool free_rolling = dynamic_cast<const NoRolling*>(rolling_.get()) != nullptr;
  if (hertz && typeid(*normal_) == typeid(HertzNormal) && mindlin &&
      typeid(*tangential_) == typeid(MindlinTangential) &&
      ((restitution && typeid(*damping_) == typeid(RestitutionDamping)) ||
       (undamped && typeid(*damping_) == typeid(ZeroDamping))) &&
      ((spring && typeid(*rolling_) == typeid(ElasticPlasticRolling)) ||
       (free_rolling && typeid(*rolling_) == typeid(NoRolling)))) {
    fused_.enabled = true;
    fused_.two_e_star_pa = 2.0 * hertz->effective_modulus_pa();
    fused_.tangential_factor_pa = mindlin->StiffnessFactorPa();
    const double damping = restitution ? -2.0 * std::sqrt(5.0 / 6.0) * restitution->beta() : 0.0;
    fused_.normal_damping = damping;
    fused_.tangential_damping =
        restitution && restitution->tangential()
            ? damping * std::sqrt(fused_.tangential_factor_pa / fused_.two_e_star_pa)
            : 0.0;
    fused_.friction = mindlin->Friction();
    fused_.rolling = spring != nullptr;
    if (spring) {
      fused_.rolling_stiffness = spring->beta() * spring->eta() * spring->eta();
      fused_.rolling_limit = spring->eta();
    }
  }
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

ContactModel ContactModel::Eepa(const EepaParams& params) {
  params.Validate();
  std::shared_ptr<const DampingModel> damping;
  if (params.restitution < 1.0) {
    damping = std::make_shared<RestitutionDamping>(params.restitution, true);
  } else {
    damping = std::make_shared<ZeroDamping>();
  }
  std::shared_ptr<const RollingModel> rolling;
  if (params.rolling_stiffness > 0.0 && params.rolling_friction > 0.0) {
    rolling =
        std::make_shared<ElasticPlasticRolling>(params.rolling_stiffness, params.rolling_friction);
  } else {
    rolling = std::make_shared<NoRolling>();
  }
  return ContactModel(std::make_shared<EepaNormal>(params), damping,
                      std::make_shared<EepaTangential>(params), rolling);
}

ContactResult ContactModel::EvaluateGeneral(const ContactKinematics& kin, double dt_s,
                                            ContactHistory& history) const {
  ContactResult result;
  const Vec3& n = kin.normal;
  const double m_eff = kin.effective_mass_kg;

  // Normal: spring (which may advance the history) plus dashpot on the normal relative velocity
  // v_n (< 0 approaching); the dashpot scales with the loading-branch stiffness.
  const NormalResponse spring =
      normal_->EvaluateWithHistory(kin.overlap_m, kin.effective_radius_m, history);
  const double v_n = kin.contact_velocity_m_s.dot(n);
  const double gamma_n = damping_->NormalCoefficient(spring.loading_stiffness_n_m, m_eff);
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
  const Vec3 rolling_torque =
      rolling_->Torque(kin, spring.loading_stiffness_n_m, f_n, dt_s, history);
  result.torque_on_i_n_m = -kin.arm_i_m * n_cross_ft + rolling_torque;
  result.torque_on_j_n_m = -kin.arm_j_m * n_cross_ft - rolling_torque;
  return result;
}

}  // namespace gonogo::dem
