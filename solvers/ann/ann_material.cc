#include "solvers/ann/ann_material.h"

#include <algorithm>
#include <chrono>
#include <functional>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/material/kinematics.h"

namespace gonogo::ann {
namespace {

constexpr char kStateTag[9] = "GNGANN04";
// Read only: without the return's count (03), and without internal variables either (02).
constexpr char kStateTagWithoutReturn[9] = "GNGANN03";
constexpr char kStateTagWithoutInternalVariables[9] = "GNGANN02";

std::shared_ptr<const IncrementNode> Append(std::shared_ptr<const IncrementNode> history,
                                            const Matrix3& increment) {
  auto node = std::make_shared<IncrementNode>();
  node->increment = increment;
  node->count = history ? history->count + 1 : 1;
  node->previous = std::move(history);
  return node;
}

// The state after one increment: the committed state's counters carried on, the increment
// appended to its history and its strain (Voigt, engineering shears) to its accumulated strain.
std::unique_ptr<AnnState> Advance(const AnnState& committed, const Matrix3& increment,
                                  const Vector6& strain_increment, const Matrix3& stress_pa) {
  auto next = std::make_unique<AnnState>();
  next->stress_pa = stress_pa;
  next->accumulated_strain = committed.accumulated_strain + strain_increment;
  next->internal_variables = committed.internal_variables;
  next->history = Append(committed.history, increment);
  next->flags = committed.flags;
  next->fell_back_at_step = committed.fell_back_at_step;
  next->unflagged_on_fallback = committed.unflagged_on_fallback;
  next->origin = committed.origin;
  return next;
}

Vector6 StrainIncrementOf(const Matrix3& increment) {
  return material::StrainToVoigt(material::HughesWinget(increment).strain_increment);
}

// The direction of the last increment the point took (SurrogateInput::previous_direction): zero
// before its first, as at a training path's first step, and zero for a network that does not
// read it (a second strain split per point it would not use).
Vector6 PreviousDirectionOf(const AnnState& committed, const SurrogateEnsemble& ensemble) {
  if (!committed.history || !ensemble.reads_previous_direction()) return Vector6::Zero();
  return IncrementDirection(StrainIncrementOf(committed.history->increment));
}

material::PointResponse Failed(const std::string& reason) {
  material::PointResponse response;
  response.status = material::UpdateStatus::kFailed;
  response.reason = reason;
  return response;
}

}  // namespace

IncrementNode::~IncrementNode() {
  std::shared_ptr<const IncrementNode> next = std::move(previous);
  while (next && next.use_count() == 1) {
    // The last owner: take its tail before it goes, so each node dies with an empty link.
    std::shared_ptr<const IncrementNode> tail =
        std::move(const_cast<IncrementNode&>(*next).previous);
    next = std::move(tail);
  }
}

void FallbackLog::RecordFallback(const Event& event) {
  std::lock_guard<std::mutex> lock(mutex_);
  fallbacks_.push_back(event);
}

void FallbackLog::RecordUnansweredFlag() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++unanswered_flags_;
}

void FallbackLog::RecordNetworkCall(double seconds, std::int64_t points) {
  std::lock_guard<std::mutex> lock(mutex_);
  network_seconds_ += seconds;
  network_point_updates_ += points;
}

void FallbackLog::RecordStressReturns(std::int64_t points) {
  std::lock_guard<std::mutex> lock(mutex_);
  stress_returns_ += points;
}

std::int64_t FallbackLog::stress_returns() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stress_returns_;
}

void FallbackLog::RecordReturn() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++returns_;
}

std::int64_t FallbackLog::returns() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return returns_;
}

void FallbackLog::RecordFallbackSeconds(double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  fallback_seconds_ += seconds;
}

double FallbackLog::network_seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return network_seconds_;
}

std::int64_t FallbackLog::network_point_updates() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return network_point_updates_;
}

double FallbackLog::fallback_seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fallback_seconds_;
}

std::vector<FallbackLog::Event> FallbackLog::fallbacks() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fallbacks_;
}

std::int64_t FallbackLog::unanswered_flags() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return unanswered_flags_;
}

