#include "server/convert.h"

#include <algorithm>
#include <memory>

#include "solvers/common/errors.h"

namespace gonogo::server {

v1::SurrogateModel ToProto(const tiers::RegisteredSurrogate& m) {
  v1::SurrogateModel out;
  out.set_id(m.id);
  out.set_soil_name(m.soil_name);
  out.set_soil_parameters(m.soil_parameters);
  out.set_fe_de_preset(m.fe_de_preset);
  out.set_architecture(m.architecture);
  out.set_members(static_cast<uint32_t>(m.members));
  out.set_data_hash(m.data_hash);
  out.set_samples(m.samples);
  out.set_fallback_paths(static_cast<uint32_t>(m.fallback_paths));
  out.set_fallback_paths_share(m.fallback_paths_share);
  out.set_walk_share(m.walk_share);
  out.set_distance_threshold(m.distance_threshold);
  out.set_spread_threshold(m.spread_threshold);
  out.set_tensile_limit_pa(m.tensile_limit_pa);
  out.set_least_principal_ratio(m.least_principal_ratio);
  for (const tiers::HeldOutResult& h : m.held_out) {
    v1::HeldOutError* e = out.add_held_out();
    e->set_path(h.path);
    e->set_replay_error(h.replay_error);
    for (const tiers::PackingDifference& packing : h.packings) {
      v1::PackingDifference* p = e->add_packings();
      p->set_packing_seed(packing.packing_seed);
      p->set_difference(packing.difference);
    }
    e->set_floor(tiers::PackingFloor(h.packings));
  }
  out.set_worst_held_out_error(m.worst_held_out_error);
  out.set_worst_error_beyond_floor(tiers::WorstErrorBeyondFloor(m));
  out.set_training_seconds(m.training_seconds);
  out.set_training(m.training);
  out.set_from_model(m.from_model);
  out.set_code_version(m.code_version);
  out.set_created_unix_ms(m.created_unix_ms);
  return out;
}

v1::WorkerTask ToWorkerTask(const TaskSpec& t) {
  v1::WorkerTask w;
  w.set_task_id(t.task_id);
  w.set_debug_delay_ms(t.debug_delay_ms);
  v1::GetTractionCurveRequest* r = w.mutable_request();
  r->set_tier(t.tier);
  *r->mutable_tyre() = ToProto(t.request.tyre);
  r->set_wheel_load_n(t.request.wheel_load_n);
  *r->mutable_soil() = ToProto(t.request.soil);
  r->set_surrogate_model(t.request.surrogate_model);
  *r->mutable_surrogate_guard() = ToProto(t.request.surrogate_guard);
  for (double s : t.request.slips) w.add_slips(s);
  w.set_threads(t.needs.threads);
  w.set_checkpoint_dir(t.checkpoint_dir);
  if (t.training) *w.mutable_training() = *t.training;
  return w;
}

TaskSpec FromWorkerTask(const v1::WorkerTask& w) {
  TaskSpec t;
  t.task_id = w.task_id();
  t.debug_delay_ms = w.debug_delay_ms();
  t.tier = w.request().tier();
  t.request.tyre = FromProto(w.request().tyre());
  t.request.wheel_load_n = w.request().wheel_load_n();
  t.request.soil = FromProto(w.request().soil());
  t.request.surrogate_model = w.request().surrogate_model();
  t.request.surrogate_guard = FromProto(w.request().surrogate_guard());
  t.request.slips.assign(w.slips().begin(), w.slips().end());
  t.needs.ranks = std::max(1, w.group_ranks_size());
  t.needs.threads = std::max(1, w.threads());
  t.checkpoint_dir = w.checkpoint_dir();
  if (w.has_training()) t.training = std::make_shared<const v1::TrainingWork>(w.training());
  return t;
}

v1::WorkerResult ToWorkerResult(const TaskResult& r) {
  v1::WorkerResult w;
  w.set_task_id(r.task_id);
  w.set_ok(r.ok);
  w.set_cancelled(r.cancelled);
  w.set_error(r.error);
  w.set_error_kind(static_cast<int32_t>(r.error_kind));
  w.set_error_field(r.error_field);
  w.set_tier_version(r.curve.tier_version);
  w.set_compute_seconds(r.compute_seconds);
  w.set_immobile_reason(r.curve.immobile_reason);
  for (const TractionPoint& p : r.curve.points) *w.add_points() = ToProto(p);
  w.set_training_output(r.training_output);
  for (const std::string& history : r.training_histories) w.add_training_histories(history);
  if (r.curve.surrogate_run) *w.mutable_surrogate_run() = ToProto(*r.curve.surrogate_run);
  return w;
}

TaskResult FromWorkerResult(const v1::WorkerResult& w, const std::string& tier,
                            const std::string& computed_by) {
  TaskResult r;
  r.task_id = w.task_id();
  r.ok = w.ok();
  r.cancelled = w.cancelled();
  r.error = w.error();
  r.error_kind = w.error_kind() >= 0 && w.error_kind() <= static_cast<int32_t>(ErrorKind::kPrecondition)
                     ? static_cast<ErrorKind>(w.error_kind())
                     : ErrorKind::kInternal;
  if (!r.ok && r.error_kind == ErrorKind::kNone) r.error_kind = ErrorKind::kInternal;
  r.error_field = w.error_field();
  r.curve.tier = tier;
  r.curve.tier_version = w.tier_version();
  r.curve.immobile_reason = w.immobile_reason();
  for (const auto& p : w.points()) r.curve.points.push_back(FromProto(p));
  if (w.has_surrogate_run()) r.curve.surrogate_run = FromProto(w.surrogate_run());
  r.computed_by = computed_by;
  r.compute_seconds = w.compute_seconds();
  r.training_output = w.training_output();
  r.training_histories.assign(w.training_histories().begin(), w.training_histories().end());
  return r;
}

}  // namespace gonogo::server
