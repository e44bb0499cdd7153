// Where traction tasks run. rank 0's scheduler submits tasks and gets each result through a callback;
// two implementations: an in-process thread pool (one process, no MPI launcher) and the MPI pool of
// worker ranks 1..N-1 (ARCHITECTURE section 5).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "solvers/common/traction.h"

namespace gonogo::server {

struct TaskSpec {
  uint64_t task_id = 0;
  std::string tier;
  TractionRequest request;   // already quantised
  uint32_t debug_delay_ms = 0;  // fault-injection delay before computing (tests, demos)
};

struct TaskResult {
  uint64_t task_id = 0;
  bool ok = false;
  bool cancelled = false;
  std::string error;          // why the task failed
  TractionCurve curve;
  std::string computed_by;    // "rank N" or "thread"
  double compute_seconds = 0;
};

using TaskCallback = std::function<void(TaskResult)>;

// The result of a task that was cancelled or dropped before it could finish.
inline TaskResult CancelledResult(uint64_t task_id, std::string why) {
  TaskResult r;
  r.task_id = task_id;
  r.cancelled = true;
  r.error = std::move(why);
  return r;
}

inline constexpr char kShuttingDown[] = "worker pool is shutting down";

class WorkerPool {
 public:
  virtual ~WorkerPool() = default;
  // Queues the task; `done` runs exactly once, on a pool thread, with its result (ok, failed or
  // cancelled). Never blocks on solver work.
  virtual void Submit(TaskSpec task, TaskCallback done) = 0;
  // Cancels a queued task (its callback runs with cancelled = true) or asks a running one to stop.
  virtual void Cancel(uint64_t task_id) = 0;
  virtual int Workers() const = 0;
  virtual std::string Describe() const = 0;
  // Stops accepting work, cancels what is queued and joins the threads.
  virtual void Shutdown() = 0;
};

}  // namespace gonogo::server
