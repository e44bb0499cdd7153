// Sphere-sphere (and sphere-plane) contact law split into sub-models: normal, damping, tangential,
// rolling. A new law is one class deriving from one of the four interfaces; ContactModel combines
// them and owns the per-contact history update. Equations and sources: solvers/dem/README.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

namespace gonogo::dem {

using Vec3 = Eigen::Vector3d;

// Elastic and frictional constants of one grain material (same material on both sides of a
// contact). Validate() throws InputError naming the offending field.
struct MaterialParams {
  double youngs_modulus_pa = 1.5e9;  // E
  double poisson_ratio = 0.293;      // nu, in [0, 0.5)
  double density_kg_m3 = 2650.0;     // rho
  double friction = 0.452;           // mu, Coulomb sliding coefficient
  double rolling_stiffness = 2.25;   // beta, dimensionless prefactor of k_r
  double rolling_limit = 0.99;       // eta, rolling friction coefficient
  double restitution = 1.0;          // e in (0, 1]; 1 gives zero damping

  void Validate() const;
  double ShearModulusPa() const { return youngs_modulus_pa / (2.0 * (1.0 + poisson_ratio)); }
  // E* of a same-material pair: 1/E* = 2 (1 - nu^2) / E (Johnson 1985, Contact Mechanics,
  // sec. 4.2).
  double EffectiveModulusPa() const {
    return youngs_modulus_pa / (2.0 * (1.0 - poisson_ratio * poisson_ratio));
  }
};

// Per-contact state carried across steps and neighbour-list rebuilds.
struct ContactHistory {
  Vec3 tangential_displacement_m = Vec3::Zero();  // xi, stored tangential spring elongation
  Vec3 rolling_angle_rad = Vec3::Zero();          // theta_r, accumulated relative rolling rotation
  double max_overlap_m = 0.0;  // delta_max, largest overlap of this contact (EEPA plasticity)
  // EEPA: the overlap at which the unloading/reloading line the contact is on meets the virgin
  // loading curve. Equals max_overlap_m until the contact reloads from the adhesive branch, which
  // moves it onto a parallel line that meets the virgin curve sooner.
  double line_max_overlap_m = 0.0;
};

// Kinematics of one contact at the current step. `normal` points from body j to body i.
struct ContactKinematics {
  Vec3 normal = Vec3::UnitZ();
  double overlap_m = 0.0;                    // d_n > 0 in contact
  double effective_radius_m = 0.0;           // r_e = r_i r_j / (r_i + r_j); r_i for a plane
  double effective_mass_kg = 0.0;            // m* = m_i m_j / (m_i + m_j); m_i for a plane
  double arm_i_m = 0.0;                      // centre of i to contact point
  double arm_j_m = 0.0;                      // centre of j to contact point (0 for a plane)
  Vec3 contact_velocity_m_s = Vec3::Zero();  // velocity of i relative to j at the contact point
  Vec3 relative_spin_rad_s = Vec3::Zero();   // omega_i - omega_j
};

// What a contact applies. Force on j is -force_on_i_n; torques include the tangential arm.
struct ContactResult {
  Vec3 force_on_i_n = Vec3::Zero();
  Vec3 torque_on_i_n_m = Vec3::Zero();
  Vec3 torque_on_j_n_m = Vec3::Zero();
  double normal_force_n = 0.0;  // elastic + damping, along `normal`
  double normal_stiffness_n_m = 0.0;
  double tangential_stiffness_n_m = 0.0;
  bool sliding = false;  // the tangential force is at the Coulomb limit
};

struct NormalResponse {
  double force_n = 0.0;        // elastic normal force F_n(d_n), compression positive
  double stiffness_n_m = 0.0;  // k_n = dF_n / dd_n on the branch the contact is on (may be < 0)
  // Stiffness of the first (virgin) loading branch at d_n, > 0. The dashpot and the rolling
  // spring scale with it. Equal to stiffness_n_m for an elastic law such as Hertz.
  double loading_stiffness_n_m = 0.0;
};

// Normal law F_n(d_n), elastic or history dependent. An elastic law implements the two
// history-free functions; a history-dependent one (EEPA) also overrides the two *WithHistory
// functions, which ContactModel calls with the contact's own history.
class NormalModel {
 public:
  virtual ~NormalModel() = default;
  // Force at overlap d_n > 0 for a contact loaded monotonically to d_n (no history).
  virtual NormalResponse Evaluate(double overlap_m, double effective_radius_m) const = 0;
  // Stored elastic energy U(d_n) = integral of F_n from 0, for energy balances.
  virtual double ElasticEnergyJ(double overlap_m, double effective_radius_m) const = 0;