std::vector<Matrix3> AnnState::Increments() const {
  std::vector<Matrix3> increments;
  increments.reserve(static_cast<std::size_t>(steps()));
  for (const IncrementNode* node = history.get(); node != nullptr; node = node->previous.get()) {
    increments.push_back(node->increment);
  }
  std::reverse(increments.begin(), increments.end());
  return increments;
}

std::unique_ptr<material::MaterialState> AnnState::Clone() const {
  auto copy = std::make_unique<AnnState>();
  copy->stress_pa = stress_pa;
  copy->accumulated_strain = accumulated_strain;
  copy->internal_variables = internal_variables;
  copy->history = history;
  copy->flags = flags;
  copy->fallback = fallback ? fallback->Clone() : nullptr;
  copy->fell_back_at_step = fell_back_at_step;
  copy->unflagged_on_fallback = unflagged_on_fallback;
  copy->origin = origin;
  return copy;
}

std::string AnnState::Serialize() const {
  ByteWriter out;
  out.PutTag(kStateTag);
  out.Put(stress_pa);
  for (int c = 0; c < 6; ++c) out.Put(accumulated_strain[c]);
  out.Put(static_cast<std::uint64_t>(internal_variables.size()));
  for (Eigen::Index v = 0; v < internal_variables.size(); ++v) out.Put(internal_variables[v]);
  out.Put(flags);
  out.Put(fell_back_at_step);
  out.Put(unflagged_on_fallback);
  const std::vector<Matrix3> increments = Increments();
  out.Put(static_cast<std::uint64_t>(increments.size()));
  for (const Matrix3& increment : increments) out.Put(increment);
  out.PutBlob(fallback ? fallback->Serialize() : std::string());
  out.PutBlob(origin ? *origin : std::string());
  return out.Take();
}

AnnMaterial::AnnMaterial(std::shared_ptr<const SurrogateEnsemble> ensemble,
                         std::shared_ptr<const material::ConstitutiveModel> fallback,
                         AnnMaterialOptions options)
    : ensemble_(std::move(ensemble)), fallback_(std::move(fallback)), options_(options) {
  if (ensemble_ == nullptr) throw InputError("ensemble", "is required");
  if (options_.fallback_enabled && fallback_ == nullptr) {
    throw InputError("fallback", "a model to fall back to is required while the fallback is on");
  }
  initial_stress_pa_ = options_.initial_stress_pa;
  if (fallback_ != nullptr) {
    // A fresh point starts where the real model's fresh point does.
    initial_stress_pa_ = material::StressOfState(*fallback_, *fallback_->InitialState(),
                                                 "fallback model, its initial state");
  }
  const std::vector<std::string>& carried = ensemble_->carried_variables();
  if (!carried.empty()) {
    if (fallback_ == nullptr || !options_.internal_variables.read) {
      throw InputError("internal_variables",
                       "the model carries internal variables; a point needs the real model and a "
                       "reader of its state to start from");
    }
    carried_reader_ = Narrowed(options_.internal_variables, carried, "internal_variables",
                               "read by the reader of the real state, but the model carries it");
    initial_internal_variables_ = CarriedOf(*fallback_->InitialState());
  }
  if (options_.record_fallback_paths) {
    if (fallback_ == nullptr) {
      throw InputError("record_fallback_paths", "there is no model to fall back to");
    }
    recorder_ = std::make_shared<const PathRecorder>(fallback_, carried_reader_);
  }
  real_ = recorder_ ? recorder_ : fallback_;
}

const material::MaterialState& AnnMaterial::RealStateOf(const material::MaterialState& state) const {
  return recorder_ ? PathRecorder::Inner(state) : state;
}

std::vector<StrainHistory> AnnMaterial::FallbackPaths() const {
  if (!recorder_) return {};
  std::vector<StrainHistory> paths = recorder_->Histories();
  // Longest first, so that a path is compared only with those it could be the start of.
  std::stable_sort(paths.begin(), paths.end(), [](const StrainHistory& a, const StrainHistory& b) {
    return a.steps() > b.steps();
  });
  std::vector<StrainHistory> kept;
  for (StrainHistory& path : paths) {
    const bool start_of_kept = std::any_of(kept.begin(), kept.end(), [&](const StrainHistory& longer) {
      return longer.initial_stress_pa == path.initial_stress_pa &&
             std::equal(path.increments.begin(), path.increments.end(), longer.increments.begin());
    });
    if (!start_of_kept) kept.push_back(std::move(path));
  }
  return kept;
}

