#include "solvers/ann/lab_paths.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "solvers/common/errors.h"

namespace gonogo::ann {
namespace {

constexpr int kXx = 0, kYy = 1, kZz = 2, kXz = 4;

struct NamedPath {
  LabPath path;
  const char* name;
};
constexpr NamedPath kPaths[] = {{LabPath::kIsotropic, "isotropic"},
                                {LabPath::kTriaxial, "triaxial"},
                                {LabPath::kSimpleShear, "simple-shear"},
                                {LabPath::kUnloadReload, "unload-reload"},
                                {LabPath::kRandomWalk, "random-walk"}};

// Records what a driver does; a failed step ends the history (stopped_reason) and every later
// Apply is a no-op returning false.
class Recorder {
 public:
  Recorder(MaterialPointDriver& driver, const InternalVariables& internal, StrainHistory* history)
      : driver_(driver), internal_(internal), history_(history) {
    history_->initial_stress_pa = driver.stress_pa();
    history_->internal_variable_names = internal.names;
    if (internal.read) history_->initial_internal_variables = internal.read(driver.state());
  }
  bool Apply(const MixedStep& step) {
    if (!history_->stopped_reason.empty()) return false;
    try {
      const Matrix3 increment = driver_.Step(step);
      history_->increments.push_back(increment);
      history_->stresses_pa.push_back(material::StressToVoigt(driver_.stress_pa()));
      if (internal_.read) history_->internal_variables.push_back(internal_.read(driver_.state()));
      return true;
    } catch (const NumericalError& e) {
      history_->stopped_reason =
          "step " + std::to_string(history_->steps() + 1) + ": " + e.what();
      return false;
    }
  }

