#include "solvers/dem/rve/rve.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/common/byte_stream.h"

namespace gonogo::dem::rve {

namespace {
using units::kPi;
constexpr char kRveTag[9] = "GNGRVE01";
constexpr int kStiffnessRefreshSteps = 20;
// Servo relaxation time in steps: each step closes 1/kServoSteps of the stress gap, judged with
// the affine contact tangent (stiffer than the relaxed packing, so the servo errs on the slow,
// stable side).
constexpr double kServoSteps = 15.0;
constexpr double kServoFloorStiffnessPa = 1e5;  // a gas has no contact stiffness
constexpr double kEquilibriumRatio = 5e-3;      // unbalanced-force ratio of a settled packing
constexpr double kPressureTolerance = 0.01;
constexpr double kStressTolerance = 0.03;  // each component, of the target pressure
constexpr int kConsolidationStepBudget = 400000;

SimulationParams SimulationParamsFor(const RveParams& params, const MaterialParams& material,
                                     double side_m, double time_step_s) {
  SimulationParams simulation;
  simulation.material = material;
  simulation.box.lo_m = Vec3::Zero();
  simulation.box.hi_m = Vec3::Constant(side_m);
  simulation.box.periodic = {true, true, true};
  simulation.time_step_s = time_step_s;
  simulation.time_step_safety = params.time_step_safety;
  simulation.threads = params.threads;
  return simulation;
}

double MeanPressurePa(const Matrix3& stress_pa) { return -stress_pa.trace() / 3.0; }

// Periodic distance between two points of a cubic cell of side L.
double PeriodicDistanceM(const Vec3& a, const Vec3& b, double side_m) {
  Vec3 delta = a - b;
  for (int d = 0; d < 3; ++d) delta[d] -= side_m * std::round(delta[d] / side_m);
  return delta.norm();
}

void PutParams(ByteWriter& out, const RveParams& p) {
  const MaterialParams& m = p.material;
  for (double v : {m.youngs_modulus_pa, m.poisson_ratio, m.density_kg_m3, m.friction,
                   m.rolling_stiffness, m.rolling_limit, m.restitution, p.mean_radius_m,
                   p.radius_spread, p.initial_solid_fraction, p.consolidation_pressure_pa,
                   p.consolidation_friction, p.time_step_safety, p.max_inertial_number}) {
    out.Put(v);
  }
  out.Put(static_cast<std::int32_t>(p.grain_count));
  out.Put(static_cast<std::uint32_t>(p.seed));
  out.Put(static_cast<std::int32_t>(p.threads));
}

void GetParams(ByteReader& in, RveParams& p) {
  MaterialParams& m = p.material;
  for (double* v : {&m.youngs_modulus_pa, &m.poisson_ratio, &m.density_kg_m3, &m.friction,
                    &m.rolling_stiffness, &m.rolling_limit, &m.restitution, &p.mean_radius_m,
                    &p.radius_spread, &p.initial_solid_fraction, &p.consolidation_pressure_pa,
                    &p.consolidation_friction, &p.time_step_safety, &p.max_inertial_number}) {
    in.Get(*v);
  }
  std::int32_t grains = 0, threads = 0;
  std::uint32_t seed = 0;
  in.Get(grains);
  in.Get(seed);
  in.Get(threads);
  p.grain_count = grains;
  p.seed = seed;
  p.threads = threads;
}
}  // namespace

MaterialParams RveParams::SeedMaterial() {
  MaterialParams material;  // E, nu, mu, beta, eta of seed 000
  material.restitution = 0.5;
  return material;
}

void RveParams::Validate() const {
  material.Validate();
  Require(grain_count >= 20, "grain_count", "must be at least 20");
  Require(std::isfinite(mean_radius_m) && mean_radius_m > 0.0, "mean_radius_m", "must be positive");
  Require(radius_spread >= 0.0 && radius_spread <= 0.5, "radius_spread", "must be in [0, 0.5]");
  Require(initial_solid_fraction > 0.0 && initial_solid_fraction <= 0.4, "initial_solid_fraction",
          "must be in (0, 0.4] (random placement)");
  Require(std::isfinite(consolidation_pressure_pa) && consolidation_pressure_pa > 0.0,
          "consolidation_pressure_pa", "must be positive");
  Require(std::isfinite(consolidation_friction) && consolidation_friction >= 0.0,
          "consolidation_friction", "must be >= 0");
  Require(time_step_safety > 0.0 && time_step_safety <= 1.0, "time_step_safety",
          "must be in (0, 1]");
  Require(std::isfinite(max_inertial_number) && max_inertial_number > 0.0 &&
              max_inertial_number <= 0.1,
          "max_inertial_number", "must be in (0, 0.1]");
  Require(threads >= 1, "threads", "must be >= 1");
}

Rve::Rve(const RveParams& params, std::unique_ptr<Simulation> simulation)
    : params_(params), simulation_(std::move(simulation)) {}

Rve::Rve(const Rve& other)
    : params_(other.params_),
      simulation_(std::make_unique<Simulation>(*other.simulation_)),
      strain_(other.strain_),
      servo_stiffness_pa_(other.servo_stiffness_pa_),
      steps_since_stiffness_(other.steps_since_stiffness_) {}

Rve& Rve::operator=(const Rve& other) {
  if (this != &other) *this = Rve(other);
  return *this;
}

Rve Rve::Generate(const RveParams& params, const std::function<void(double)>& progress) {
  params.Validate();
  // Radii uniform in r_mean (1 +- spread); grains placed at random without overlap in a cube
  // holding the requested solid fraction.
  std::mt19937_64 random(params.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> radii(params.grain_count);
  double solid_volume_m3 = 0.0;
  for (double& r : radii) {
    r = params.mean_radius_m * (1.0 + params.radius_spread * (2.0 * unit(random) - 1.0));
    solid_volume_m3 += 4.0 / 3.0 * kPi * r * r * r;
  }
  // Largest first, so the hard placements happen while the cell is empty.
  std::sort(radii.begin(), radii.end(), std::greater<double>());
  const double side_m = std::cbrt(solid_volume_m3 / params.initial_solid_fraction);
  MaterialParams consolidation_material = params.material;
  consolidation_material.friction = params.consolidation_friction;
  Particles grains;
  for (double r : radii) {
    bool placed = false;
    for (int attempt = 0; attempt < 100000 && !placed; ++attempt) {
      const Vec3 candidate(side_m * unit(random), side_m * unit(random), side_m * unit(random));
      placed = true;
      for (std::size_t g = 0; g < grains.size() && placed; ++g) {
        placed = PeriodicDistanceM(candidate, grains.position_m[g], side_m) >
                 r + grains.radius_m[g];
      }
      if (placed) grains.Add(candidate, Vec3::Zero(), r, params.material.density_kg_m3);
    }
    if (!placed) {
      throw LimitError("initial_solid_fraction",
                       "random placement failed; lower the initial solid fraction");
    }
  }
  auto simulation = std::make_unique<Simulation>(
      SimulationParamsFor(params, consolidation_material, side_m, 0.0), std::move(grains));
  Rve rve(params, std::move(simulation));

  // Isotropic consolidation.
  if (!rve.ServoToIsotropic(params.consolidation_pressure_pa, progress)) {
    throw LimitError("consolidation_pressure_pa",
                     "isotropic consolidation did not settle within the step budget");
  }
  // Same grains, contacts and history under the loading material (its own friction).
  auto loading = std::make_unique<Simulation>(
      SimulationParamsFor(params, params.material, side_m, rve.time_step_s()),
      Particles(rve.simulation_->particles()));
  loading->RestoreState(rve.simulation_->SaveState());
  loading->SetVelocityGradient(Matrix3::Zero());
  Rve consolidated(params, std::move(loading));
  return consolidated;
}

bool Rve::ServoToIsotropic(double target_pa, const std::function<void(double)>& progress) {
  // Every normal stress held at -p and every shear stress at 0 by the servo (a random packing
  // carries some shear stress otherwise; the cell shears a little).
  MixedControl isotropic;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) isotropic.stress_controlled[a][b] = true;
    isotropic.target_stress_pa(a, a) = -target_pa;
  }
  const double start_pa = MeanPressurePa(StressPa());
  for (int step = 0; step < kConsolidationStepBudget; ++step) {
    ServoStep(isotropic);
    if (step % 100 == 99) {
      const Matrix3 stress_pa = StressPa();
      const double pressure_pa = MeanPressurePa(stress_pa);
      const Matrix3 deviation = stress_pa + target_pa * Matrix3::Identity();  // 0 at target
      if (std::abs(pressure_pa - target_pa) < kPressureTolerance * target_pa &&
          deviation.cwiseAbs().maxCoeff() < kStressTolerance * target_pa &&
          simulation_->UnbalancedForceRatio() < kEquilibriumRatio) {
        return true;
      }
    }
    if (progress && step % 1000 == 999) {
      const double span = target_pa - start_pa;
      const double done = span == 0 ? 1.0 : (MeanPressurePa(StressPa()) - start_pa) / span;
      progress(std::min(1.0, std::max(0.0, done)));
    }
  }
  return false;
}

