#include "server/training_work.h"

#include <algorithm>
#include <memory>

#include "solvers/ann/strain_history.h"
#include "solvers/ann/stress_surrogate.h"
#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/surrogate_training.h"

namespace gonogo::server {

namespace {

// The soil of a task, from its canonical text; InputError(field, ...) when it is not one.
SoilParameters SoilOf(const std::string& canonical_text, const std::string& field) {
  std::optional<SoilParameters> soil;
  try {
    soil = ParseCanonicalText(canonical_text);
  } catch (const std::invalid_argument& e) {
    throw InputError(field, e.what());
  }
  Require(soil.has_value(), field, "is missing");
  return *soil;
}

// The soil's RVE (its canonical text; InputError(field, ...) when it is not one) at the
// configuration's numerics, packed from `packing_seed` (0: the configuration's own). The template
// is settled once per process, configuration and packing (SharedRveMaterial), then shared by
// every path this rank runs.
std::shared_ptr<const dem::rve::RveMaterial> RveOfPacking(const std::string& soil_parameters,
                                                          const std::string& fe_de_preset,
                                                          unsigned packing_seed,
                                                          const std::string& field) {
  tiers::FeDeOptions fe_de = tiers::FeDeOptions::Preset(fe_de_preset);
  if (packing_seed > 0) fe_de.numerics.seed = packing_seed;
  return dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(SoilOf(soil_parameters, field), fe_de.numerics, field));
}

std::string RunRvePath(const v1::RvePathWork& work, const ComputeContext& context) {
  const auto rve = RveOfPacking(work.soil_parameters(), work.fe_de_preset(), work.packing_seed(),
                                "training.rve_path.soil_parameters");
  if (context.Cancelled()) throw CancelledError();
  const ann::LabPathSpec spec = LabPathSpecOf(work);
  spec.Validate("training.rve_path.");
  const ann::InternalVariables recorded = tiers::RveVariables(
      {work.recorded_variables().begin(), work.recorded_variables().end()},
      "training.rve_path.recorded_variables");
  const std::vector<ann::StrainHistory> history =
      tiers::RunLabPaths(*rve, {{work.path(), spec}}, 1, {}, recorded);
  return ann::SerializeHistory(history.front());
}

std::string TrainMember(const v1::TrainMemberWork& work, const ComputeContext& context) {
  std::vector<ann::StrainHistory> histories;
  histories.reserve(static_cast<std::size_t>(work.histories_size()));
  for (const std::string& bytes : work.histories()) histories.push_back(ann::ParseHistory(bytes));
  ann::TrainingOptions options;
  options.epochs = work.epochs();
  options.batch_size = work.batch_size();
  options.learning_rate = work.learning_rate();
  options.seed = work.seed();
  options.threads = 1;  // bit-reproducible; the pool's parallelism is one member per rank
  options.stop = [&] { return context.Cancelled(); };
  options.history_weights.assign(work.history_weights().begin(), work.history_weights().end());
  options.Validate("training.train_member.");
  ann::StressSurrogate member = [&] {
    if (!work.base_member_path().empty()) {
      return ann::StressSurrogate::FineTune(ann::StressSurrogate::Load(work.base_member_path()),
                                            histories, options);
    }
    ann::MlpArchitecture architecture;
    architecture.hidden_widths.assign(work.hidden_widths().begin(), work.hidden_widths().end());
    architecture.anchored = work.anchored();
    architecture.pressure_reference_pa = work.pressure_reference_pa();
    architecture.homogeneous_term = work.homogeneous_term();
    architecture.previous_direction = work.previous_direction();
    architecture.carried_variables.assign(work.carried_variables().begin(),
                                          work.carried_variables().end());
    architecture.Validate("training.train_member.");
    return ann::StressSurrogate::Train(histories, architecture, options);
  }();
  return member.Bytes();
}

std::string RunRigPaths(const v1::RigPathsWork& work, const ComputeContext& context) {
  const SoilParameters soil = SoilOf(work.soil_parameters(), "training.rig_paths.soil_parameters");
  TractionRequest request;
  request.soil.parameters = soil;
  request.tyre.diameter_m = work.diameter_m();
  request.tyre.width_m = work.width_m();
  request.tyre.section_height_m = 0.5 * work.width_m();
  request.wheel_load_n = work.wheel_load_n();
  request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
  const tiers::FeDeTier fe_de(tiers::FeDeOptions::Preset(work.fe_de_preset()));
  const tiers::RecordedRigRun recorded = tiers::RecordRigPaths(
      fe_de, request, context,
      tiers::RveVariables({work.recorded_variables().begin(), work.recorded_variables().end()},
                          "training.rig_paths.recorded_variables"));
  const int count = static_cast<int>(recorded.paths.size());
  Require(count > 0, "training.rig_paths", "the rig run recorded no paths");
  v1::RigPathsOutput output;
  output.set_elements(recorded.run.elements);
  output.set_fe_steps(recorded.run.fe_steps);
  for (const ann::StrainHistory& path :
       tiers::EvenlySpread(recorded.paths, work.training_points(), 0)) {
    output.add_training(ann::SerializeHistory(path));
  }
  for (const ann::StrainHistory& path :
       tiers::EvenlySpread(recorded.paths, work.held_out_points(),
                           tiers::RigHeldOutOffset(count, work.training_points()))) {
    output.add_held_out(ann::SerializeHistory(path));
  }
  return output.SerializeAsString();
}

std::string RunReplayPath(const v1::ReplayPathWork& work, const ComputeContext& context) {
  const auto rve = RveOfPacking(work.soil_parameters(), work.fe_de_preset(), work.packing_seed(),
                                "training.replay_path.soil_parameters");
  if (context.Cancelled()) throw CancelledError();
  const ann::InternalVariables recorded =
      tiers::RveVariables({work.recorded_variables().begin(), work.recorded_variables().end()},
                          "training.replay_path.recorded_variables");
  return ann::SerializeHistory(
      tiers::ReplayedOnRve(rve, ann::ParseHistory(work.history()), recorded));
}

}  // namespace

std::string RunTrainingWork(const v1::TrainingWork& work, const ComputeContext& context) {
  switch (work.work_case()) {
    case v1::TrainingWork::kRvePath:
      return RunRvePath(work.rve_path(), context);
    case v1::TrainingWork::kTrainMember:
      return TrainMember(work.train_member(), context);
    case v1::TrainingWork::kRigPaths:
      return RunRigPaths(work.rig_paths(), context);
    case v1::TrainingWork::kReplayPath:
      return RunReplayPath(work.replay_path(), context);
    default:
      throw InputError("training", "names no work");
  }
}

v1::RvePathWork ToProto(const ann::LabPathSpec& spec) {
  v1::RvePathWork work;
  work.set_path(ann::LabPathName(spec.path));
  work.set_pressure_pa(spec.pressure_pa);
  work.set_max_strain(spec.max_strain);
  work.set_steps(spec.steps);
  work.set_settle_steps(spec.settle_steps);
  work.set_walk_step_strain(spec.walk_step_strain);
  work.set_seed(spec.seed);
  return work;
}

ann::LabPathSpec LabPathSpecOf(const v1::RvePathWork& work) {
  ann::LabPathSpec spec;
  spec.path = ann::ParseLabPath(work.path(), "training.rve_path.path");
  spec.pressure_pa = work.pressure_pa();
  spec.max_strain = work.max_strain();
  spec.steps = work.steps();
  spec.settle_steps = work.settle_steps();
  spec.walk_step_strain = work.walk_step_strain();
  spec.seed = work.seed();
  return spec;
}

}  // namespace gonogo::server
