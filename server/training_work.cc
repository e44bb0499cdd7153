#include "server/training_work.h"

#include "solvers/ann/stress_surrogate.h"
#include "solvers/ann/strain_history.h"
#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/fe_de_tier.h"
#include "solvers/tiers/surrogate_training.h"

namespace gonogo::server {

namespace {

std::string RunRvePath(const v1::RvePathWork& work, const ComputeContext& context) {
  std::optional<SoilParameters> soil;
  try {
    soil = ParseCanonicalText(work.soil_parameters());
  } catch (const std::invalid_argument& e) {
    throw InputError("training.rve_path.soil_parameters", e.what());
  }
  Require(soil.has_value(), "training.rve_path.soil_parameters", "is missing");
  const tiers::FeDeOptions fe_de = tiers::FeDeOptions::Preset(work.fe_de_preset());
  // The template is settled once per process and configuration (SharedRveMaterial), then shared
  // by every path this rank runs.
  const auto rve = dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(
      *soil, fe_de.numerics, "training.rve_path.soil_parameters"));
  if (context.Cancelled()) throw CancelledError();
  const ann::LabPathSpec spec = LabPathSpecOf(work);
  spec.Validate("training.rve_path.");
  const std::vector<ann::StrainHistory> history =
      tiers::RunLabPaths(*rve, {{work.path(), spec}}, 1);
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
  options.Validate("training.train_member.");
  ann::StressSurrogate member = [&] {
    if (!work.base_member_path().empty()) {
      return ann::StressSurrogate::FineTune(ann::StressSurrogate::Load(work.base_member_path()),
                                            histories, options);
    }
    ann::MlpArchitecture architecture;
    architecture.hidden_widths.assign(work.hidden_widths().begin(), work.hidden_widths().end());
    architecture.anchored = work.anchored();
    architecture.Validate("training.train_member.");
    return ann::StressSurrogate::Train(histories, architecture, options);
  }();
  return member.Bytes();
}

}  // namespace

std::string RunTrainingWork(const v1::TrainingWork& work, const ComputeContext& context) {
  switch (work.work_case()) {
    case v1::TrainingWork::kRvePath:
      return RunRvePath(work.rve_path(), context);
    case v1::TrainingWork::kTrainMember:
      return TrainMember(work.train_member(), context);
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
