// The embedded default: traction tasks on threads of the server process.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/task_queue.h"
#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

class ThreadPool : public WorkerPool {
 public:
  ThreadPool(const TierRegistry& tiers, int threads);
  ~ThreadPool() override;

  void Submit(TaskSpec task, TaskCallback done) override;
  void Cancel(uint64_t task_id) override;
  int Workers() const override { return static_cast<int>(threads_.size()); }
  std::string Describe() const override;
  void Shutdown() override;

 private:
  struct Entry {
    TaskSpec task;
    TaskCallback done;
    std::shared_ptr<std::atomic<bool>> cancel = std::make_shared<std::atomic<bool>>(false);
  };
  void Loop();

  const TierRegistry& tiers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  TwoLaneQueue<Entry> queue_;
  std::map<uint64_t, std::shared_ptr<std::atomic<bool>>> running_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace gonogo::server
