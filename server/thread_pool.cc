#include "server/thread_pool.h"

#include <algorithm>
#include <string>

#include "server/task_runner.h"

namespace gonogo::server {

ThreadPool::ThreadPool(const TierRegistry& tiers, int threads) : tiers_(tiers) {
  for (int i = 0; i < std::max(1, threads); ++i) threads_.emplace_back([this] { Loop(); });
}

ThreadPool::~ThreadPool() { Shutdown(); }

std::string ThreadPool::Describe() const {
  return "in-process pool of " + std::to_string(threads_.size()) + " threads";
}

void ThreadPool::Submit(TaskSpec task, TaskCallback done) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stopping_) {
      queue_.Push(Entry{std::move(task), std::move(done)});
      wake_.notify_one();
      return;
    }
  }
  done(CancelledResult(task.task_id, kShuttingDown));
}

void ThreadPool::Cancel(uint64_t task_id) {
  TaskCallback done;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto running = running_.find(task_id);
    if (running != running_.end()) {
      running->second->store(true);
      return;
    }
    std::optional<Entry> queued = queue_.Remove(task_id);
    if (!queued) return;
    done = std::move(queued->done);
  }
  done(CancelledResult(task_id, "cancelled"));
}

void ThreadPool::Loop() {
  for (;;) {
    Entry entry;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.Empty(); });
      if (queue_.Empty()) return;
      entry = queue_.Pop();
      running_[entry.task.task_id] = entry.cancel;
    }
    auto flag = entry.cancel;
    // A task that asks for several ranks runs alone here (no communicator): every tier must.
    ComputeContext context;
    context.cancelled = [flag] { return flag->load(); };
    std::string latest_note;  // the tier's, sent with its next fraction (both on this thread)
    if (entry.task.progress) {
      context.progress_note = [&latest_note](const std::string& note) { latest_note = note; };
      context.progress = [&latest_note, &report = entry.task.progress](double fraction) {
        report(fraction, latest_note);
      };
    }
    context.threads = std::max(1, entry.task.needs.threads);
    context.checkpoint_dir = entry.task.checkpoint_dir;
    TaskResult r = RunTask(tiers_, entry.task, context, "thread");
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_.erase(entry.task.task_id);
    }
    entry.done(std::move(r));
  }
}

void ThreadPool::Shutdown() {
  std::vector<Entry> dropped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
    dropped = queue_.TakeAll();
    for (auto& [id, flag] : running_) flag->store(true);
    wake_.notify_all();
  }
  for (Entry& e : dropped) e.done(CancelledResult(e.task.task_id, kShuttingDown));
  for (auto& t : threads_) t.join();
  threads_.clear();
}

}  // namespace gonogo::server
