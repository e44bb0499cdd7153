// The one component that resolves traction curves, for map jobs, single-curve queries and the
// scalability study alike (ARCHITECTURE sections 2 and 6):
//   1. exact cache key, 2. (when allowed) a similar tyre on the same soil (seed 001 similarity),
//   3. else a task on the worker pool, whose curve is stored the moment it arrives (a crash loses
//      no finished curve).
// Task ids come from one counter, so cancelling one caller's task never touches another's.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cache/curve_store.h"
#include "server/curve_lookup.h"
#include "server/worker_pool.h"
#include "solvers/common/errors.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// One curve to resolve: a request already quantised (cache::Quantise) and its key.
struct CurveTask {
  TractionRequest request;
  std::string key;
};

enum class CurveSource { kUnresolved, kCacheExact, kCacheSimilar, kComputed, kFailed, kCancelled };

// A curve query on a tier expected to take at least this long is a job (SubmitCurve), never
// computed inside one RPC.
inline constexpr double kLongQuerySeconds = 60.0;

struct Resolution {
  CurveSource source = CurveSource::kUnresolved;
  TractionCurve curve;                 // the answer (for a similarity hit: scaled to the request)
  std::optional<CachedAnswer> cached;  // set for cache hits
  cache::StoredCurve stored;           // the stored curve behind the answer (computed or cached)
  ErrorKind error_kind = ErrorKind::kNone;  // kFailed / kCancelled: why
  std::string error;

  bool ok() const {
    return source == CurveSource::kCacheExact || source == CurveSource::kCacheSimilar ||
           source == CurveSource::kComputed;
  }
};

struct ResolveOptions {
  bool allow_similarity = true;
  // The cache scope of the caller: "" (the default) shares curves with every identity; an
  // identity's name keeps its curves to itself (gonogo-server --private-curves).
  std::string scope;
  uint32_t debug_delay_ms = 0;  // fault-injection delay on every computed task
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  // Polled about every 100 ms while tasks are out: true cancels what is outstanding.
  std::function<bool()> stop;
  // True once the caller no longer wants the work (a cancelled job): a curve that still arrives is
  // dropped, not committed, and reported as cancelled. A drain stops without discarding, so that a
  // curve finished meanwhile is kept for the resumed job.
  std::function<bool()> discard;
  // A failed task cancels the rest (a map cannot be drawn with a hole in it).
  bool stop_on_failure = false;
  // Only the cache: misses stay kUnresolved and nothing is sent to the pool.
  bool lookup_only = false;
  // After the cache lookups, before any task is sent: the resolutions so far.
  std::function<void(const std::vector<Resolution>&)> after_lookups;
  // Each computed, failed or cancelled task as it ends (on the resolving thread).
  std::function<void(size_t index, const Resolution&)> on_task_end;
  // A running task's progress (fraction of its curve, and the tier's note on its run or ""), from
  // a pool thread.
  std::function<void(size_t index, double fraction, const std::string& note)> on_task_progress;
};

// Tasks a Resolve call keeps in the pool per worker: enough to keep every worker busy, few enough
// that callers running at once take turns.
inline constexpr size_t kInFlightPerWorker = 2;

class CurveResolver {
 public:
  CurveResolver(cache::CurveStore& store, WorkerPool& pool) : store_(store), pool_(pool) {}

  // The quantised, validated request and its cache key, for `tier`: strips what the tier does not
  // read, snaps to the key's resolution, validates. Throws InputError naming the field.
  static CurveTask Prepare(const TractionTier& tier, TractionRequest request,
                           const std::string& soil_field = "soil");

  // Resolves every task; returns one Resolution per task, in order. Blocks the calling thread (not
  // a solver thread) until every task has ended or been cancelled; never throws for a task's
  // failure (it is in the Resolution), only for database errors.
  std::vector<Resolution> Resolve(const TractionTier& tier, const std::vector<CurveTask>& tasks,
                                  const ResolveOptions& options);

  WorkerPool& pool() { return pool_; }
  // A fresh task id: one counter numbers every task of the pool (curves and training tasks), so
  // that cancelling one caller's task never touches another's.
  uint64_t NewTaskId() { return next_task_id_++; }
  // Long tasks (a tier expected to take kCheckpointedTaskSeconds or more) get a restart
  // directory under `root`, named by their cache key: a task stopped by a crash or a drain and
  // run again (the job resumed after a restart, or the same curve asked again) continues from its
  // last checkpoint. The directory is removed once the curve is stored or the task failed; a
  // cancelled task keeps it. Empty root (the default): no checkpoints.
  void set_checkpoint_root(std::string root) { checkpoint_root_ = std::move(root); }
  // What a computed task's tier kept for training (TaskResult::training_histories: the fe-ann
  // tier's fallback paths) goes to `keeper` as the task ends, computed, failed or cancelled (on
  // the resolving thread; server/fallback_paths.h). A keeper's error is logged, never the
  // task's. Unset (the default): they are dropped.
  using TrainingHistoryKeeper =
      std::function<void(const TractionTier&, const CurveTask&, const TaskResult&)>;
  void set_training_history_keeper(TrainingHistoryKeeper keeper) {
    training_history_keeper_ = std::move(keeper);
  }

 private:
  cache::CurveStore& store_;
  WorkerPool& pool_;
  std::atomic<uint64_t> next_task_id_{1};
  std::string checkpoint_root_;
  TrainingHistoryKeeper training_history_keeper_;
};

// Tasks expected to take at least this long get a restart directory (set_checkpoint_root).
inline constexpr double kCheckpointedTaskSeconds = 60;

// The API form of a resolved curve answering `request` (an exact or similarity hit with its
// provenance, or a freshly computed curve). `answer` must be ok().
void FillResolved(const TractionRequest& request, const Resolution& answer, v1::TractionCurve* out);

}  // namespace gonogo::server
