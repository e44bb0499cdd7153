// The MPI worker pool (ARCHITECTURE section 5). Rank 0 owns an MpiPool whose single communication
// thread is the only thread of the process that calls MPI; ranks 1..N-1 run RunMpiWorker().
//
// Messages (tags): rank 0 -> worker TASK (a serialised v1.WorkerTask), CANCEL (the 8-byte task id),
// STOP (empty); worker -> rank 0 HELLO (empty, once, when its loop starts: the rank has checked
// in and gets tasks from then on), RESULT (a serialised v1.WorkerResult) and PROGRESS (a
// v1.WorkerProgress, at most twice a second). A worker holds at most one task. Idle loops poll with
// MPI_Iprobe and an exponential back-off sleep instead of blocking in MPI_Recv, which would spin a
// core at 100 % (PLATFORM-NOTES).
//
// Rank groups: a task whose tier needs k > 1 ranks (TaskSpec::needs.ranks, capped at the number of
// workers) is sent to k free workers at once with the list of the group's world ranks. They create
// the group's communicator together (MPI_Comm_create_group, collective on the group only, so the
// other workers and rank 0 are not involved), run the tier collectively on it, and each sends a
// RESULT; the leader's (the group's rank 0) carries the curve. Meanwhile one-rank tasks flow to the
// remaining workers. When the next task is a group that does not fit, free workers are held for it
// until it does (it would otherwise starve behind a stream of one-rank tasks).
//
// The queue has two lanes, cheap and long (server/task_queue.h), served in turn.
#pragma once

#include <atomic>
#include <deque>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "server/task_queue.h"
#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// True when this process was started by an MPI launcher (mpirun, srun); read from the environment
// before MPI_Init so that a plain `gonogo-server` never touches MPI.
bool LaunchedUnderMpi();

class MpiPool : public WorkerPool {
 public:
  // `world_size` ranks, of which 1..world_size-1 are workers. MPI must be initialised with at least
  // MPI_THREAD_SERIALIZED.
  explicit MpiPool(int world_size);
  ~MpiPool() override;

  void Submit(TaskSpec task, TaskCallback done) override;
  void Cancel(uint64_t task_id) override;
  int Workers() const override { return world_size_ - 1; }
  int ReadyWorkers() const override { return ready_workers_.load(); }
  std::string Describe() const override;
  // Stops every worker rank (they return from RunMpiWorker) and joins the communication thread.
  void Shutdown() override;

 private:
  struct Entry {
    TaskSpec task;
    TaskCallback done;
  };
  // A task on its worker(s): the ranks still to report and the leader's result once it is in.
  struct Running {
    Entry entry;
    std::vector<int> ranks;  // world ranks, leader first
    int outstanding = 0;
    TaskResult leader_result;
    bool cancel_sent = false;
  };
  void CommLoop();

  const int world_size_;
  std::atomic<int> ready_workers_{0};
  std::mutex mutex_;
  TwoLaneQueue<Entry> queue_;
  std::vector<uint64_t> cancels_;
  bool stopping_ = false;
  std::thread comm_;
};

// The loop of a worker rank; returns when rank 0 sends STOP.
void RunMpiWorker(const TierRegistry& tiers, int rank);

}  // namespace gonogo::server
