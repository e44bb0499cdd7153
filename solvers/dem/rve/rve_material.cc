#include "solvers/dem/rve/rve_material.h"

#include <exception>
#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::dem::rve {

void RveMaterialParams::Validate() const {
  rve.Validate();
  Require(min_steps_per_increment >= 1, "min_steps_per_increment", "must be >= 1");
  Require(relax_steps >= 0, "relax_steps", "must be >= 0");
  Require(max_strain_increment > 0.0 && max_strain_increment <= 0.1, "max_strain_increment",
          "must be in (0, 0.1]");
  Require(batch_threads >= 1, "batch_threads", "must be >= 1");
}

std::unique_ptr<material::MaterialState> RveState::Clone() const {
  return std::make_unique<RveState>(rve_);
}

RveMaterial::RveMaterial(const RveMaterialParams& params)
    : RveMaterial(params, Rve::Generate((params.Validate(), params.rve))) {}

RveMaterial::RveMaterial(const RveMaterialParams& params, Rve initial)
    : params_(params), initial_(std::move(initial)) {
  params_.Validate();
}

std::unique_ptr<material::MaterialState> RveMaterial::InitialState() const {
  return std::make_unique<RveState>(initial_);
}

std::unique_ptr<material::MaterialState> RveMaterial::RestoreState(const std::string& bytes) const {
  return std::make_unique<RveState>(Rve::Restore(bytes));
}

material::PointResponse RveMaterial::UpdateOne(const material::PointIncrement& increment,
                                               bool want_tangent) const {
  material::PointResponse response;
  const auto* committed = dynamic_cast<const RveState*>(increment.committed);
  if (committed == nullptr) {
    response.reason = "committed state is missing or not an RVE state";
    return response;
  }
  const material::Matrix3& increment_gradient = increment.displacement_gradient_increment;
  if (!increment_gradient.allFinite()) {
    response.reason = "displacement_gradient_increment is not finite";
    return response;
  }
  const std::string problem = Rve::IncrementProblem(increment_gradient);
  if (!problem.empty()) {
    response.reason = "displacement_gradient_increment: " + problem;
    return response;
  }
  // The stretch alone counts: a rigid rotation of any size strains nothing.
  const double largest = Rve::IncrementStrain(increment_gradient);
  if (largest > params_.max_strain_increment) {
    response.reason = "strain increment " + std::to_string(largest) + " exceeds " +
                      std::to_string(params_.max_strain_increment) + "; cut the step";
    return response;
  }
  try {
    // The committed RVE is copied, never advanced in place.
    auto next = std::make_unique<RveState>(committed->rve());
    next->rve().ApplyIncrement(increment_gradient, params_.min_steps_per_increment,
                               params_.relax_steps);
    response.stress_pa = next->rve().StressPa();
    if (!response.stress_pa.allFinite()) {
      response.reason = "the RVE stress is not finite";
      return response;
    }
    if (want_tangent) {
      response.tangent_pa = next->rve().TangentPa();
      response.has_tangent = true;
    }
    response.state = std::move(next);
    response.status = material::UpdateStatus::kOk;
  } catch (const std::exception& error) {
    // E.g. a cell sheared so far that its faces are closer than three grain diameters.
    response.reason = error.what();
  }
  return response;
}

std::vector<material::PointResponse> RveMaterial::Update(
    const std::vector<material::PointIncrement>& increments, bool want_tangent) const {
  const int count = static_cast<int>(increments.size());
  std::vector<material::PointResponse> responses(count);
#pragma omp parallel for schedule(dynamic, 1) num_threads(params_.batch_threads)
  for (int k = 0; k < count; ++k) responses[k] = UpdateOne(increments[k], want_tangent);
  return responses;
}

}  // namespace gonogo::dem::rve
