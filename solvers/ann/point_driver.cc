#include "solvers/ann/point_driver.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::ann {

void DriverOptions::Validate(const std::string& field_prefix) const {
  if (!(relative_tolerance > 0 && relative_tolerance < 1)) {
    throw InputError(field_prefix + "relative_tolerance", "must be in (0, 1)");
  }
  if (!(absolute_tolerance_pa > 0 && std::isfinite(absolute_tolerance_pa))) {
    throw InputError(field_prefix + "absolute_tolerance_pa", "must be a positive number of Pa");
  }
  if (max_iterations < 1) {
    throw InputError(field_prefix + "max_iterations", "must be at least 1");
  }
}

InternalVariables Narrowed(const InternalVariables& all, const std::vector<std::string>& names,
                           const std::string& field, const std::string& what) {
  std::vector<std::size_t> columns;
  for (const std::string& name : names) {
    const auto found = std::find(all.names.begin(), all.names.end(), name);
    if (found == all.names.end()) {
      std::string known;
      for (const std::string& read : all.names) known += (known.empty() ? "" : ", ") + read;
      throw InputError(field, "'" + name + "' is not " + what + " (" + known + ")");
    }
    columns.push_back(static_cast<std::size_t>(found - all.names.begin()));
  }
  InternalVariables narrowed;
  if (names.empty()) return narrowed;
  narrowed.names = names;
  narrowed.read = [read = all.read, columns](const material::MaterialState& state) {
    const std::vector<double> values = read(state);
    std::vector<double> chosen;
    for (std::size_t column : columns) chosen.push_back(values.at(column));
    return chosen;
  };
  return narrowed;
}

Matrix3 IncrementOf(const Vector6& strain_increment, const Matrix3& spin_increment) {
  return material::DisplacementGradientForStrain(material::VoigtToStrain(strain_increment)) +
         spin_increment;
}

MaterialPointDriver::MaterialPointDriver(const material::ConstitutiveModel& model,
                                         DriverOptions options)
    : model_(model), options_(options), committed_(model.InitialState()) {
  options_.Validate("driver.");
  material::PointResponse start = TryIncrement(Matrix3::Zero(), false);
  if (start.status != material::UpdateStatus::kOk) {
    throw NumericalError(model_.Name() + " point: a zero increment on the initial state failed: " +
                         start.reason);
  }
  stress_pa_ = start.stress_pa;
}

material::PointResponse MaterialPointDriver::TryIncrement(const Matrix3& increment,
                                                          bool want_tangent) const {
  material::PointIncrement point;
  point.displacement_gradient_increment = increment;
  point.committed = committed_.get();
  std::vector<material::PointResponse> responses = model_.Update({point}, want_tangent);
  return std::move(responses.at(0));
}

Matrix3 MaterialPointDriver::Step(const MixedStep& step) {
  std::vector<int> held;
  double largest_target = 0;
  for (int c = 0; c < 6; ++c) {
    if (!step.stress_controlled[c]) continue;
    held.push_back(c);
    largest_target = std::max(largest_target, std::abs(step.stress_target_pa[c]));
  }
  const double tolerance =
      std::max(options_.relative_tolerance * largest_target, options_.absolute_tolerance_pa);
  const int free = static_cast<int>(held.size());
  Vector6 strain = step.strain_increment;
  const bool continuing = step.stress_controlled == last_controlled_;
  for (int c : held) strain[c] = continuing ? last_strain_[c] : 0;

  std::string last_reason = "no iteration";
  for (iterations_ = 1; iterations_ <= options_.max_iterations; ++iterations_) {
    const Matrix3 increment = IncrementOf(strain, step.spin_increment);
    material::PointResponse response = TryIncrement(increment, free > 0);
    if (response.status != material::UpdateStatus::kOk) {
      throw NumericalError(model_.Name() + " point: " + response.reason);
    }
    const Vector6 stress = material::StressToVoigt(response.stress_pa);
    Eigen::VectorXd residual(free);
    for (int k = 0; k < free; ++k) residual[k] = stress[held[k]] - step.stress_target_pa[held[k]];
    if (free == 0 || residual.cwiseAbs().maxCoeff() <= tolerance) {
      committed_ = std::move(response.state);
      stress_pa_ = response.stress_pa;
      last_controlled_ = step.stress_controlled;
      last_strain_ = strain;
      return increment;
    }
    if (!response.has_tangent) {
      throw NumericalError(model_.Name() + " point: a stress-controlled step needs the tangent, "
                           "which the model did not give");
    }
    Eigen::MatrixXd held_tangent(free, free);
    for (int i = 0; i < free; ++i) {
      for (int j = 0; j < free; ++j) held_tangent(i, j) = response.tangent_pa(held[i], held[j]);
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(held_tangent);
    if (!lu.isInvertible()) {
      throw NumericalError(model_.Name() + " point: the tangent of the stress-controlled "
                           "components is singular (no stiffness to hold the stress with)");
    }
    const Eigen::VectorXd correction = lu.solve(residual);
    for (int k = 0; k < free; ++k) strain[held[k]] -= correction[k];
    last_reason = "stress off its target by " + std::to_string(residual.cwiseAbs().maxCoeff()) +
                  " Pa (tolerance " + std::to_string(tolerance) + " Pa)";
  }
  iterations_ = options_.max_iterations;
  throw NumericalError(model_.Name() + " point: a stress-controlled step did not converge in " +
                       std::to_string(options_.max_iterations) + " iterations: " + last_reason);
}

}  // namespace gonogo::ann
