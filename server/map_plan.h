// Planning and evaluation of one map job, free of I/O: terrain cells are grouped into terrain units
// (soil class x rating-cone-index bin), each unit needs one traction curve per axle, and every cell is
// judged from its unit's curves and its own slope.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "server/geo/terrain.h"
#include "server/request_convert.h"
#include "solvers/common/tier.h"
#include "solvers/mobility/gonogo.h"
#include "solvers/mobility/vehicle.h"

namespace gonogo::server {

struct TerrainUnit {
  int32_t soil_code = -1;        // -1 when there is no soil raster
  std::string soil_name;
  std::optional<SoilParameters> parameters;
  double rating_cone_index_pa = 0;  // quantised (cache bin)
  int64_t cells = 0;
};

struct MapPlan {
  std::vector<int32_t> cell_unit;          // per cell: unit index, -1 for no data
  std::vector<TerrainUnit> units;
  std::vector<TractionRequest> tasks;      // unique, quantised
  std::vector<std::string> task_keys;      // cache key of each task
  std::vector<std::vector<int>> unit_axle_task;  // [unit][axle] -> task index
};

// Throws InputError("soil_class") for a class code missing from the soil table. `surrogate_model`
// (fe-ann; empty: each soil's best) and `surrogate_guard` go into every request, which the tier
// then settles (TractionTier::ResolveChoices) before it is keyed.
MapPlan PlanMap(const geo::TerrainLayers& terrain, const mobility::VehicleSpec& vehicle,
                const std::map<int32_t, SoilClassInfo>& soil_table, const TractionTier& tier,
                const std::vector<double>& slips, const std::string& surrogate_model = "",
                const SurrogateGuard& surrogate_guard = {});

struct MapVerdicts {
  std::vector<uint8_t> go_class;  // per cell, mobility::GoClass codes
  std::vector<float> speed_kmh;   // per cell, NaN for no data
  int64_t no_go_cannot_carry = 0;  // NO-GO cells by reason
  int64_t no_go_soft_soil = 0;
  int64_t no_go_traction = 0;
  std::string cannot_carry_example;  // one solver message, for the summary
};

// `curves[i]` answers plan.tasks[i]. `soft_soil_vci_pa` is the vehicle cone index for the requested
// passes (NRMM soft-soil test: a unit whose RCI is below it is NO-GO), or 0 to skip the test.
MapVerdicts EvaluateMap(const MapPlan& plan, const geo::TerrainLayers& terrain,
                        const mobility::VehicleSpec& vehicle, const mobility::Criteria& criteria,
                        const std::vector<TractionCurve>& curves, double soft_soil_vci_pa);

}  // namespace gonogo::server