 private:
  MaterialPointDriver& driver_;
  const InternalVariables& internal_;
  StrainHistory* history_;
};

// A step with the normal stresses xx and yy held at -pressure (tension positive) and the axial
// strain increment given, no shear.
MixedStep TriaxialStep(double pressure_pa, double axial_strain_increment) {
  MixedStep step;
  step.stress_controlled[kXx] = step.stress_controlled[kYy] = true;
  step.stress_target_pa[kXx] = step.stress_target_pa[kYy] = -pressure_pa;
  step.strain_increment[kZz] = axial_strain_increment;
  return step;
}

}  // namespace

std::string LabPathName(LabPath path) {
  for (const NamedPath& named : kPaths) {
    if (named.path == path) return named.name;
  }
  return "unknown";
}

LabPath ParseLabPath(const std::string& name, const std::string& field) {
  std::string known;
  for (const NamedPath& named : kPaths) {
    if (name == named.name) return named.path;
    known += std::string(known.empty() ? "" : ", ") + named.name;
  }
  throw InputError(field, "unknown path '" + name + "'; known: " + known);
}

std::vector<LabPath> AllLabPaths() {
  std::vector<LabPath> paths;
  for (const NamedPath& named : kPaths) paths.push_back(named.path);
  return paths;
}

void LabPathSpec::Validate(const std::string& field_prefix) const {
  if (!(pressure_pa > 0 && std::isfinite(pressure_pa))) {
    throw InputError(field_prefix + "pressure_pa", "must be a positive number of Pa");
  }
  if (!(max_strain > 0 && max_strain <= 0.5)) {
    throw InputError(field_prefix + "max_strain", "must be in (0, 0.5]");
  }
  if (steps < 1 || steps > 100000) {
    throw InputError(field_prefix + "steps", "must be in [1, 100000]");
  }
  if (settle_steps < 1 || settle_steps > 1000) {
    throw InputError(field_prefix + "settle_steps", "must be in [1, 1000]");
  }
  if (!(walk_step_strain > 0 && walk_step_strain <= max_strain)) {
    throw InputError(field_prefix + "walk_step_strain", "must be in (0, max_strain]");
  }
  if (!(walk_persistence >= 0 && walk_persistence < 1)) {
    throw InputError(field_prefix + "walk_persistence", "must be in [0, 1)");
  }
}

StrainHistory RunLabPath(const material::ConstitutiveModel& model, const LabPathSpec& spec,
                         const DriverOptions& options, const InternalVariables& internal) {
  spec.Validate("path.");
  MaterialPointDriver driver(model, options);
  StrainHistory history;
  Recorder recorder(driver, internal, &history);

  // Settling: the normal stresses from where the model starts to -pressure, linearly; no shear.
  const Vector6 start = material::StressToVoigt(driver.stress_pa());
  for (int k = 1; k <= spec.settle_steps; ++k) {
    MixedStep step;
    const double fraction = static_cast<double>(k) / spec.settle_steps;
    for (int c : {kXx, kYy, kZz}) {
      step.stress_controlled[c] = true;
      step.stress_target_pa[c] = start[c] + fraction * (-spec.pressure_pa - start[c]);
    }
    recorder.Apply(step);
  }

  const double per_step = spec.max_strain / spec.steps;
  switch (spec.path) {
    case LabPath::kIsotropic: {
      MixedStep step;
      for (int c : {kXx, kYy, kZz}) step.strain_increment[c] = -per_step / 3;
      for (int k = 0; k < spec.steps; ++k) recorder.Apply(step);
      for (int c : {kXx, kYy, kZz}) step.strain_increment[c] = per_step / 3;
      for (int k = 0; k < std::max(1, spec.steps / 2); ++k) recorder.Apply(step);
      break;
    }
    case LabPath::kTriaxial:
      for (int k = 0; k < spec.steps; ++k) {
        recorder.Apply(TriaxialStep(spec.pressure_pa, -per_step));
      }
      break;
    case LabPath::kSimpleShear: {
      MixedStep step;
      step.stress_controlled[kZz] = true;
      step.stress_target_pa[kZz] = -spec.pressure_pa;
      step.strain_increment[kXz] = per_step;  // engineering: gamma_xz
      step.spin_increment(0, 2) = 0.5 * per_step;
      step.spin_increment(2, 0) = -0.5 * per_step;
      for (int k = 0; k < spec.steps; ++k) recorder.Apply(step);
      break;
    }
    case LabPath::kUnloadReload: {
      const int loading = std::max(1, spec.steps / 3);
      const int unloading = std::max(1, spec.steps / 6);
      const int reloading = std::max(1, spec.steps - loading - unloading);
      for (int k = 0; k < loading; ++k) {
        recorder.Apply(TriaxialStep(spec.pressure_pa, -0.5 * spec.max_strain / loading));
      }
      for (int k = 0; k < unloading; ++k) {
        recorder.Apply(TriaxialStep(spec.pressure_pa, 0.25 * spec.max_strain / unloading));
      }
      for (int k = 0; k < reloading; ++k) {
        recorder.Apply(TriaxialStep(spec.pressure_pa, -0.75 * spec.max_strain / reloading));
      }
      break;
    }
    case LabPath::kRandomWalk: {
      std::mt19937_64 random(spec.seed);
      std::normal_distribution<double> normal(0.0, 1.0);
      const double rho = spec.walk_persistence, fresh = std::sqrt(1 - rho * rho);
      Vector6 walked = Vector6::Zero();
      Vector6 direction = Vector6::Zero();  // g_k of the header's AR(1) process
      for (int k = 0; k < spec.steps; ++k) {
        for (int c = 0; c < 6; ++c) direction[c] = rho * direction[c] + fresh * normal(random);
        MixedStep step;
        step.strain_increment = spec.walk_step_strain * direction / direction.norm();
        for (int c : {kXx, kYy, kZz}) step.strain_increment[c] -= spec.walk_step_strain / 12;
        for (int c = 0; c < 6; ++c) {
          if (std::abs(walked[c] + step.strain_increment[c]) > spec.max_strain) {
            step.strain_increment[c] = -step.strain_increment[c];
            direction[c] = -direction[c];  // a persistent walk turns back from the bound
          }
        }
        if (!recorder.Apply(step)) break;
        walked += step.strain_increment;
      }
      break;
    }
  }
  return history;
}

}  // namespace gonogo::ann
