#include "server/request_convert.h"

#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::server {

void RequireShort(const std::string& text, size_t max_bytes, const std::string& field) {
  if (text.size() > max_bytes) {
    throw LimitError(field, "is " + std::to_string(text.size()) + " bytes long; the limit is " +
                                std::to_string(max_bytes));
  }
}

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
  r.surrogate_guard = FromProto(request.surrogate_guard());
  return r;
}

SurrogateGuard FromProto(const v1::SurrogateGuard& p) {
  SurrogateGuard g;
  if (p.has_distance_threshold()) g.distance_threshold = p.distance_threshold();
  if (p.has_spread_threshold()) g.spread_threshold = p.spread_threshold();
  if (p.has_pressure_floor_pa()) g.pressure_floor_pa = p.pressure_floor_pa();
  if (p.has_fallback_enabled()) g.fallback_enabled = p.fallback_enabled();
  if (p.has_return_after_steps()) g.return_after_steps = p.return_after_steps();
  return g;
}

v1::SurrogateGuard ToProto(const SurrogateGuard& g) {
  v1::SurrogateGuard p;
  if (g.distance_threshold) p.set_distance_threshold(*g.distance_threshold);
  if (g.spread_threshold) p.set_spread_threshold(*g.spread_threshold);
  if (g.pressure_floor_pa) p.set_pressure_floor_pa(*g.pressure_floor_pa);
  if (g.fallback_enabled) p.set_fallback_enabled(*g.fallback_enabled);
  if (g.return_after_steps) p.set_return_after_steps(*g.return_after_steps);
  return p;
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

SurrogateRun FromProto(const v1::SurrogateRun& p) {
  SurrogateRun run;
  run.fe_steps = p.fe_steps();
  run.fallbacks = static_cast<int>(p.fallbacks());
  run.fallback_point_steps.assign(p.fallback_point_steps().begin(),
                                  p.fallback_point_steps().end());
  run.fallbacks_flagged.below_pressure_floor = static_cast<int>(p.fallbacks_below_pressure_floor());
  run.fallbacks_flagged.beyond_distance = static_cast<int>(p.fallbacks_beyond_distance());
  run.fallbacks_flagged.beyond_spread = static_cast<int>(p.fallbacks_beyond_spread());
  run.returns = p.returns();
  run.unanswered_flags = p.unanswered_flags();
  run.fallback_paths_kept = static_cast<int>(p.fallback_paths_kept());
  run.network_point_updates = p.network_point_updates();
  run.network_seconds = p.network_seconds();
  run.fallback_seconds = p.fallback_seconds();
  return run;
}

v1::SurrogateRun ToProto(const SurrogateRun& run) {
  v1::SurrogateRun p;
  p.set_fe_steps(run.fe_steps);
  p.set_fallbacks(static_cast<uint32_t>(run.fallbacks));
  for (std::int64_t step : run.fallback_point_steps) p.add_fallback_point_steps(step);
  p.set_fallbacks_below_pressure_floor(
      static_cast<uint32_t>(run.fallbacks_flagged.below_pressure_floor));
  p.set_fallbacks_beyond_distance(static_cast<uint32_t>(run.fallbacks_flagged.beyond_distance));
  p.set_fallbacks_beyond_spread(static_cast<uint32_t>(run.fallbacks_flagged.beyond_spread));
  p.set_returns(run.returns);
  p.set_unanswered_flags(run.unanswered_flags);
  p.set_fallback_paths_kept(static_cast<uint32_t>(run.fallback_paths_kept));
  p.set_network_point_updates(run.network_point_updates);
  p.set_network_seconds(run.network_seconds);
  p.set_fallback_seconds(run.fallback_seconds);
  return p;
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

std::map<int32_t, SoilClassInfo> SoilTableOf(const v1::SoilTable& table) {
  std::map<int32_t, SoilClassInfo> out;
  for (int i = 0; i < table.classes_size(); ++i) {
    const v1::SoilClass& c = table.classes(i);
    const std::string field = "soil_table.classes[" + std::to_string(i) + "]";
    Require(!out.count(c.code()), field + ".code", "code " + std::to_string(c.code()) + " repeats");
    const double ri = c.remolding_index() == 0 ? 1.0 : c.remolding_index();
    Require(std::isfinite(ri) && ri > 0 && ri <= 2, field + ".remolding_index",
            "must lie in (0, 2]");
    const std::string library_name = c.bekker_soil().empty() ? c.name() : c.bekker_soil();
    out[c.code()] = SoilClassInfo{
        library_name, ri,
        SoilParametersFromProto(c.has_parameters(), c.parameters(), c.has_bekker(), c.bekker())};
    if (out[c.code()].parameters) {
      out[c.code()].parameters =
          SoilModels().Validate(*out[c.code()].parameters, field + ".parameters");
    }
  }
  return out;
}

// The names a map request stores and echoes.
void RequireShortNames(const v1::MapRequest& request) {
  RequireShort(request.name(), kMaxNameBytes, "name");
  RequireShort(request.vehicle().name(), kMaxNameBytes, "vehicle.name");
  RequireShort(request.vehicle().description(), kMaxTextBytes, "vehicle.description");
  RequireShort(request.surrogate_model(), kMaxIdBytes, "surrogate_model");
  if (request.soil_table().classes_size() > kMaxSoilClasses) {
    throw LimitError("soil_table.classes", "at most 256 soil classes (got " +
                                               std::to_string(request.soil_table().classes_size()) + ")");
  }
  for (const auto& c : request.soil_table().classes()) {
    const std::string field = "soil_table.classes[code " + std::to_string(c.code()) + "]";
    RequireShort(c.name(), kMaxNameBytes, field + ".name");
    RequireShort(c.bekker_soil(), kMaxNameBytes, field + ".bekker_soil");
  }
}

}  // namespace gonogo::server