  // Force at overlap d_n > 0 for this contact; first advances `history` to include d_n.
  // Default: the law has no history, so Evaluate(overlap_m, effective_radius_m).
  virtual NormalResponse EvaluateWithHistory(double overlap_m, double effective_radius_m,
                                             ContactHistory& history) const {
    (void)history;
    return Evaluate(overlap_m, effective_radius_m);
  }
  // Energy returned if the contact unloaded from d_n to separation along its current unloading
  // branch (the integral of F_n from 0 to d_n on that branch). Default: ElasticEnergyJ.
  virtual double ElasticEnergyWithHistoryJ(double overlap_m, double effective_radius_m,
                                           const ContactHistory& history) const {
    (void)history;
    return ElasticEnergyJ(overlap_m, effective_radius_m);
  }
};

// Viscous damping coefficients gamma (N s/m) from the spring stiffness and the effective mass.
class DampingModel {
 public:
  virtual ~DampingModel() = default;
  virtual double NormalCoefficient(double normal_stiffness_n_m, double effective_mass_kg) const = 0;
  virtual double TangentialCoefficient(double tangential_stiffness_n_m,
                                       double effective_mass_kg) const = 0;
};

// Tangential spring stiffness k_t and the Coulomb coefficient; ContactModel applies the history.
class TangentialModel {
 public:
  virtual ~TangentialModel() = default;
  virtual double Stiffness(double overlap_m, double effective_radius_m) const = 0;
  virtual double Friction() const = 0;
};

// Rolling resistance torque on i (torque on j is its negative); updates the rolling history.
class RollingModel {
 public:
  virtual ~RollingModel() = default;
  virtual Vec3 Torque(const ContactKinematics& kin, double normal_stiffness_n_m,
                      double normal_force_n, double dt_s, ContactHistory& history) const = 0;
};

// Hertz, as seed 000 writes it: F_n = 2 E sqrt(r_e d_n) d_n / (3 (1 - nu^2)) = 4/3 E* sqrt(r_e)
// d_n^{3/2} (Johnson 1985, sec. 4.2); k_n = 2 E* sqrt(r_e d_n).
class HertzNormal : public NormalModel {
 public:
  explicit HertzNormal(const MaterialParams& material);
  NormalResponse Evaluate(double overlap_m, double effective_radius_m) const override;
  double ElasticEnergyJ(double overlap_m, double effective_radius_m) const override;
  double effective_modulus_pa() const { return effective_modulus_pa_; }

 private:
  double effective_modulus_pa_;
};

// Tsuji et al. (1992) / LIGGGHTS `model hertz` damping: gamma = -2 sqrt(5/6) beta sqrt(k m*),
// beta = ln e / sqrt(ln^2 e + pi^2), with k = S_n = 2 E* sqrt(r_e d_n) (normal) or S_t (tangent).
class RestitutionDamping : public DampingModel {
 public:
  RestitutionDamping(double restitution, bool tangential);
  double NormalCoefficient(double normal_stiffness_n_m, double effective_mass_kg) const override;
  double TangentialCoefficient(double tangential_stiffness_n_m,
                               double effective_mass_kg) const override;
  static double BetaFromRestitution(double restitution);
  double beta() const { return beta_; }
  bool tangential() const { return tangential_; }

 private:
  double beta_;
  bool tangential_;
};

// No dissipation in the springs.
class ZeroDamping : public DampingModel {
 public:
  double NormalCoefficient(double, double) const override { return 0.0; }
  double TangentialCoefficient(double, double) const override { return 0.0; }
};

// Mindlin (1949) no-slip stiffness as seed 000 writes it: k_t = 4 G sqrt(r_e d_n) / (2 - nu).
class MindlinTangential : public TangentialModel {
 public:
  explicit MindlinTangential(const MaterialParams& material);
  double Stiffness(double overlap_m, double effective_radius_m) const override;
  double Friction() const override { return friction_; }
  // k_t / sqrt(r_e d_n) = 4 G / (2 - nu).
  double StiffnessFactorPa() const { return 4.0 * shear_modulus_pa_ / (2.0 - poisson_ratio_); }

