// The MPI worker pool (ARCHITECTURE section 5). Rank 0 owns an MpiPool whose single communication
// thread is the only thread of the process that calls MPI; ranks 1..N-1 run RunMpiWorker().
//
// Messages (tags): rank 0 -> worker TASK (a serialised v1.WorkerTask), CANCEL (the 8-byte task id),
// STOP (empty); worker -> rank 0 RESULT (a serialised v1.WorkerResult). A worker holds at most one
// task. Idle loops poll with MPI_Iprobe and an exponential back-off sleep instead of blocking in
// MPI_Recv, which would spin a core at 100 % (PLATFORM-NOTES).
#pragma once

#include <atomic>
#include <deque>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

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
  std::string Describe() const override;
  // Stops every worker rank (they return from RunMpiWorker) and joins the communication thread.
  void Shutdown() override;

 private:
  struct Entry {
    TaskSpec task;
    TaskCallback done;
  };
  void CommLoop();

  const int world_size_;
  std::mutex mutex_;
  std::deque<Entry> queue_;
  std::vector<uint64_t> cancels_;
  bool stopping_ = false;
  std::thread comm_;
};

// The loop of a worker rank; returns when rank 0 sends STOP.
void RunMpiWorker(const TierRegistry& tiers, int rank);

}  // namespace gonogo::server
