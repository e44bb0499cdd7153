// What a request carries, from its protobuf message to the solvers' value types, with the
// validation that names the offending field and the bounds on its strings. The one place where the
// API's defaults ("0 means ...") are applied. Depends on the proto and the solvers' value types
// only, so that the request fuzzer (tests/fuzz) builds it alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "gonogo/v1/mobility.pb.h"
#include "solvers/common/traction.h"
#include "solvers/mobility/gonogo.h"
#include "solvers/mobility/vehicle.h"

namespace gonogo::server {

// Strings a request may carry, bounded before anything is stored or echoed back.
inline constexpr size_t kMaxNameBytes = 256;   // job, vehicle, soil and model names
inline constexpr size_t kMaxIdBytes = 64;      // job ids, model ids, product names, page tokens
inline constexpr size_t kMaxTextBytes = 4096;  // free text: a vehicle's description
inline constexpr int kMaxSoilClasses = 256;    // classes of a map's soil table

// LimitError (RESOURCE_EXHAUSTED) naming `field` when `text` is longer than `max_bytes`.
void RequireShort(const std::string& text, size_t max_bytes, const std::string& field);
// The names and the soil-table size of a map request, bounded (LimitError naming the field).
void RequireShortNames(const v1::MapRequest& request);

TyreGeometry FromProto(const v1::Tyre& tyre);
v1::Tyre ToProto(const TyreGeometry& tyre);
TractionPoint FromProto(const v1::TractionPoint& point);
// The explicit parameter set of a soil state or soil class: `parameters` when present, else the
// deprecated Bekker alias as a "bekker" set, else none.
std::optional<SoilParameters> SoilParametersFromProto(bool has_parameters,
                                                     const v1::SoilParameterSet& parameters,
                                                     bool has_bekker,
                                                     const v1::BekkerParameters& bekker);
v1::SoilParameterSet ToProto(const SoilParameters& p);
SoilState FromProto(const v1::SoilState& soil);
// The request of a curve query: tyre, load, soil and the slip sweep (slip_step 0: 0.05). Not
// validated; throws InputError("slip_step") for a bad step, LimitError for one below 0.001.
TractionRequest FromProto(const v1::GetTractionCurveRequest& request);
v1::SoilState ToProto(const SoilState& soil);
v1::TractionPoint ToProto(const TractionPoint& point);
SurrogateRun FromProto(const v1::SurrogateRun& run);
v1::SurrogateRun ToProto(const SurrogateRun& run);
// The fields set, and only those (not validated: TractionRequest::Validate does).
SurrogateGuard FromProto(const v1::SurrogateGuard& guard);
v1::SurrogateGuard ToProto(const SurrogateGuard& guard);

// Throws InputError naming "vehicle.<field>".
mobility::VehicleSpec VehicleFromProto(const v1::Vehicle& vehicle);
// Applies the defaults and validates; throws InputError naming "criteria.<field>".
mobility::Criteria CriteriaFromProto(const v1::Criteria& criteria);

// One class of a map's soil table.
struct SoilClassInfo {
  std::string name;
  double remolding_index = 1.0;              // RCI = CI * RI
  std::optional<SoilParameters> parameters;  // explicit soil-model parameters
};
// The soil table by class code, validated (InputError naming "soil_table.classes[i].<field>").
std::map<int32_t, SoilClassInfo> SoilTableOf(const v1::SoilTable& table);

}  // namespace gonogo::server