 private:
  double shear_modulus_pa_;
  double poisson_ratio_;
  double friction_;
};

// Elastic-plastic spring (Iwashita & Oda 1998; Ai et al. 2011, model type C without the dashpot,
// as LIGGGHTS `rolling_friction epsd2/epsd3`): k_r = beta k_n eta^2 r_e^2, |M_r| <= eta F_n r_e.
class ElasticPlasticRolling : public RollingModel {
 public:
  ElasticPlasticRolling(double rolling_stiffness, double rolling_limit);
  Vec3 Torque(const ContactKinematics& kin, double normal_stiffness_n_m, double normal_force_n,
              double dt_s, ContactHistory& history) const override;
  double StiffnessNmRad(double normal_stiffness_n_m, double effective_radius_m) const;
  double beta() const { return beta_; }
  double eta() const { return eta_; }

 private:
  double beta_;
  double eta_;
};

// No rolling resistance.
class NoRolling : public RollingModel {
 public:
  Vec3 Torque(const ContactKinematics&, double, double, double, ContactHistory&) const override {
    return Vec3::Zero();
  }
};

// Edinburgh Elasto-Plastic Adhesion (EEPA) parameters of one grain material (Morrissey 2013;
// Thakur et al. 2014; EDEM's EEPA model). Same material on both sides of a contact. Defaults are
// the fine-grained sand (FGS) of seed 001 Table 3. Validate() throws InputError naming the field.
struct EepaParams {
  double shear_modulus_pa = 5.0e8;   // G
  double poisson_ratio = 0.25;       // nu, in [0, 0.5)
  double density_kg_m3 = 2500.0;     // rho
  double restitution = 0.6;          // e in (0, 1]; sets the dashpot (1 = none)
  double friction = 0.5;             // mu, Coulomb sliding coefficient
  double rolling_friction = 0.01;    // eta in |M_r| <= eta F_n r_e
  double rolling_stiffness = 2.25;   // beta in k_r = beta k_n eta^2 r_e^2 (Ai et al. 2011)
  double pull_off_force_n = -2.0;    // f0 <= 0, constant attraction (EDEM sign: negative)
  double surface_energy_j_m2 = 7.0;  // Delta gamma >= 0
  double plasticity_ratio = 0.9;     // lambda_p = 1 - k1/k2, in [0, 1)
  double slope_exponent = 1.5;       // n >= 1, loading and unloading branches
  double tensile_exponent = 1.5;     // chi >= 1, adhesive branch
  double tangential_stiffness_multiplier = 0.67;  // k_t / (loading normal stiffness) > 0
  // k1 in N/m^n. 0 = Hertz-equivalent k1 = 4/3 E* sqrt(r_e) from G and nu (needs n = 1.5).
  double loading_stiffness_n_m_pow_n = 0.0;

