#include "server/pool_wait.h"

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>

namespace gonogo::server {

std::vector<TaskResult> RunAndWait(WorkerPool& pool, std::vector<TaskSpec> tasks,
                                   std::chrono::steady_clock::time_point deadline,
                                   const std::function<bool()>& abandon) {
  struct Shared {
    std::mutex mutex;
    std::condition_variable done;
    std::map<uint64_t, TaskResult> results;
  };
  auto shared = std::make_shared<Shared>();
  std::vector<uint64_t> ids;
  for (TaskSpec& t : tasks) {
    ids.push_back(t.task_id);
    pool.Submit(std::move(t), [shared](TaskResult r) {
      std::lock_guard<std::mutex> lock(shared->mutex);
      shared->results[r.task_id] = std::move(r);
      shared->done.notify_all();
    });
  }
  bool cancelled = false;
  std::unique_lock<std::mutex> lock(shared->mutex);
  while (shared->results.size() < ids.size()) {
    shared->done.wait_for(lock, std::chrono::milliseconds(100));
    if (!cancelled && (std::chrono::steady_clock::now() > deadline || (abandon && abandon()))) {
      cancelled = true;
      lock.unlock();
      for (uint64_t id : ids) pool.Cancel(id);
      lock.lock();
    }
  }
  std::vector<TaskResult> out;
  for (uint64_t id : ids) out.push_back(std::move(shared->results[id]));
  return out;
}

}  // namespace gonogo::server
