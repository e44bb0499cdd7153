// Where traction tasks run. rank 0's scheduler submits tasks and gets each result through a callback;
// two implementations: an in-process thread pool (one process, no MPI launcher) and the MPI pool of
// worker ranks 1..N-1 (ARCHITECTURE section 5).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "gonogo/v1/worker.pb.h"
#include "solvers/common/errors.h"
#include "solvers/common/tier.h"
#include "solvers/common/traction.h"

namespace gonogo::server {

// A running task's progress: the fraction of its curve done, in [0, 1], and the tier's latest note
// on its run ("" if none; ComputeContext::progress_note).
using TaskProgress = std::function<void(double fraction, const std::string& note)>;

// Tasks expected to take at least this long go to the long lane of a pool's queue, so that cheap
// and long tasks never wait in one FIFO behind each other.
inline constexpr double kLongTaskSeconds = 1.0;

struct TaskSpec {
  uint64_t task_id = 0;
  std::string tier;
  TractionRequest request;   // already quantised
  uint32_t debug_delay_ms = 0;  // fault-injection delay before computing (tests, demos)
  // From the tier (TractionTier::Needs). ranks > 1: a collective task on a rank group; a pool
  // with fewer workers gives it all of them, the thread pool runs it alone.
  TierNeeds needs;
  TaskProgress progress;  // may be empty; called on a pool thread; never crosses MPI
  // Where the tier may keep restart files (ComputeContext::checkpoint_dir); empty: none.
  std::string checkpoint_dir;
  // Set: a training task of a TrainSurrogate job (server/training_work.h) instead of a traction
  // curve; `tier` and `request` are then unused, and the answer is TaskResult::training_output.
  std::shared_ptr<const v1::TrainingWork> training;
};

struct TaskResult {
  uint64_t task_id = 0;
  bool ok = false;
  bool cancelled = false;
  ErrorKind error_kind = ErrorKind::kNone;  // why the task failed, typed across ranks
  std::string error_field;    // the field named, for bad input
  std::string error;          // why the task failed
  TractionCurve curve;
  std::string computed_by;    // "rank N", "ranks N,M" for a rank group, or "thread"
  double compute_seconds = 0;
  std::string training_output;  // a training task's answer (TrainingWork)
  // What a curve's tier kept for training (ComputeContext::keep_training_histories), also of a
  // task that failed or was cancelled: SerializeHistory each.
  std::vector<std::string> training_histories;
};

using TaskCallback = std::function<void(TaskResult)>;

// The result of a task that was cancelled or dropped before it could finish.
inline TaskResult CancelledResult(uint64_t task_id, std::string why) {
  TaskResult r;
  r.task_id = task_id;
  r.cancelled = true;
  r.error_kind = ErrorKind::kCancelled;
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
  // Workers ready for tasks: all of them for threads; under MPI, the ranks that have checked in.
  virtual int ReadyWorkers() const { return Workers(); }
  virtual std::string Describe() const = 0;
  // Stops accepting work, cancels what is queued and joins the threads.
  virtual void Shutdown() = 0;
};

}  // namespace gonogo::server
