// One material point driven along a laboratory path through the constitutive seam
// (solvers/material/constitutive.h), whatever answers there: a return map, a DE RVE or a network.
//
// A step prescribes, per Voigt component (xx yy zz yz xz xy, engineering shears), either the
// strain increment or the stress to reach; the stress-controlled components are found by Newton's
// method on the model's own tangent,
//   delta_eps_s <- delta_eps_s - (D_ss)^-1 (sigma_s(delta_eps) - sigma_s_target),
// each iteration a trial update from the committed state (nothing is committed until the step
// converges), as a servo-controlled laboratory cell holds its confining stress. The first guess
// of the held components is the last step's, when it held the same ones (zero otherwise), so
// that a model is tried near where the path goes (a surrogate is asked what it was trained on). A prescribed spin
// (the skew part of the displacement-gradient increment) lets a step be a true simple shear.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"
#include "solvers/material/kinematics.h"

namespace gonogo::ann {

using material::Matrix3;
using material::Vector6;

struct MixedStep {
  // Per Voigt component: true, its stress is held at stress_target_pa; false, its strain
  // increment is strain_increment.
  std::array<bool, 6> stress_controlled{};
  Vector6 strain_increment = Vector6::Zero();   // engineering shears (gamma = 2 eps)
  Vector6 stress_target_pa = Vector6::Zero();   // Cauchy, tension positive, Pa
  Matrix3 spin_increment = Matrix3::Zero();     // skew part added to the increment
};

struct DriverOptions {
  // A stress-controlled component has converged when it is within
  // max(relative_tolerance x the largest |target|, absolute_tolerance_pa) of its target.
  double relative_tolerance = 1e-4;
  double absolute_tolerance_pa = 1.0;
  int max_iterations = 25;
  void Validate(const std::string& field_prefix) const;
};

// Reads what a history records of a state beyond the stress (void ratio, coordination ...); the
// names are fixed per recorder, the values per state.
struct InternalVariables {
  std::vector<std::string> names;
  std::function<std::vector<double>(const material::MaterialState&)> read;
};

// `all` narrowed to `names`, in that order (no reader at all for no names). Throws
// InputError(field, "'<name>' is not <what> (<the names all reads>)") for a name it does not read.
InternalVariables Narrowed(const InternalVariables& all, const std::vector<std::string>& names,
                           const std::string& field, const std::string& what);

class MaterialPointDriver {
 public:
  // Starts from the model's InitialState() and the stress of a zero increment on it.
  MaterialPointDriver(const material::ConstitutiveModel& model, DriverOptions options = {});

  // One step; on success the state is committed and the applied displacement-gradient increment
  // returned. Throws NumericalError naming the step's reason (the model's failure, or no
  // convergence within max_iterations) and leaves the committed state as it was.
  Matrix3 Step(const MixedStep& step);

  const Matrix3& stress_pa() const { return stress_pa_; }
  const material::MaterialState& state() const { return *committed_; }
  int iterations_last_step() const { return iterations_; }

 private:
  material::PointResponse TryIncrement(const Matrix3& increment, bool want_tangent) const;

  // The last converged step's control and strain increment: the first guess of the held
  // components when the next step holds the same ones (a continuing path moves as it did).
  std::array<bool, 6> last_controlled_{};
  Vector6 last_strain_ = Vector6::Zero();

  const material::ConstitutiveModel& model_;
  DriverOptions options_;
  std::unique_ptr<material::MaterialState> committed_;
  Matrix3 stress_pa_ = Matrix3::Zero();
  int iterations_ = 0;
};

// The displacement-gradient increment of a Voigt strain increment (engineering shears) plus a
// skew spin: dH = DisplacementGradientForStrain(eps) + spin.
Matrix3 IncrementOf(const Vector6& strain_increment, const Matrix3& spin_increment);

}  // namespace gonogo::ann
