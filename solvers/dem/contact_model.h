// Sphere-sphere (and sphere-plane) contact law split into sub-models: normal, damping, tangential,
// rolling. A new law is one class deriving from one of the four interfaces; ContactModel combines
// them and owns the per-contact history update. Equations and sources: solvers/dem/README.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

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
  double force_n = 0.0;        // elastic normal force F_n(d_n)
  double stiffness_n_m = 0.0;  // k_n = dF_n / dd_n
};

// Elastic normal law F_n(d_n).
class NormalModel {
 public:
  virtual ~NormalModel() = default;
  virtual NormalResponse Evaluate(double overlap_m, double effective_radius_m) const = 0;
  // Stored elastic energy U(d_n) = integral of F_n, for energy balances.
  virtual double ElasticEnergyJ(double overlap_m, double effective_radius_m) const = 0;
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

  // Forces for one contact with overlap > 0; advances `history` by dt_s.
  ContactResult Evaluate(const ContactKinematics& kin, double dt_s, ContactHistory& history) const;

  const NormalModel& normal() const { return *normal_; }

 private:
  std::shared_ptr<const NormalModel> normal_;
  std::shared_ptr<const DampingModel> damping_;
  std::shared_ptr<const TangentialModel> tangential_;
  std::shared_ptr<const RollingModel> rolling_;
};

// Rotates a stored history vector onto the plane normal to `normal`, keeping its length (the
// LAMMPS/LIGGGHTS practice for shear history when the contact plane turns).
void ProjectOntoContactPlane(const Vec3& normal, Vec3& stored);

}  // namespace gonogo::dem
