// Conversions between the API's protobuf messages and the server's own types: registered models and
// the worker protocol. The conversions of what a request carries are in server/request_convert.h.
#pragma once

#include <optional>

#include "gonogo/v1/mobility.pb.h"
#include "gonogo/v1/worker.pb.h"
#include "server/request_convert.h"
#include "server/worker_pool.h"
#include "solvers/common/traction.h"
#include "solvers/mobility/gonogo.h"
#include "solvers/mobility/vehicle.h"
#include "solvers/tiers/surrogate_registry.h"

namespace gonogo::server {

// A registered fe-ann model with its provenance, as ListSurrogateModels and training jobs show it.
v1::SurrogateModel ToProto(const tiers::RegisteredSurrogate& model);

v1::WorkerTask ToWorkerTask(const TaskSpec& task);
TaskSpec FromWorkerTask(const v1::WorkerTask& task);
v1::WorkerResult ToWorkerResult(const TaskResult& result);
TaskResult FromWorkerResult(const v1::WorkerResult& result, const std::string& tier,
                            const std::string& computed_by);

}  // namespace gonogo::server