void Rve::SettleIsotropic(double mean_stress_pa) {
  Require(std::isfinite(mean_stress_pa) && mean_stress_pa > 0, "mean_stress_pa",
          "must be a positive pressure, Pa");
  if (!ServoToIsotropic(mean_stress_pa, nullptr)) {
    throw LimitError("mean_stress_pa", "the RVE did not settle at " +
                                           std::to_string(mean_stress_pa) +
                                           " Pa within the step budget");
  }
  simulation_->SetVelocityGradient(Matrix3::Zero());
}

double Rve::StableRate1S() const { return StableRateAt1S(StressPa()); }

double Rve::StableRateAt1S(const Matrix3& stress_pa) const {
  const double pressure_pa = std::max(MeanPressurePa(stress_pa), params_.consolidation_pressure_pa);
  // I = rate d sqrt(rho / p) (GDR MiDi 2004, Eur. Phys. J. E 14, 341).
  return params_.max_inertial_number /
         (2.0 * params_.mean_radius_m *
          std::sqrt(params_.material.density_kg_m3 / pressure_pa));
}

void Rve::ServoStep(const MixedControl& control) {
  if (++steps_since_stiffness_ >= kStiffnessRefreshSteps) {
    servo_stiffness_pa_ = TangentPa();
    steps_since_stiffness_ = 0;
  }
  static constexpr int kVoigt[3][3] = {{0, 5, 4}, {5, 1, 3}, {4, 3, 2}};
  const Matrix3 stress_pa = StressPa();
  const double dt_s = simulation_->time_step_s();
  // A gas (no contact yet) may be compressed ten times faster: nothing inertial to disturb. A
  // held stress may need its axis to move faster than the driven one (dilatancy), hence 3x.
  const double rate_cap_1_s =
      StableRateAt1S(stress_pa) * (simulation_->ContactCount() < params_.grain_count ? 10.0 : 3.0);
  Matrix3 rate_1_s = control.strain_rate_1_s;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      if (!control.stress_controlled[i][j] && !control.stress_controlled[j][i]) continue;
      const int v = kVoigt[i][j];
      const double stiffness_pa = std::max(servo_stiffness_pa_(v, v), kServoFloorStiffnessPa);
      const double gap_pa = control.target_stress_pa(i, j) - stress_pa(i, j);
      // Normal: d(sigma_ii) = D L_ii dt. Shear: d(sigma_ij) = D (L_ij + L_ji) dt.
      double rate = gap_pa / (stiffness_pa * kServoSteps * dt_s) * (i == j ? 1.0 : 0.5);
      rate = std::clamp(rate, -rate_cap_1_s, rate_cap_1_s);
      rate_1_s(i, j) = rate;
      rate_1_s(j, i) = rate;
    }
  }
  simulation_->SetVelocityGradient(rate_1_s);
  simulation_->Step();
  strain_ += 0.5 * (rate_1_s + rate_1_s.transpose()) * dt_s;
}

