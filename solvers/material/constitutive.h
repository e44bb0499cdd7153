// The scale-bridging seam (ARCHITECTURE section 4, the seeds' "VUMAT"): the finite-element solver
// hands a batch of strain increments with their committed states down and gets Cauchy stresses,
// optional tangents, new states and a status back. It never knows what answers at a point: a
// return map, a periodic DE RVE or a network.
//
// Conventions for every model:
// - Stress is Cauchy, in Pa, tension positive (soil-mechanics output flips the sign, not this
//   seam).
// - An increment is the displacement-gradient increment dH = d(du)/dx on the configuration at
//   the start of the increment; its symmetric part is the strain increment, its skew part the
//   rotation increment. A model that only needs small strain uses sym(dH).
// - Tangents are 6 x 6 Voigt matrices dsigma/deps, order xx yy zz yz xz xy, engineering shear
//   strains (gamma = 2 eps), in Pa.
// - A committed state is never changed in place: on failure the response carries no new state,
//   so the caller can cut the step and retry from the committed one.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace gonogo::material {

using Matrix3 = Eigen::Matrix3d;
using Voigt6x6 = Eigen::Matrix<double, 6, 6>;

// Small-strain moduli of a fresh point: what a solver's stable time step and hourglass stiffness
// are estimated from.
struct ElasticModuli {
  double bulk_pa = 0;
  double shear_pa = 0;
};

class MaterialPointStore;  // point_store.h

// What a model keeps at one integration point between increments.
class MaterialState {
 public:
  virtual ~MaterialState() = default;
  virtual std::unique_ptr<MaterialState> Clone() const = 0;
  // Compact bytes from which the model's RestoreState rebuilds the state (for checkpoints and for
  // moving a point to another rank).
  virtual std::string Serialize() const = 0;
};

enum class UpdateStatus {
  kOk,
  kFailed,  // no new state; `reason` says why (too large an increment, a cell too distorted ...)
};

struct PointIncrement {
  Matrix3 displacement_gradient_increment = Matrix3::Zero();
  const MaterialState* committed = nullptr;
};

struct PointResponse {
  UpdateStatus status = UpdateStatus::kFailed;
  std::string reason;
  std::unique_ptr<MaterialState> state;  // set only when status is kOk
  Matrix3 stress_pa = Matrix3::Zero();
  bool has_tangent = false;
  Voigt6x6 tangent_pa = Voigt6x6::Zero();
};

class ConstitutiveModel {
 public:
  virtual ~ConstitutiveModel() = default;
  virtual std::string Name() const = 0;
  // The state of a fresh point and its stress.
  virtual std::unique_ptr<MaterialState> InitialState() const = 0;
  virtual std::unique_ptr<MaterialState> RestoreState(const std::string& bytes) const = 0;
  // One response per increment, in order. Points are independent, so a model may run them in
  // parallel; the results do not depend on how the batch is split.
  virtual std::vector<PointResponse> Update(const std::vector<PointIncrement>& increments,
                                            bool want_tangent) const = 0;
  // Small-strain moduli of a fresh point, for a solver's stable time step and hourglass stiffness.
  // Default: from the tangent D of a zero increment on InitialState(): K = (sum of the upper-left
  // 3 x 3 of D) / 9, G = mean of the three shear diagonal terms D(3,3), D(4,4), D(5,5). Throws
  // std::logic_error when the model fails that update or gives no tangent.
  virtual ElasticModuli InitialElasticModuli() const;
  // The store a solver keeps this model's points in (point_store.h): trial states it commits or
  // discards, addressed by handle. Default: a LocalPointStore over Update, which refers to this
  // model (so the model must outlive it). A model whose states live elsewhere (other ranks, an
  // RVE server) returns its own store.
  virtual std::unique_ptr<MaterialPointStore> MakePointStore() const;
};

// Helpers for implementations.

// Runs `update_one` over the batch on OpenMP threads with a static schedule. Each point writes
// only its own response, so the results do not depend on the thread count. An exception thrown by
// `update_one` becomes a kFailed response whose reason is its message.
std::vector<PointResponse> UpdateEachPoint(
    const std::vector<PointIncrement>& increments,
    const std::function<PointResponse(const PointIncrement&)>& update_one);

// The stress of `state` as `model` answers it: a zero increment, not committed. Throws
// gonogo::NumericalError("<what>: ...") when the model refuses that increment.
Matrix3 StressOfState(const ConstitutiveModel& model, const MaterialState& state,
                      const std::string& what);

// `count` doubles as raw bytes (host byte order), for Serialize().
std::string PackDoubles(const double* values, std::size_t count);
// The inverse, for RestoreState(): throws gonogo::InputError(field, ...) when `bytes` does not
// hold exactly `count` doubles or one of them is not finite.
std::vector<double> UnpackDoubles(const std::string& bytes, std::size_t count,
                                  const std::string& field);

}  // namespace gonogo::material
