// Conversions between the API's protobuf messages and the solvers' value types, with the validation
// that names the offending field. The one place where defaults of the API ("0 means ...") are applied.
#pragma once

#include <optional>

#include "gonogo/v1/mobility.pb.h"
#include "gonogo/v1/worker.pb.h"
#include "server/worker_pool.h"
#include "solvers/common/traction.h"
#include "solvers/mobility/gonogo.h"
#include "solvers/mobility/vehicle.h"
#include "solvers/tiers/surrogate_registry.h"

namespace gonogo::server {

TyreGeometry FromProto(const v1::Tyre& tyre);
v1::Tyre ToProto(const TyreGeometry& tyre);
TractionPoint FromProto(const v1::TractionPoint& point);
// Bekker parameters of a message that has them, else nullopt.
// The explicit parameter set of a soil state or soil class: `parameters` when present, else the
// deprecated Bekker alias as a "bekker" set, else none.
std::optional<SoilParameters> SoilParametersFromProto(bool has_parameters,
                                                     const v1::SoilParameterSet& parameters,
                                                     bool has_bekker,
                                                     const v1::BekkerParameters& bekker);
v1::SoilParameterSet ToProto(const SoilParameters& p);
SoilState FromProto(const v1::SoilState& soil);
// The request of a curve query: tyre, load, soil and the slip sweep (slip_step 0: 0.05). Not
// validated; throws InputError("slip_step") for a bad step.
TractionRequest FromProto(const v1::GetTractionCurveRequest& request);
v1::SoilState ToProto(const SoilState& soil);
v1::TractionPoint ToProto(const TractionPoint& point);

// Throws InputError naming "vehicle.<field>".
mobility::VehicleSpec VehicleFromProto(const v1::Vehicle& vehicle);
// Applies the defaults and validates; throws InputError naming "criteria.<field>".
mobility::Criteria CriteriaFromProto(const v1::Criteria& criteria);

// A registered fe-ann model with its provenance, as ListSurrogateModels and training jobs show it.
v1::SurrogateModel ToProto(const tiers::RegisteredSurrogate& model);

v1::WorkerTask ToWorkerTask(const TaskSpec& task);
TaskSpec FromWorkerTask(const v1::WorkerTask& task);
v1::WorkerResult ToWorkerResult(const TaskResult& result);
TaskResult FromWorkerResult(const v1::WorkerResult& result, const std::string& tier,
                            const std::string& computed_by);

}  // namespace gonogo::server