void Rve::Run(const MixedControl& control, int steps) {
  Require(control.strain_rate_1_s.allFinite() && control.target_stress_pa.allFinite(), "control",
          "rates and target stresses must be finite");
  for (int s = 0; s < steps; ++s) ServoStep(control);
  simulation_->SetVelocityGradient(Matrix3::Zero());
}

std::string Rve::IncrementProblem(const Matrix3& displacement_gradient_increment) {
  if (!displacement_gradient_increment.allFinite()) return "the increment is not finite";
  // A real logarithm of F = I + dH (and so a real root F^(1/n)) exists when no real eigenvalue
  // of F is <= 0 (the principal logarithm; Higham 2008, Functions of Matrices, ch. 1 and 11).
  const Matrix3 deformation = Matrix3::Identity() + displacement_gradient_increment;
  const Eigen::EigenSolver<Matrix3> solver(deformation, false);
  for (int k = 0; k < 3; ++k) {
    const std::complex<double> lambda = solver.eigenvalues()[k];
    const bool real = std::abs(lambda.imag()) <= 1e-12 * std::max(1.0, std::abs(lambda));
    if (real && lambda.real() <= 0.0) {
      return "I + dH has the eigenvalue " + std::to_string(lambda.real()) + " (det " +
             std::to_string(deformation.determinant()) +
             "): no real logarithm; the increment inverts or flattens the cell, or turns it "
             "by half a turn";
    }
  }
  return "";
}

