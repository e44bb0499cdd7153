#include "server/convert.h"

#include <algorithm>
#include <memory>

#include "solvers/common/errors.h"

namespace gonogo::server {

TyreGeometry FromProto(const v1::Tyre& t) {
  return TyreGeometry{t.diameter_m(),   t.width_m(),          t.section_height_m(),
                      t.deflection_m(), t.rolling_radius_m(), t.inflation_pressure_pa()};
}

std::optional<SoilParameters> SoilParametersFromProto(bool has_parameters,
                                                     const v1::SoilParameterSet& parameters,
                                                     bool has_bekker,
                                                     const v1::BekkerParameters& bekker) {
  if (has_parameters) {
    SoilParameters p;
    p.model = parameters.model();
    p.values.insert(parameters.values().begin(), parameters.values().end());
    return p;
  }
  if (!has_bekker) return std::nullopt;
  return BekkerParameters{bekker.n(),           bekker.kc(),
                          bekker.kphi(),        bekker.cohesion_pa(),
                          bekker.friction_angle_deg(), bekker.shear_deformation_m()}
      .ToSoilModel();
}

v1::SoilParameterSet ToProto(const SoilParameters& p) {
  v1::SoilParameterSet out;
  out.set_model(p.model);
  out.mutable_values()->insert(p.values.begin(), p.values.end());
  return out;
}

SoilState FromProto(const v1::SoilState& p) {
  SoilState s;
  s.cone_index_pa = p.cone_index_pa();
  s.soil_name = p.soil_name();
  s.parameters =
      SoilParametersFromProto(p.has_parameters(), p.parameters(), p.has_bekker(), p.bekker());
  return s;
}

TractionRequest FromProto(const v1::GetTractionCurveRequest& request) {
  TractionRequest r;
  r.tyre = FromProto(request.tyre());
  r.wheel_load_n = request.wheel_load_n();
  r.soil = FromProto(request.soil());
  r.slips = TractionRequest::SlipSweep(request.slip_step() == 0 ? 0.05 : request.slip_step());
  r.surrogate_model = request.surrogate_model();
  return r;
}

v1::SoilState ToProto(const SoilState& s) {
  v1::SoilState p;
  p.set_cone_index_pa(s.cone_index_pa);
  p.set_soil_name(s.soil_name);
  if (s.parameters) *p.mutable_parameters() = ToProto(*s.parameters);
  return p;
}

v1::Tyre ToProto(const TyreGeometry& t) {
  v1::Tyre p;
  p.set_diameter_m(t.diameter_m);
  p.set_width_m(t.width_m);
  p.set_section_height_m(t.section_height_m);
  p.set_deflection_m(t.deflection_m);
  p.set_rolling_radius_m(t.rolling_radius_m);
  p.set_inflation_pressure_pa(t.inflation_pressure_pa);
  return p;
}

TractionPoint FromProto(const v1::TractionPoint& p) {
  return TractionPoint{p.slip(),         p.drawbar_pull_n(),   p.torque_nm(),
                       p.sinkage_m(),    p.tractive_efficiency(), p.gross_traction_n(),
                       p.motion_resistance_n()};
}

v1::TractionPoint ToProto(const TractionPoint& p) {
  v1::TractionPoint q;
  q.set_slip(p.slip);
  q.set_drawbar_pull_n(p.drawbar_pull_n);
  q.set_torque_nm(p.torque_nm);
  q.set_sinkage_m(p.sinkage_m);
  q.set_tractive_efficiency(p.tractive_efficiency);
  q.set_gross_traction_n(p.gross_traction_n);
  q.set_motion_resistance_n(p.motion_resistance_n);
  return q;
}

mobility::VehicleSpec VehicleFromProto(const v1::Vehicle& p) {
  mobility::VehicleSpec v;
  v.name = p.name();
  v.mass_kg = p.mass_kg();
  bool fractions_given = false;
  for (const v1::Axle& a : p.axles()) {
    mobility::AxleSpec axle;
    axle.load_fraction = a.load_fraction();
    axle.wheels = static_cast<int>(a.wheels());
    Require(a.has_tyre(), "vehicle.axles[" + std::to_string(v.axles.size()) + "].tyre",
            "is missing");
    axle.tyre = FromProto(a.tyre());
    axle.driven = a.driven();
    fractions_given = fractions_given || axle.load_fraction != 0;
    v.axles.push_back(axle);
  }
  if (!fractions_given && !v.axles.empty()) {
    mobility::SetTwoAxleSplitFromCg(v, p.cg_behind_front_axle_m(), p.wheelbase_m());
  }
  v.drive_power_w = p.drive_power_w();
  v.max_speed_kmh = p.max_speed_kmh();
  v.driveline_efficiency =
      p.driveline_efficiency() == 0 ? mobility::kDefaultDrivelineEfficiency : p.driveline_efficiency();
  v.ground_clearance_m = p.ground_clearance_m();
  v.automatic_transmission = p.automatic_transmission();
  v.tyre_chains = p.tyre_chains();
  v.Validate();
  return v;
}

mobility::Criteria CriteriaFromProto(const v1::Criteria& p) {
  mobility::Criteria c;
  if (p.design_slip() != 0) c.design_slip = p.design_slip();
  if (p.max_slip() != 0) c.max_slip = p.max_slip();
  if (p.go_margin() != 0) c.go_margin = p.go_margin();
  if (p.passes() != 0) c.passes = static_cast<int>(p.passes());
  if (p.slip_step() != 0) c.slip_step = p.slip_step();
  c.Validate();
  return c;
}

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
  out.set_distance_threshold(m.distance_threshold);
  out.set_spread_threshold(m.spread_threshold);
  out.set_tensile_limit_pa(m.tensile_limit_pa);
  out.set_least_principal_ratio(m.least_principal_ratio);
  for (const tiers::HeldOutResult& h : m.held_out) {
    v1::HeldOutError* e = out.add_held_out();
    e->set_path(h.path);
    e->set_replay_error(h.replay_error);
  }
  out.set_worst_held_out_error(m.worst_held_out_error);
  out.set_training_seconds(m.training_seconds);
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
  r.computed_by = computed_by;
  r.compute_seconds = w.compute_seconds();
  r.training_output = w.training_output();
  return r;
}

}  // namespace gonogo::server