  void Validate() const;
  double YoungsModulusPa() const { return 2.0 * shear_modulus_pa * (1.0 + poisson_ratio); }
  // E* of a same-material pair, as MaterialParams::EffectiveModulusPa.
  double EffectiveModulusPa() const {
    return YoungsModulusPa() / (2.0 * (1.0 - poisson_ratio * poisson_ratio));
  }
  // The elastic constants as MaterialParams (for the Rayleigh time step and particle density).
  MaterialParams Material() const;
};

// The two soils of seed 001 Table 3 by name, "2NS_sand" or "FGS". Throws InputError("soil").
EepaParams Seed001EepaSoil(const std::string& name);

// EEPA normal law (Thakur et al. 2014, Granular Matter 16:383, sec. 2; Morrissey 2013). With
// d = d_n, d_max = history.max_overlap_m, d_L = history.line_max_overlap_m <= d_max and
// k2 = k1 / (1 - lambda_p):
//   F = f0 + min(k1 d^n, max(k2 (d^n - d_p^n), -k_adh d^chi)),  d_p^n = lambda_p d_L^n,
// the three branches of the paper in one expression: loading f0 + k1 d^n, unloading/reloading
// f0 + k2 (d^n - d_p^n), adhesive f0 - k_adh d^chi.
// k_adh makes the adhesive branch meet the unloading line of d_max at the minimum force
// f_min = f0 - pull, pull = 3/2 pi Delta_gamma a_p, a_p^2 = 2 r_e d_p(d_max) (the circle in which
// the undeformed spheres meet at d_p), reached at d_min^n = d_p^n - pull / k2, so
// k_adh = pull / d_min^chi; a pull above k2 d_p^n / 2 is capped there with d_min = d_p / 2 (as
// LIGGGHTS' model edinburgh, against which this law is tested).
// A contact that reloads from the adhesive branch does so along the k2 line through its point,
// parallel to the first one (seed 001 sec. 5.2): d_L drops to where that line meets k1 d^n.
// Sources and choices: solvers/dem/README.md.
class EepaNormal : public NormalModel {
 public:
  explicit EepaNormal(const EepaParams& params);
  // Virgin loading, d_max = d_n: f0 + k1 d^n.
  NormalResponse Evaluate(double overlap_m, double effective_radius_m) const override;
  // Integral of F from 0 to d_n on the unloading branch of d_max = d_n.
  double ElasticEnergyJ(double overlap_m, double effective_radius_m) const override;
  // F on the branch of (d_n, d_max, d_L); updates d_max = max(d_max, d_n), d_L = d_n on the
  // virgin curve, and on the adhesive branch d_L to the k2 line through (d_n, F).
  NormalResponse EvaluateWithHistory(double overlap_m, double effective_radius_m,
                                     ContactHistory& history) const override;
  double ElasticEnergyWithHistoryJ(double overlap_m, double effective_radius_m,
                                   const ContactHistory& history) const override;

  // F and dF/dd at overlap d_n <= max_overlap_m of a contact whose largest overlap was
  // max_overlap_m and which is on the k2 line of that overlap; changes nothing.
  NormalResponse Force(double overlap_m, double max_overlap_m, double effective_radius_m) const;
  // The same on the k2 line that meets the virgin curve at line_max_overlap_m <= max_overlap_m.
  NormalResponse Force(double overlap_m, double max_overlap_m, double line_max_overlap_m,
                       double effective_radius_m) const;
  // Integral of F(s, max_overlap_m) for s from 0 to overlap_m <= max_overlap_m.
  double UnloadingEnergyJ(double overlap_m, double max_overlap_m, double effective_radius_m) const;
  // The same along the k2 line of line_max_overlap_m, then the adhesive branch of max_overlap_m.
  double UnloadingEnergyJ(double overlap_m, double max_overlap_m, double line_max_overlap_m,
                          double effective_radius_m) const;
  // k1 in N/m^n for effective radius r_e.
  double LoadingStiffness(double effective_radius_m) const;
  // dF/dd of the loading branch, n k1 d^{n-1} (N/m).
  double LoadingBranchStiffness(double overlap_m, double effective_radius_m) const;
  // Most negative force after loading to max_overlap_m (= f0 without adhesion).
  double MinimumForceN(double max_overlap_m, double effective_radius_m) const;

 private:
  // The branch constants of one contact after loading to d_max.
  struct Branches {
    double k1, k2;                 // N/m^n
    double plastic_overlap_pow_n;  // d_p^n
    double min_overlap_pow_n;      // d_min^n (> 0 when d_p > 0)
    bool pull_capped;              // pull capped at k2 d_p^n / 2, d_min = d_p / 2
    double k_adh;                  // N/m^chi
  };
  Branches BranchesFor(double max_overlap_m, double effective_radius_m) const;
  // Overlap at which the k2 line with plastic overlap^n line_plastic_pow_n meets the adhesive
  // branch of b (lower_line: a line below that of d_max).
  double CrossingOverlapM(const Branches& b, double line_plastic_pow_n, bool lower_line) const;
  enum class Branch { kLoading, kLine, kAdhesive };
  struct BranchResponse {
    NormalResponse response;
    Branch branch;
  };
  BranchResponse ForceOnBranch(double overlap_m, double max_overlap_m, double line_max_overlap_m,
                               double effective_radius_m) const;

