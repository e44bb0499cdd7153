// Runs one traction (or training) task on the calling thread: the code shared by every pool and by the MPI workers.
#pragma once

#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// Never throws: input errors, solver failures and cancellation all come back in the result, typed
// (TaskResult::error_kind). Collective on context.communicator when it is set.
TaskResult RunTask(const TierRegistry& tiers, const TaskSpec& task,
                   const ComputeContext& context, const std::string& computed_by);

}  // namespace gonogo::server
