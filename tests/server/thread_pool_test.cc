#include "server/thread_pool.h"

#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>

#include "server/task_runner.h"
#include "solvers/tiers/builtin_tiers.h"

namespace gonogo::server {
namespace {

TaskSpec Task(uint64_t id, double cone_index_pa, uint32_t delay_ms = 0) {
  TaskSpec t;
  t.task_id = id;
  t.tier = "empirical";
  t.request.soil.cone_index_pa = cone_index_pa;
  t.request.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0};
  t.request.wheel_load_n = 13438;
  t.request.slips = TractionRequest::SlipSweep(0.1);
  t.debug_delay_ms = delay_ms;
  return t;
}

struct Collector {
  std::mutex m;
  std::condition_variable cv;
  std::vector<TaskResult> results;
  TaskCallback Callback() {
    return [this](TaskResult r) {
      std::lock_guard<std::mutex> l(m);
      results.push_back(std::move(r));
      cv.notify_all();
    };
  }
  void WaitFor(size_t n) {
    std::unique_lock<std::mutex> l(m);
    cv.wait_for(l, std::chrono::seconds(20), [&] { return results.size() >= n; });
  }
};

TEST(RunTask, ErrorsComeBackAsResultsNeverAsExceptions) {
  TierRegistry tiers;
  RegisterBuiltinTiers(tiers);
  TaskSpec bad_tier = Task(1, 3e5);
  bad_tier.tier = "nope";
  TaskResult r = RunTask(tiers, bad_tier, nullptr, "thread");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("tier"), std::string::npos);
  TaskResult nan = RunTask(tiers, Task(2, NAN), nullptr, "thread");
  EXPECT_FALSE(nan.ok);
  EXPECT_NE(nan.error.find("cone_index_pa"), std::string::npos) << nan.error;
  TaskResult good = RunTask(tiers, Task(3, 3e5), nullptr, "thread");
  EXPECT_TRUE(good.ok);
  EXPECT_EQ(good.curve.points.size(), 11u);
}

TEST(ThreadPool, RunsEveryTaskAndCancelsQueuedOnes) {
  TierRegistry tiers;
  RegisterBuiltinTiers(tiers);
  ThreadPool pool(tiers, 1);
  Collector c;
  pool.Submit(Task(1, 3e5, 300), c.Callback());  // occupies the only thread
  for (uint64_t id = 2; id <= 5; ++id) pool.Submit(Task(id, 3e5), c.Callback());
  pool.Cancel(4);  // still queued
  pool.Cancel(1);  // running: its delay loop sees the flag
  c.WaitFor(5);
  ASSERT_EQ(c.results.size(), 5u);
  int ok = 0, cancelled = 0;
  for (const auto& r : c.results) {
    ok += r.ok;
    cancelled += r.cancelled;
    if (r.task_id == 1 || r.task_id == 4) {
      EXPECT_TRUE(r.cancelled) << r.task_id;
    }
  }
  EXPECT_EQ(ok, 3);
  EXPECT_EQ(cancelled, 2);
}

TEST(ThreadPool, ShutdownCancelsWhatIsQueued) {
  TierRegistry tiers;
  RegisterBuiltinTiers(tiers);
  Collector c;
  {
    ThreadPool pool(tiers, 1);
    for (uint64_t id = 1; id <= 4; ++id) pool.Submit(Task(id, 3e5, 100), c.Callback());
    pool.Shutdown();
  }
  EXPECT_EQ(c.results.size(), 4u) << "every callback runs exactly once";
}

}  // namespace
}  // namespace gonogo::server
