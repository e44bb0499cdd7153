#include "solvers/ann/path_recorder.h"

#include <algorithm>
#include <stdexcept>

#include "solvers/common/errors.h"

namespace gonogo::ann {

struct PathRecorder::Step {
  Matrix3 increment = Matrix3::Zero();
  Vector6 stress_pa = Vector6::Zero();
  std::vector<double> internal_variables;
  std::shared_ptr<const Step> previous;
  ~Step() {  // unlinks its chain iteratively (no deep recursion on long paths)
    std::shared_ptr<const Step> next = std::move(previous);
    while (next && next.use_count() == 1) {
      std::shared_ptr<const Step> tail = std::move(const_cast<Step&>(*next).previous);
      next = std::move(tail);
    }
  }
};

namespace {

class RecordedState : public material::MaterialState {
 public:
  std::unique_ptr<material::MaterialState> Clone() const override {
    auto copy = std::make_unique<RecordedState>();
    copy->inner = inner->Clone();
    copy->point = point;
    copy->path = path;
    return copy;
  }
  std::string Serialize() const override { return inner->Serialize(); }

  std::unique_ptr<material::MaterialState> inner;
  std::int64_t point = 0;  // < 0: not recorded
  std::shared_ptr<const PathRecorder::Step> path;
};

}  // namespace

PathRecorder::PathRecorder(std::shared_ptr<const material::ConstitutiveModel> inner,
                           InternalVariables internal)
    : inner_(std::move(inner)), internal_(std::move(internal)) {
  if (inner_ == nullptr) throw InputError("inner", "a model to record is required");
}

std::unique_ptr<material::MaterialState> PathRecorder::Wrap(
    std::unique_ptr<material::MaterialState> inner) const {
  const Matrix3 start_pa =
      material::StressOfState(*inner_, *inner, "recorded model, a point's start");
  std::vector<double> start_internal;
  if (internal_.read) start_internal = internal_.read(*inner);
  auto state = std::make_unique<RecordedState>();
  state->inner = std::move(inner);
  std::lock_guard<std::mutex> lock(mutex_);
  state->point = next_point_++;
  initial_stress_pa_[state->point] = start_pa;
  if (internal_.read) initial_internal_[state->point] = std::move(start_internal);
  return state;
}

std::unique_ptr<material::MaterialState> PathRecorder::InitialState() const {
  return Wrap(inner_->InitialState());
}

std::unique_ptr<material::MaterialState> PathRecorder::RestoreState(const std::string& bytes) const {
  return Wrap(inner_->RestoreState(bytes));
}

std::unique_ptr<material::MaterialState> PathRecorder::RestoreUnrecorded(
    const std::string& bytes) const {
  auto state = std::make_unique<RecordedState>();
  state->inner = inner_->RestoreState(bytes);
  state->point = -1;
  return state;
}

const material::MaterialState& PathRecorder::Inner(const material::MaterialState& recorded) {
  return *static_cast<const RecordedState&>(recorded).inner;
}

material::ElasticModuli PathRecorder::InitialElasticModuli() const {
  return inner_->InitialElasticModuli();
}

std::vector<material::PointResponse> PathRecorder::Update(
    const std::vector<material::PointIncrement>& increments, bool want_tangent) const {
  std::vector<material::PointIncrement> inner_increments(increments.size());
  for (std::size_t i = 0; i < increments.size(); ++i) {
    const auto& committed = static_cast<const RecordedState&>(*increments[i].committed);
    inner_increments[i] = {increments[i].displacement_gradient_increment, committed.inner.get()};
  }
  std::vector<material::PointResponse> responses = inner_->Update(inner_increments, want_tangent);
  std::vector<std::pair<std::int64_t, std::shared_ptr<const Step>>> recorded;
  for (std::size_t i = 0; i < increments.size(); ++i) {
    if (responses[i].status != material::UpdateStatus::kOk) continue;
    const auto& committed = static_cast<const RecordedState&>(*increments[i].committed);
    if (committed.point < 0) {
      auto next = std::make_unique<RecordedState>();
      next->inner = std::move(responses[i].state);
      next->point = committed.point;
      responses[i].state = std::move(next);
      continue;
    }
    auto step = std::make_shared<Step>();
    step->increment = increments[i].displacement_gradient_increment;
    step->stress_pa = material::StressToVoigt(responses[i].stress_pa);
    if (internal_.read) step->internal_variables = internal_.read(*responses[i].state);
    step->previous = committed.path;
    auto next = std::make_unique<RecordedState>();
    next->inner = std::move(responses[i].state);
    next->point = committed.point;
    next->path = step;
    responses[i].state = std::move(next);
    recorded.emplace_back(committed.point, std::move(step));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [point, step] : recorded) newest_[point] = std::move(step);
  return responses;
}

std::vector<StrainHistory> PathRecorder::Histories() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StrainHistory> histories;
  for (const auto& [point, newest] : newest_) {
    StrainHistory history;
    history.initial_stress_pa = initial_stress_pa_.at(point);
    if (internal_.read) {
      history.internal_variable_names = internal_.names;
      history.initial_internal_variables = initial_internal_.at(point);
    }
    for (const Step* step = newest.get(); step != nullptr; step = step->previous.get()) {
      history.increments.push_back(step->increment);
      history.stresses_pa.push_back(step->stress_pa);
      if (internal_.read) history.internal_variables.push_back(step->internal_variables);
    }
    std::reverse(history.increments.begin(), history.increments.end());
    std::reverse(history.stresses_pa.begin(), history.stresses_pa.end());
    std::reverse(history.internal_variables.begin(), history.internal_variables.end());
    histories.push_back(std::move(history));
  }
  return histories;
}

}  // namespace gonogo::ann
