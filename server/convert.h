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

namespace gonogo::server {

TyreGeometry FromProto(const v1::Tyre& tyre);
v1::Tyre ToProto(const TyreGeometry& tyre);
TractionPoint FromProto(const v1::TractionPoint& point);
// Bekker parameters of a message that has them, else nullopt.
std::optional<BekkerParameters> BekkerFromProto(bool present, const v1::BekkerParameters& p);
v1::BekkerParameters ToProto(const BekkerParameters& b);
SoilState FromProto(const v1::SoilState& soil);
v1::SoilState ToProto(const SoilState& soil);
v1::TractionPoint ToProto(const TractionPoint& point);

// Throws InputError naming "vehicle.<field>".
mobility::VehicleSpec VehicleFromProto(const v1::Vehicle& vehicle);
// Applies the defaults and validates; throws InputError naming "criteria.<field>".
mobility::Criteria CriteriaFromProto(const v1::Criteria& criteria);

v1::WorkerTask ToWorkerTask(const TaskSpec& task);
TaskSpec FromWorkerTask(const v1::WorkerTask& task);
v1::WorkerResult ToWorkerResult(const TaskResult& result);
TaskResult FromWorkerResult(const v1::WorkerResult& result, const std::string& tier,
                            const std::string& computed_by);

}  // namespace gonogo::server
