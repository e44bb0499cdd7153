#include "server/thread_pool.h"

#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>

#include "server/task_queue.h"
#include "server/task_runner.h"
#include "solvers/tiers/builtin_tiers.h"
#include "solvers/tiers/diagnostic_tiers.h"

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
  TaskResult r = RunTask(tiers, bad_tier, ComputeContext{}, "thread");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("tier"), std::string::npos);
  EXPECT_EQ(r.error_kind, ErrorKind::kBadInput);
  EXPECT_EQ(r.error_field, "tier");
  TaskResult nan = RunTask(tiers, Task(2, NAN), ComputeContext{}, "thread");
  EXPECT_FALSE(nan.ok);
  EXPECT_NE(nan.error.find("cone_index_pa"), std::string::npos) << nan.error;
  EXPECT_EQ(nan.error_kind, ErrorKind::kBadInput);
  TaskResult good = RunTask(tiers, Task(3, 3e5), ComputeContext{}, "thread");
  EXPECT_TRUE(good.ok);
  EXPECT_EQ(good.error_kind, ErrorKind::kNone);
  EXPECT_EQ(good.curve.points.size(), 11u);
}

TEST(RunTask, ErrorsKeepTheirKind) {
  TierRegistry tiers;
  RegisterBuiltinTiers(tiers);
  RegisterDiagnosticTiers(tiers);
  TaskSpec failing = Task(1, 3e5);
  failing.tier = "diagnostic-numerical-failure";
  const TaskResult numerical = RunTask(tiers, failing, ComputeContext{}, "thread");
  EXPECT_FALSE(numerical.ok);
  EXPECT_FALSE(numerical.cancelled);
  EXPECT_EQ(numerical.error_kind, ErrorKind::kNumerical);
  EXPECT_NE(numerical.error.find("did not converge"), std::string::npos) << numerical.error;

  ComputeContext cancelled;
  cancelled.cancelled = [] { return true; };
  const TaskResult stopped = RunTask(tiers, Task(2, 3e5), cancelled, "thread");
  EXPECT_TRUE(stopped.cancelled);
  EXPECT_EQ(stopped.error_kind, ErrorKind::kCancelled);

  // Alone (no communicator), the rank-group probe still answers: every tier must run on one rank.
  TaskSpec group = Task(3, 3e5);
  group.tier = "diagnostic-rank-group";
  const TaskResult alone = RunTask(tiers, group, ComputeContext{}, "thread");
  ASSERT_TRUE(alone.ok) << alone.error;
  EXPECT_EQ(alone.curve.points.size(), 11u);
}

TEST(TwoLaneQueue, AlternatesBetweenCheapAndLongTasks) {
  struct Entry {
    TaskSpec task;
  };
  TwoLaneQueue<Entry> queue;
  auto push = [&](uint64_t id, double seconds) {
    Entry e;
    e.task.task_id = id;
    e.task.needs.expected_seconds = seconds;
    queue.Push(std::move(e));
  };
  push(1, 600);  // long
  push(2, 600);
  for (uint64_t id = 10; id < 14; ++id) push(id, 0.001);  // cheap
  std::vector<uint64_t> order;
  while (!queue.Empty()) order.push_back(queue.Pop().task.task_id);
  // The cheap lane goes first, then the lanes take turns; a lane left alone drains.
  EXPECT_EQ(order, (std::vector<uint64_t>{10, 1, 11, 2, 12, 13}));

  push(20, 0.001);
  Entry group;
  group.task.task_id = 21;
  group.task.needs.ranks = 2;  // a rank group is long whatever its expected time
  queue.Push(std::move(group));
  ASSERT_TRUE(queue.Remove(21).has_value());
  EXPECT_FALSE(queue.Remove(21).has_value());
  EXPECT_EQ(queue.Size(), 1u);
  EXPECT_EQ(queue.TakeAll().size(), 1u);
  EXPECT_TRUE(queue.Empty());
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