double Rve::IncrementStrain(const Matrix3& displacement_gradient_increment) {
  const Matrix3& dh = displacement_gradient_increment;
  if (dh == dh.transpose()) return dh.cwiseAbs().maxCoeff();  // F = U
  // U = sqrt(F^T F) from the eigen-decomposition of the right Cauchy-Green tensor.
  const Matrix3 deformation = Matrix3::Identity() + dh;
  const Eigen::SelfAdjointEigenSolver<Matrix3> solver(deformation.transpose() * deformation);
  const Matrix3 stretch = solver.eigenvectors() *
                          solver.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                          solver.eigenvectors().transpose();
  return (stretch - Matrix3::Identity()).cwiseAbs().maxCoeff();
}

void Rve::ApplyIncrement(const Matrix3& displacement_gradient_increment, int min_steps,
                         int relax_steps) {
  const std::string problem = IncrementProblem(displacement_gradient_increment);
  Require(problem.empty(), "displacement_gradient_increment", problem);
  const double dt_s = simulation_->time_step_s();
  const Matrix3& dh = displacement_gradient_increment;
  const int steps =
      std::max(std::max(min_steps, 1),
               static_cast<int>(std::ceil(IncrementStrain(dh) / (StableRate1S() * dt_s))));
  // Each step maps the cell by A = F^(1/n) = exp(log(F) / n), F = I + dH, so that the n steps
  // end at exactly F H_0 (a constant L = dH / (n dt) would end at (I + dH / n)^n ~ exp(dH):
  // for a rotation by theta, a cell also shrunk by 1 - cos(theta) across the axis). The engine
  // maps by I + dt L, hence L = (A - I) / dt. A symmetric F takes its root from its
  // eigen-decomposition, exactly symmetric, so that a stretch stays free of spin.
  const Matrix3 identity = Matrix3::Identity();
  Matrix3 step_change = Matrix3::Zero(), log_deformation = Matrix3::Zero();  // A - I, log F
  if (dh == dh.transpose()) {
    if (!dh.isZero(0.0)) {
      // F = V (I + M) V^T from dH = V M V^T: log1p and expm1 keep small strains exact.
      const Eigen::SelfAdjointEigenSolver<Matrix3> solver(dh);
      const Matrix3& v = solver.eigenvectors();
      Eigen::Vector3d log_stretch, root_change;
      for (int k = 0; k < 3; ++k) {
        log_stretch[k] = std::log1p(solver.eigenvalues()[k]);
        root_change[k] = std::expm1(log_stretch[k] / steps);
      }
      log_deformation = v * log_stretch.asDiagonal() * v.transpose();
      step_change = v * root_change.asDiagonal() * v.transpose();
      log_deformation = (0.5 * (log_deformation + log_deformation.transpose())).eval();
      step_change = (0.5 * (step_change + step_change.transpose())).eval();
    }
  } else {
    log_deformation = (identity + dh).log();
    step_change = (log_deformation / steps).exp() - identity;
  }
  const Matrix3 rate_1_s = step_change / dt_s;
  simulation_->SetVelocityGradient(rate_1_s);
  simulation_->Run(steps);
  // Logarithmic strain of the increment; its symmetric part is zero for a rigid rotation.
  strain_ += 0.5 * (log_deformation + log_deformation.transpose());
  simulation_->SetVelocityGradient(Matrix3::Zero());
  simulation_->Run(relax_steps);
}