  EepaParams params_;
  double plastic_overlap_factor_;  // lambda_p^{1/n}: d_p = lambda_p^{1/n} d_max
};

// EEPA tangential stiffness: k_t = m_t k_load, the multiplier m_t times the normal loading
// stiffness as in EDEM, taken here as the slope of the loading branch k_load = n k1 d^{n-1}
// (= 2 E* sqrt(r_e d), Hertz's S_n, for n = 1.5).
class EepaTangential : public TangentialModel {
 public:
  explicit EepaTangential(const EepaParams& params);
  double Stiffness(double overlap_m, double effective_radius_m) const override;
  double Friction() const override { return friction_; }

 private:
  EepaNormal normal_;
  double multiplier_;
  double friction_;
};

// The four sub-models of one contact law. Immutable after construction; safe to share across
// threads (Evaluate only writes the history it is given).
class ContactModel {
 public:
  ContactModel(std::shared_ptr<const NormalModel> normal,
               std::shared_ptr<const DampingModel> damping,
               std::shared_ptr<const TangentialModel> tangential,
               std::shared_ptr<const RollingModel> rolling);

  // Seed 000 law: Hertz + Mindlin + Coulomb + elastic-plastic rolling, damping from
  // material.restitution (none when it is 1).
  static ContactModel HertzMindlin(const MaterialParams& material);
  // EEPA normal law + EEPA tangential stiffness + Coulomb + elastic-plastic rolling, damping from
  // params.restitution on the loading stiffness (none when it is 1).
  static ContactModel Eepa(const EepaParams& params);

  // Forces for one contact with overlap > 0; advances `history` by dt_s.
  ContactResult Evaluate(const ContactKinematics& kin, double dt_s, ContactHistory& history) const;

  const NormalModel& normal() const { return *normal_; }
  // True when the sub-models are the seed 000 set (Hertz, restitution or no damping, Mindlin,
  // elastic-plastic or no rolling): Evaluate then takes a fused path with one square root for
  // both stiffnesses and one for both dashpots, equal to the general path to round-off.
  bool fused() const { return fused_.enabled; }
  // The general path through the four sub-models, whatever they are (for checking the fused one).
  ContactResult EvaluateGeneral(const ContactKinematics& kin, double dt_s,
                                ContactHistory& history) const;

 private:
  struct FusedHertzMindlin {
    bool enabled = false;
    double two_e_star_pa = 0.0;          // k_n / sqrt(r_e d_n)
    double tangential_factor_pa = 0.0;   // k_t / sqrt(r_e d_n)
    double normal_damping = 0.0;         // gamma_n / sqrt(k_n m*) = -2 sqrt(5/6) beta
    double tangential_damping = 0.0;     // gamma_t / sqrt(k_n m*) = the above sqrt(k_t / k_n)
    double friction = 0.0;
    bool rolling = false;
    double rolling_stiffness = 0.0;      // beta eta^2
    double rolling_limit = 0.0;          // eta
  };
  ContactResult EvaluateFused(const ContactKinematics& kin, double dt_s,
                              ContactHistory& history) const;

