#include "server/curve_resolver.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

#include <spdlog/spdlog.h>

#include "cache/curve_key.h"

namespace gonogo::server {

namespace {

// A task's restart directory: root/<FNV-1a 64 of its cache key, hex>, stable across restarts.
std::string CheckpointDirectory(const std::string& root, const std::string& key) {
  std::uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : key) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  char name[17];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(hash));
  return root + "/" + name;
}

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Results and progress of the outstanding tasks, filled on pool threads.
struct Inbox {
  std::mutex mutex;
  std::condition_variable arrived;
  std::deque<TaskResult> results;
};

}  // namespace

CurveTask CurveResolver::Prepare(const TractionTier& tier, TractionRequest request,
                                 const std::string& soil_field) {
  request.soil = SoilForTier(tier, std::move(request.soil));
  request.Validate();
  tier.ValidateSoil(request.soil, soil_field);
  tier.ResolveChoices(request, "");
  CurveTask task;
  task.request = cache::Quantise(request);
  task.request.Validate();
  task.key = cache::CurveKey(tier.Name(), tier.VersionFor(task.request), task.request);
  return task;
}

std::vector<Resolution> CurveResolver::Resolve(const TractionTier& tier,
                                               const std::vector<CurveTask>& tasks,
                                               const ResolveOptions& options) {
  std::vector<Resolution> out(tasks.size());
  std::vector<std::string> keys;  // the tasks' keys within the caller's scope
  for (const CurveTask& task : tasks) keys.push_back(cache::Scoped(options.scope, task.key));
  // 1. The cache: exact key, then a similar tyre.
  for (size_t i = 0; i < tasks.size(); ++i) {
    auto found = LookUpCurve(store_, tier, tasks[i].request, keys[i], options.allow_similarity,
                             options.scope);
    if (!found) continue;
    Resolution& r = out[i];
    r.source = found->similarity ? CurveSource::kCacheSimilar : CurveSource::kCacheExact;
    r.curve = found->curve;
    r.stored = found->source;
    r.cached = std::move(found);
  }
  if (options.after_lookups) options.after_lookups(out);
  if (options.lookup_only) return out;

  // 2. The misses go to the pool, at most kInFlightPerWorker per worker at a time, so that
  //    several callers (map jobs running at once, curve queries) interleave in the pool's queue
  //    instead of one waiting behind the whole of another. Each result is stored as it arrives.
  auto inbox = std::make_shared<Inbox>();
  std::deque<size_t> unsent;
  for (size_t i = 0; i < tasks.size(); ++i) {
    if (!out[i].ok()) unsent.push_back(i);
  }
  const size_t in_flight_limit =
      std::max<size_t>(2, kInFlightPerWorker * static_cast<size_t>(std::max(1, pool_.Workers())));
  std::map<uint64_t, size_t> outstanding;  // pool task id -> task index
  auto submit_more = [&] {
    while (!unsent.empty() && outstanding.size() < in_flight_limit) {
      const size_t i = unsent.front();
      unsent.pop_front();
      TaskSpec spec;
      spec.task_id = NewTaskId();
      spec.tier = tier.Name();
      spec.request = tasks[i].request;
      spec.debug_delay_ms = options.debug_delay_ms;
      spec.needs = tier.Needs(tasks[i].request);
      if (!checkpoint_root_.empty() && spec.needs.expected_seconds >= kCheckpointedTaskSeconds) {
        spec.checkpoint_dir = CheckpointDirectory(checkpoint_root_, keys[i]);
        std::error_code error;
        std::filesystem::create_directories(spec.checkpoint_dir, error);
        if (error) spec.checkpoint_dir.clear();  // computed without checkpoints then
      }
      if (options.on_task_progress) {
        spec.progress = [report = options.on_task_progress, i](double f, const std::string& note) {
          report(i, f, note);
        };
      }
      outstanding[spec.task_id] = i;
      pool_.Submit(std::move(spec), [inbox](TaskResult r) {
        std::lock_guard<std::mutex> lock(inbox->mutex);
        inbox->results.push_back(std::move(r));
        inbox->arrived.notify_one();
      });
    }
  };
  submit_more();

  bool stopped = false;
  bool failed = false;
  while (!outstanding.empty()) {
    std::deque<TaskResult> batch;
    {
      std::unique_lock<std::mutex> lock(inbox->mutex);
      inbox->arrived.wait_for(lock, std::chrono::milliseconds(100),
                              [&] { return !inbox->results.empty(); });
      batch.swap(inbox->results);
    }
    const bool discard = options.discard && options.discard();
    for (TaskResult& result : batch) {
      if (discard && result.ok) {
        result.ok = false;
        result.cancelled = true;
        result.error = "cancelled";
      }
      auto it = outstanding.find(result.task_id);
      if (it == outstanding.end()) continue;
      const size_t i = it->second;
      outstanding.erase(it);
      Resolution& r = out[i];
      if (training_history_keeper_ && !result.training_histories.empty()) {
        try {
          training_history_keeper_(tier, tasks[i], result);
        } catch (const std::exception& e) {
          spdlog::warn("traction task {} ({}): its {} paths for training were not kept: {}",
                       result.task_id, tier.Name(), result.training_histories.size(), e.what());
        }
      }
      if (!result.cancelled && !checkpoint_root_.empty()) {
        std::error_code ignored;  // stored or failed: the restart files are of no more use
        std::filesystem::remove_all(CheckpointDirectory(checkpoint_root_, keys[i]), ignored);
      }
      if (result.ok) {
        result.curve.tier = tier.Name();
        r.source = CurveSource::kComputed;
        r.stored = cache::StoredCurve{keys[i],        tasks[i].request,
                                      result.curve,        result.computed_by,
                                      result.compute_seconds, NowMs(), options.scope};
        store_.Put(r.stored);  // committed now: a crash loses no finished curve
        r.curve = std::move(result.curve);
      } else {
        r.source = result.cancelled ? CurveSource::kCancelled : CurveSource::kFailed;
        r.error_kind = result.cancelled ? ErrorKind::kCancelled : result.error_kind;
        r.error = result.error;
        failed = failed || !result.cancelled;
        if (!result.cancelled) {
          spdlog::warn("traction task {} ({}) failed, {}: {}", result.task_id, tier.Name(),
                       ErrorKindName(result.error_kind), result.error);
        }
      }
      if (options.on_task_end) options.on_task_end(i, r);
    }
    const bool stop = (options.stop && options.stop()) ||
                      std::chrono::steady_clock::now() > options.deadline ||
                      (failed && options.stop_on_failure);
    if (stop && !stopped) {
      for (const auto& [task_id, _] : outstanding) pool_.Cancel(task_id);
      stopped = true;
    }
    if (!stopped) submit_more();
  }
  // What was never sent is cancelled.
  for (size_t i : unsent) {
    out[i].source = CurveSource::kCancelled;
    out[i].error_kind = ErrorKind::kCancelled;
    out[i].error = "cancelled";
  }
  return out;
}

void FillResolved(const TractionRequest& request, const Resolution& answer,
                  v1::TractionCurve* out) {
  if (answer.cached) {
    FillAnswer(request, *answer.cached, out);
  } else {
    FillCurve(answer.stored, false, out);
  }
}

}  // namespace gonogo::server