Eigen::VectorXd AnnMaterial::CarriedOf(const material::MaterialState& real_state) const {
  if (!carried_reader_.read) return Eigen::VectorXd();
  const std::vector<double> values = carried_reader_.read(real_state);
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

std::unique_ptr<material::MaterialState> AnnMaterial::InitialState() const {
  auto state = std::make_unique<AnnState>();
  state->stress_pa = initial_stress_pa_;
  state->internal_variables = initial_internal_variables_;
  return state;
}

std::unique_ptr<material::MaterialState> AnnMaterial::RestoreState(const std::string& bytes) const {
  auto state = std::make_unique<AnnState>();
  try {
    ByteReader in(bytes);
    const bool without_internal = bytes.compare(0, 8, kStateTagWithoutInternalVariables) == 0;
    const bool without_return =
        without_internal || bytes.compare(0, 8, kStateTagWithoutReturn) == 0;
    in.ExpectTag(without_internal ? kStateTagWithoutInternalVariables
                 : without_return ? kStateTagWithoutReturn
                                  : kStateTag);
    in.Get(state->stress_pa);
    for (int c = 0; c < 6; ++c) in.Get(state->accumulated_strain[c]);
    std::uint64_t carried = 0;
    if (!without_internal) in.Get(carried);
    if (carried != carried_reader_.names.size()) {
      throw InputError("state", "carries " + std::to_string(carried) +
                                    " internal variables, the model " +
                                    std::to_string(carried_reader_.names.size()));
    }
    state->internal_variables.resize(static_cast<Eigen::Index>(carried));
    for (Eigen::Index v = 0; v < state->internal_variables.size(); ++v) {
      in.Get(state->internal_variables[v]);
    }
    in.Get(state->flags);
    in.Get(state->fell_back_at_step);
    if (!without_return) in.Get(state->unflagged_on_fallback);
    std::uint64_t steps = 0;
    in.Get(steps);
    if (steps > bytes.size() / 72) throw InputError("state", "step count larger than the bytes");
    for (std::uint64_t s = 0; s < steps; ++s) {
      Matrix3 increment;
      in.Get(increment);
      state->history = Append(std::move(state->history), increment);
    }
    std::string fallback_bytes, origin_bytes;
    in.GetBlob(fallback_bytes);
    in.GetBlob(origin_bytes);
    if (!in.AtEnd()) throw InputError("state", "trailing bytes");
    if (!origin_bytes.empty()) {
      if (fallback_ == nullptr) throw InputError("state", "a point with an origin and no fallback");
      state->origin = Intern(std::move(origin_bytes));
    }
    if (!fallback_bytes.empty()) {
      if (fallback_ == nullptr) throw InputError("state", "a fallen-back point and no fallback");
      state->fallback = recorder_ ? recorder_->RestoreUnrecorded(fallback_bytes)
                                  : fallback_->RestoreState(fallback_bytes);
    }
  } catch (const InputError& e) {
    throw InputError("material.state", e.what());
  }
  return state;
}

std::shared_ptr<const std::string> AnnMaterial::Intern(std::string bytes) const {
  const std::size_t hash = std::hash<std::string>{}(bytes);
  std::lock_guard<std::mutex> lock(intern_mutex_);
  const auto [first, last] = origins_.equal_range(hash);
  for (auto it = first; it != last; ++it) {
    if (*it->second == bytes) return it->second;
  }
  auto shared = std::make_shared<const std::string>(std::move(bytes));
  origins_.emplace(hash, shared);
  return shared;
}

std::unique_ptr<AnnState> AnnMaterial::StateFrom(const std::string& real_state_bytes) const {
  if (fallback_ == nullptr) {
    throw InputError("material.state", "a point cannot start from a real state without its model");
  }
  const std::unique_ptr<material::MaterialState> real = fallback_->RestoreState(real_state_bytes);
  auto state = std::make_unique<AnnState>();
  state->stress_pa =
      material::StressOfState(*fallback_, *real, "fallback model, a point's starting state");
  state->internal_variables = CarriedOf(*real);
  state->origin = Intern(real_state_bytes);
  return state;
}

material::PointResponse AnnMaterial::FallBack(const AnnState& committed, const Matrix3& increment,
                                              bool want_tangent) const {
  std::unique_ptr<material::MaterialState> state =
      committed.origin ? real_->RestoreState(*committed.origin) : real_->InitialState();
  const std::vector<Matrix3> history = committed.Increments();
  for (std::size_t s = 0; s < history.size(); ++s) {
    material::PointIncrement replay;
    replay.displacement_gradient_increment = history[s];
    replay.committed = state.get();
    std::vector<material::PointResponse> step = real_->Update({replay}, false);
    if (step.at(0).status != material::UpdateStatus::kOk) {
      return Failed("fallback: replaying the point's step " + std::to_string(s + 1) + " of " +
                    std::to_string(history.size()) + " failed: " + step.at(0).reason);
    }
    state = std::move(step.at(0).state);
  }
  material::PointIncrement now;
  now.displacement_gradient_increment = increment;
  now.committed = state.get();
  std::vector<material::PointResponse> answer = real_->Update({now}, want_tangent);
  material::PointResponse response = std::move(answer.at(0));
  if (response.status != material::UpdateStatus::kOk) {
    response.reason = "fallback: " + response.reason;
    return response;
  }
  std::unique_ptr<AnnState> next =
      Advance(committed, increment, StrainIncrementOf(increment), response.stress_pa);
  next->flags = committed.flags + 1;
  next->fallback = std::move(response.state);
  next->fell_back_at_step = committed.steps();
  next->unflagged_on_fallback = 0;
  response.state = std::move(next);
  return response;
}

std::vector<bool> AnnMaterial::WouldFlag(const std::vector<material::PointIncrement>& increments,
                                         const std::vector<std::size_t>& on_fallback) const {
  std::vector<bool> flags(on_fallback.size(), true);
  if (options_.return_after_steps <= 0) return flags;
  std::vector<SurrogateInput> inputs;
  std::vector<std::size_t> asked;  // indices into on_fallback
  for (std::size_t k = 0; k < on_fallback.size(); ++k) {
    const std::size_t i = on_fallback[k];
    const auto& committed = static_cast<const AnnState&>(*increments[i].committed);
    const material::IncrementKinematics split =
        material::HughesWinget(increments[i].displacement_gradient_increment);
    if (!split.ok()) continue;  // the real model answers (or refuses) it; no return on it
    SurrogateInput input;
    input.strain_increment = material::StrainToVoigt(split.strain_increment);
    input.stress_pa = material::StressToVoigt(committed.stress_pa);
    input.accumulated_strain = committed.accumulated_strain;
    input.internal_variables = CarriedOf(RealStateOf(*committed.fallback));
    input.previous_direction = PreviousDirectionOf(committed, *ensemble_);
    inputs.push_back(input);
    asked.push_back(k);
  }
  const std::vector<EnsembleAnswer> answers = ensemble_->Answer(inputs, false);
  for (std::size_t a = 0; a < asked.size(); ++a) flags[asked[a]] = answers[a].out_of_distribution;
  return flags;
}

std::vector<material::PointResponse> AnnMaterial::Update(
    const std::vector<material::PointIncrement>& increments, bool want_tangent) const {
  std::vector<material::PointResponse> responses(increments.size());
  std::vector<std::size_t> on_network, on_fallback;
  std::vector<SurrogateInput> inputs;
  std::vector<material::IncrementKinematics> kinematics;
  for (std::size_t i = 0; i < increments.size(); ++i) {
    const auto& committed = static_cast<const AnnState&>(*increments[i].committed);
    if (committed.fallback) {
      on_fallback.push_back(i);
      continue;
    }
    material::IncrementKinematics split =
        material::HughesWinget(increments[i].displacement_gradient_increment);
    if (!split.ok()) {
      responses[i] = Failed(split.failure_reason);
      continue;
    }
    SurrogateInput input;
    input.strain_increment = material::StrainToVoigt(split.strain_increment);
    input.stress_pa = material::StressToVoigt(committed.stress_pa);
    input.accumulated_strain = committed.accumulated_strain;
    input.internal_variables = committed.internal_variables;
    input.previous_direction = PreviousDirectionOf(committed, *ensemble_);
    on_network.push_back(i);
    inputs.push_back(input);
    kinematics.push_back(std::move(split));
  }
  using Clock = std::chrono::steady_clock;
  const auto network_start = Clock::now();
  const std::vector<EnsembleAnswer> answers = ensemble_->Answer(inputs, want_tangent);
  log_->RecordNetworkCall(std::chrono::duration<double>(Clock::now() - network_start).count(),
                          static_cast<std::int64_t>(inputs.size()));
  const auto fallback_start = Clock::now();
  std::int64_t stress_returns = 0;
  for (std::size_t k = 0; k < on_network.size(); ++k) {
    const std::size_t i = on_network[k];
    const auto& committed = static_cast<const AnnState&>(*increments[i].committed);
    const EnsembleAnswer& answer = answers[k];
    if (answer.out_of_distribution && options_.fallback_enabled) {
      responses[i] = FallBack(committed, increments[i].displacement_gradient_increment,
                              want_tangent);
      if (responses[i].status == material::UpdateStatus::kOk) {
        log_->RecordFallback({committed.steps(), answer.distance, answer.relative_spread,
                              answer.below_pressure_floor, answer.beyond_distance,
                              answer.beyond_spread});
      }
      continue;
    }
    if (answer.out_of_distribution) log_->RecordUnansweredFlag();
    const Matrix3& rotation = kinematics[k].rotation;
    bool capped = false;
    const Matrix3 stress = ensemble_->Admissible(
        rotation * committed.stress_pa * rotation.transpose() +
            material::VoigtToStress(answer.stress_increment_pa),
        &capped);
    stress_returns += capped ? 1 : 0;
    std::unique_ptr<AnnState> next = Advance(
        committed, increments[i].displacement_gradient_increment, inputs[k].strain_increment, stress);
    next->flags += answer.out_of_distribution ? 1 : 0;
    if (next->internal_variables.size() > 0) {
      next->internal_variables += answer.internal_variable_increments;
    }
    material::PointResponse& response = responses[i];
    response.status = material::UpdateStatus::kOk;
    response.stress_pa = next->stress_pa;
    response.has_tangent = want_tangent;
    if (want_tangent) response.tangent_pa = answer.tangent_pa;
    response.state = std::move(next);
  }
  if (!on_fallback.empty()) {
    std::vector<material::PointIncrement> batch;
    for (std::size_t i : on_fallback) {
      const auto& committed = static_cast<const AnnState&>(*increments[i].committed);
      batch.push_back({increments[i].displacement_gradient_increment, committed.fallback.get()});
    }
    std::vector<material::PointResponse> real = real_->Update(batch, want_tangent);
    const std::vector<bool> would_flag = WouldFlag(increments, on_fallback);
    for (std::size_t k = 0; k < on_fallback.size(); ++k) {
      const std::size_t i = on_fallback[k];
      const auto& committed = static_cast<const AnnState&>(*increments[i].committed);
      responses[i] = std::move(real[k]);
      if (responses[i].status != material::UpdateStatus::kOk) continue;
      const Matrix3& increment = increments[i].displacement_gradient_increment;
      std::unique_ptr<AnnState> next = Advance(committed, increment, StrainIncrementOf(increment),
                                               responses[i].stress_pa);
      next->fallback = std::move(responses[i].state);
      if (options_.return_after_steps > 0) {
        next->unflagged_on_fallback = would_flag[k] ? 0 : committed.unflagged_on_fallback + 1;
        if (next->unflagged_on_fallback >= options_.return_after_steps) {
          // Back to the network, from where the real model is now.
          next->internal_variables = CarriedOf(RealStateOf(*next->fallback));
          next->fallback.reset();
          next->unflagged_on_fallback = 0;
          log_->RecordReturn();
        }
      }
      responses[i].state = std::move(next);
    }
  }
  log_->RecordStressReturns(stress_returns);
  log_->RecordFallbackSeconds(std::chrono::duration<double>(Clock::now() - fallback_start).count());
  return responses;
}

}  // namespace gonogo::ann
