#include "server/map_plan.h"

#include <cmath>
#include <unordered_map>

#include "cache/curve_key.h"
#include "solvers/common/errors.h"

namespace gonogo::server {

MapPlan PlanMap(const geo::TerrainLayers& terrain, const mobility::VehicleSpec& vehicle,
                const std::map<int32_t, SoilClassInfo>& soil_table, const TractionTier& tier,
                const std::vector<double>& slips, const std::string& surrogate_model,
                const SurrogateGuard& surrogate_guard) {
  MapPlan plan;
  const size_t cells = terrain.cone_index_kpa.size();
  plan.cell_unit.assign(cells, -1);
  const bool has_soil = !terrain.soil_class.empty();
  const SoilClassInfo no_soil;

  // Unit of a cell: (soil code, rating cone index bin), packed into one 64-bit key.
  std::unordered_map<uint64_t, int32_t> unit_of_key;
  for (size_t c = 0; c < cells; ++c) {
    if (!terrain.valid[c]) continue;
    int32_t code = -1;
    const SoilClassInfo* soil = &no_soil;
    if (has_soil) {
      code = terrain.soil_class[c];
      auto it = soil_table.find(code);
      if (it == soil_table.end()) {
        const int width = terrain.grid.width;
        throw InputError("soil_class", "class code " + std::to_string(code) + " at row " +
                                           std::to_string(c / width) + " col " +
                                           std::to_string(c % width) +
                                           " is not in the soil table");
      }
      soil = &it->second;
    }
    const double rci_pa = terrain.cone_index_kpa[c] * 1000.0 * soil->remolding_index;
    const int bin = cache::ConeIndexBin(rci_pa);
    const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(code)) << 32) |
                         static_cast<uint32_t>(bin);
    auto [it, inserted] = unit_of_key.try_emplace(key, static_cast<int32_t>(plan.units.size()));
    if (inserted) {
      plan.units.push_back(
          TerrainUnit{code, soil->name, soil->parameters, cache::ConeIndexOfBin(bin), 0});
    }
    plan.units[it->second].cells++;
    plan.cell_unit[c] = it->second;
  }

  // One task per (unit, axle), deduplicated by cache key (axles with equal wheels share a curve).
  std::unordered_map<std::string, int> task_of_key;
  plan.unit_axle_task.resize(plan.units.size());
  for (size_t u = 0; u < plan.units.size(); ++u) {
    // What the tier chooses depends on the soil alone (fe-ann: its model): once per unit.
    TractionRequest unit;
    unit.soil = SoilForTier(tier, SoilState{plan.units[u].rating_cone_index_pa,
                                            plan.units[u].soil_name, plan.units[u].parameters});
    unit.surrogate_model = surrogate_model;
    unit.surrogate_guard = surrogate_guard;
    tier.ResolveChoices(unit, "");
    for (size_t a = 0; a < vehicle.axles.size(); ++a) {
      TractionRequest r = unit;
      r.tyre = vehicle.axles[a].tyre;
      r.wheel_load_n = vehicle.WheelLoadN(static_cast<int>(a));
      r.slips = slips;
      TractionRequest q = cache::Quantise(r);
      std::string key = cache::CurveKey(tier.Name(), tier.VersionFor(q), q);
      auto [it, inserted] = task_of_key.try_emplace(key, static_cast<int>(plan.tasks.size()));
      if (inserted) {
        plan.tasks.push_back(std::move(q));
        plan.task_keys.push_back(std::move(key));
      }
      plan.unit_axle_task[u].push_back(it->second);
    }
  }
  return plan;
}

MapVerdicts EvaluateMap(const MapPlan& plan, const geo::TerrainLayers& terrain,
                        const mobility::VehicleSpec& vehicle, const mobility::Criteria& criteria,
                        const std::vector<TractionCurve>& curves, double soft_soil_vci_pa) {
  std::vector<mobility::VehicleTraction> unit_traction(plan.units.size());
  for (size_t u = 0; u < plan.units.size(); ++u) {
    std::vector<const TractionCurve*> per_axle;
    for (int t : plan.unit_axle_task[u]) per_axle.push_back(&curves[t]);
    unit_traction[u] = mobility::CombineAxles(vehicle, per_axle);
    unit_traction[u].soft_soil_ok = plan.units[u].rating_cone_index_pa >= soft_soil_vci_pa;
  }
  MapVerdicts out;
  const size_t cells = plan.cell_unit.size();
  out.go_class.assign(cells, static_cast<uint8_t>(mobility::GoClass::kNoData));
  out.speed_kmh.assign(cells, std::nanf(""));
  for (size_t c = 0; c < cells; ++c) {
    const int32_t u = plan.cell_unit[c];
    if (u < 0) continue;
    const mobility::CellVerdict v =
        mobility::EvaluateCell(vehicle, criteria, unit_traction[u], terrain.slope_percent[c]);
    out.go_class[c] = static_cast<uint8_t>(v.go_class);
    switch (v.reason) {
      case mobility::NoGoReason::kCannotCarry:
        ++out.no_go_cannot_carry;
        if (out.cannot_carry_example.empty()) {
          out.cannot_carry_example = unit_traction[u].immobile_reason;
        }
        break;
      case mobility::NoGoReason::kSoftSoil: ++out.no_go_soft_soil; break;
      case mobility::NoGoReason::kTraction: ++out.no_go_traction; break;
      case mobility::NoGoReason::kNone: break;
    }
    if (v.go_class != mobility::GoClass::kNoData) out.speed_kmh[c] = v.speed_kmh;
  }
  return out;
}

}  // namespace gonogo::server