Matrix3 Rve::StressPa() const {
  const Matrix3 stress = -simulation_->ContactVirialNM() / simulation_->cell().VolumeM3();
  return 0.5 * (stress + stress.transpose());
}

Voigt6x6 Rve::TangentPa() const {
  return simulation_->ContactStiffnessVoigtNM() / simulation_->cell().VolumeM3();
}

RveSnapshot Rve::Snapshot() const {
  RveSnapshot snapshot;
  snapshot.time_s = simulation_->time_s();
  snapshot.strain = strain_;
  snapshot.stress_pa = StressPa();
  snapshot.volume_m3 = simulation_->cell().VolumeM3();
  double solid_m3 = 0.0;
  for (double r : simulation_->particles().radius_m) solid_m3 += 4.0 / 3.0 * kPi * r * r * r;
  snapshot.solid_fraction = solid_m3 / snapshot.volume_m3;
  snapshot.coordination_number =
      2.0 * simulation_->ContactCount() / static_cast<double>(simulation_->particles().size());
  snapshot.fabric = simulation_->ContactFabric();
  snapshot.unbalanced_force_ratio = simulation_->UnbalancedForceRatio();
  return snapshot;
}

std::string Rve::Save() const {
  ByteWriter out;
  out.PutTag(kRveTag);
  PutParams(out, params_);
  out.Put(strain_);
  for (int k = 0; k < 36; ++k) out.Put(servo_stiffness_pa_.data()[k]);
  out.Put(static_cast<std::int32_t>(steps_since_stiffness_));
  out.PutBlob(simulation_->SaveState());
  return out.Take();
}

Rve Rve::Restore(const std::string& bytes, int threads) {
  ByteReader in(bytes);
  in.ExpectTag(kRveTag);
  RveParams params;
  GetParams(in, params);
  if (threads > 0) params.threads = threads;
  params.Validate();
  Matrix3 strain;
  in.Get(strain);
  Voigt6x6 servo_stiffness_pa;
  for (int k = 0; k < 36; ++k) in.Get(servo_stiffness_pa.data()[k]);
  std::int32_t steps_since_stiffness = 0;
  in.Get(steps_since_stiffness);
  std::string state;
  in.GetBlob(state);
  Require(in.AtEnd(), "state", "trailing bytes after the saved RVE");
  // A simulation needs one grain to exist; RestoreState replaces grains, cell and time step.
  Particles single_grain;
  single_grain.Add(Vec3::Zero(), Vec3::Zero(), params.mean_radius_m, params.material.density_kg_m3);
  auto simulation = std::make_unique<Simulation>(
      SimulationParamsFor(params, params.material, 100.0 * params.mean_radius_m, 0.0),
      std::move(single_grain));
  simulation->RestoreState(state);
  Rve rve(params, std::move(simulation));
  rve.strain_ = strain;
  rve.servo_stiffness_pa_ = servo_stiffness_pa;
  rve.steps_since_stiffness_ = steps_since_stiffness;
  return rve;
}

}  // namespace gonogo::dem::rve