  std::shared_ptr<const NormalModel> normal_;
  std::shared_ptr<const DampingModel> damping_;
  std::shared_ptr<const TangentialModel> tangential_;
  std::shared_ptr<const RollingModel> rolling_;
  FusedHertzMindlin fused_;
};

// Rotates a stored history vector onto the plane normal to `normal`, keeping its length (the
// LAMMPS/LIGGGHTS practice for shear history when the contact plane turns). Inline: it runs twice
// per contact per step.
inline void ProjectOntoContactPlane(const Vec3& normal, Vec3& stored) {
  const double normal_part = stored.dot(normal);
  if (normal_part == 0.0) return;
  const double length_sq_before = stored.squaredNorm();
  stored -= normal_part * normal;
  const double length_sq_after = stored.squaredNorm();
  if (length_sq_after > 0.0) stored *= std::sqrt(length_sq_before / length_sq_after);
}

// ProjectOntoContactPlane on two history vectors at once, with the same result bit for bit: the
// two length ratios share one packed division and one packed square root (the divider is the
// bottleneck of the contact law). A vector with no normal part gets the ratio 1 exactly.
inline void ProjectTwoOntoContactPlane(const Vec3& normal, Vec3& first, Vec3& second) {
  const double first_length_sq_before = first.squaredNorm();
  const double second_length_sq_before = second.squaredNorm();
  first -= first.dot(normal) * normal;
  second -= second.dot(normal) * normal;
  const double first_length_sq_after = first.squaredNorm();
  const double second_length_sq_after = second.squaredNorm();
  const Eigen::Array2d before(first_length_sq_before, second_length_sq_before);
  const Eigen::Array2d after(first_length_sq_after > 0.0 ? first_length_sq_after : 1.0,
                             second_length_sq_after > 0.0 ? second_length_sq_after : 1.0);
  const Eigen::Array2d scale = (before / after).sqrt();
  first *= first_length_sq_after > 0.0 ? scale[0] : 1.0;
  second *= second_length_sq_after > 0.0 ? scale[1] : 1.0;
}

// Defined here so that the pair loop inlines the seed 000 contact (the hot path of every step).
inline ContactResult ContactModel::Evaluate(const ContactKinematics& kin, double dt_s,
                                            ContactHistory& history) const {
  return fused_.enabled ? EvaluateFused(kin, dt_s, history) : EvaluateGeneral(kin, dt_s, history);
}

inline ContactResult ContactModel::EvaluateFused(const ContactKinematics& kin, double dt_s,
                                                 ContactHistory& history) const {
  // The general path below with the seed 000 sub-models written out: the same equations
  // (README "Contact law (seed 000)"), sqrt(r_e d_n) and sqrt(k_n m*) taken once.
  ContactResult result;
  const Vec3& n = kin.normal;
  const double root_m = std::sqrt(kin.effective_radius_m * kin.overlap_m);
  const double k_n = fused_.two_e_star_pa * root_m;
  const double elastic_n = (2.0 / 3.0) * k_n * kin.overlap_m;  // 4/3 E* sqrt(r_e) d^{3/2}
  const double root_km = std::sqrt(k_n * kin.effective_mass_kg);
  const double gamma_n = fused_.normal_damping * root_km;
  const double v_n = kin.contact_velocity_m_s.dot(n);
  const double f_n = elastic_n - gamma_n * v_n;
  result.normal_force_n = f_n;
  result.normal_stiffness_n_m = k_n;

  const Vec3 v_t = kin.contact_velocity_m_s - v_n * n;
  Vec3& xi = history.tangential_displacement_m;
  Vec3& theta = history.rolling_angle_rad;
  if (fused_.rolling) {
    ProjectTwoOntoContactPlane(n, xi, theta);
  } else {
    ProjectOntoContactPlane(n, xi);
  }
  xi += v_t * dt_s;
  const double k_t = fused_.tangential_factor_pa * root_m;
  const double gamma_t = fused_.tangential_damping * root_km;
  Vec3 f_t = -k_t * xi - gamma_t * v_t;
  const double f_t_limit = fused_.friction * std::max(f_n, 0.0);
  const double f_t_magnitude_sq = f_t.squaredNorm();
  if (f_t_magnitude_sq > f_t_limit * f_t_limit) {
    const double f_t_magnitude = std::sqrt(f_t_magnitude_sq);
    f_t *= f_t_limit / f_t_magnitude;
    xi = k_t > 0.0 ? Vec3(-(f_t + gamma_t * v_t) / k_t) : Vec3::Zero();
    result.sliding = true;
  }
  result.tangential_stiffness_n_m = k_t;
  result.force_on_i_n = f_n * n + f_t;
  const Vec3 n_cross_ft = n.cross(f_t);
  Vec3 rolling_torque = Vec3::Zero();
  if (fused_.rolling) {
    theta += (kin.relative_spin_rad_s - kin.relative_spin_rad_s.dot(n) * n) * dt_s;
    const double r_e = kin.effective_radius_m;
    const double k_r = fused_.rolling_stiffness * k_n * r_e * r_e;
    rolling_torque = -k_r * theta;
    const double limit = fused_.rolling_limit * std::max(f_n, 0.0) * r_e;
    const double magnitude_sq = rolling_torque.squaredNorm();
    if (magnitude_sq > limit * limit) {
      rolling_torque *= limit / std::sqrt(magnitude_sq);
      theta = k_r > 0.0 ? Vec3(-rolling_torque / k_r) : Vec3::Zero();
    }
  }
  result.torque_on_i_n_m = -kin.arm_i_m * n_cross_ft + rolling_torque;
  result.torque_on_j_n_m = -kin.arm_j_m * n_cross_ft - rolling_torque;
  return result;
}

}  // namespace gonogo::dem
