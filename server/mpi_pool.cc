#include "server/mpi_pool.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <optional>

#include "server/convert.h"
#include "server/task_runner.h"

namespace gonogo::server {

namespace {

enum Tag : int { kTagTask = 1, kTagResult = 2, kTagCancel = 3, kTagStop = 4 };

// Back-off for idle polling: 50 us doubling to 5 ms, reset by any message.
class Backoff {
 public:
  void Reset() { us_ = 50; }
  void Sleep() {
    std::this_thread::sleep_for(std::chrono::microseconds(us_));
    us_ = std::min(us_ * 2, 5000);
  }

 private:
  int us_ = 50;
};

std::string Receive(int source, int tag, int* from = nullptr) {
  MPI_Status status;
  MPI_Probe(source, tag, MPI_COMM_WORLD, &status);
  int bytes = 0;
  MPI_Get_count(&status, MPI_BYTE, &bytes);
  std::string buffer(static_cast<size_t>(bytes), '\0');
  MPI_Recv(buffer.data(), bytes, MPI_BYTE, status.MPI_SOURCE, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (from) *from = status.MPI_SOURCE;
  return buffer;
}

void Send(const std::string& bytes, int dest, int tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}

}  // namespace

bool LaunchedUnderMpi() {
  // mpirun sets OMPI_COMM_WORLD_SIZE; srun --mpi=pmix sets PMIX_RANK.
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMIX_RANK") != nullptr;
}

MpiPool::MpiPool(int world_size) : world_size_(world_size) {
  comm_ = std::thread([this] { CommLoop(); });
}

MpiPool::~MpiPool() { Shutdown(); }

std::string MpiPool::Describe() const {
  return "MPI pool of " + std::to_string(world_size_ - 1) + " worker ranks";
}

void MpiPool::Submit(TaskSpec task, TaskCallback done) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stopping_) {
      queue_.push_back(Entry{std::move(task), std::move(done)});
      return;
    }
  }
  done(CancelledResult(task.task_id, kShuttingDown));
}

void MpiPool::Cancel(uint64_t task_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  cancels_.push_back(task_id);
}

void MpiPool::CommLoop() {
  // busy[w]: the task rank w is computing.
  std::vector<std::optional<Entry>> busy(world_size_);
  std::vector<bool> cancel_sent(world_size_, false);
  Backoff backoff;
  for (;;) {
    std::vector<std::pair<int, std::string>> to_send;  // (rank, serialised task)
    std::vector<Entry> cancelled_queued;
    std::vector<uint64_t> cancels;
    bool stopping;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping = stopping_;
      cancels.swap(cancels_);
      for (uint64_t id : cancels) {
        auto it = std::find_if(queue_.begin(), queue_.end(),
                               [&](const Entry& e) { return e.task.task_id == id; });
        if (it != queue_.end()) {
          cancelled_queued.push_back(std::move(*it));
          queue_.erase(it);
        }
      }
      if (stopping) {
        for (Entry& e : queue_) cancelled_queued.push_back(std::move(e));
        queue_.clear();
      }
      for (int w = 1; w < world_size_ && !queue_.empty(); ++w) {
        if (busy[w]) continue;
        busy[w] = std::move(queue_.front());
        queue_.pop_front();
        cancel_sent[w] = false;
        to_send.emplace_back(w, ToWorkerTask(busy[w]->task).SerializeAsString());
      }
    }
    bool did_work = !to_send.empty() || !cancelled_queued.empty();
    for (Entry& e : cancelled_queued) {
      e.done(CancelledResult(e.task.task_id, stopping ? kShuttingDown : "cancelled"));
    }
    for (const auto& [rank, bytes] : to_send) Send(bytes, rank, kTagTask);
    // Cancellation of running tasks, and of every running task while stopping.
    for (int w = 1; w < world_size_; ++w) {
      if (!busy[w] || cancel_sent[w]) continue;
      const uint64_t id = busy[w]->task.task_id;
      if (stopping || std::find(cancels.begin(), cancels.end(), id) != cancels.end()) {
        Send(std::string(reinterpret_cast<const char*>(&id), sizeof id), w, kTagCancel);
        cancel_sent[w] = true;
      }
    }
    // Results.
    for (;;) {
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &status);
      if (!flag) break;
      int from = 0;
      v1::WorkerResult result;
      result.ParseFromString(Receive(status.MPI_SOURCE, kTagResult, &from));
      did_work = true;
      if (!busy[from]) continue;
      Entry entry = std::move(*busy[from]);
      busy[from].reset();
      entry.done(FromWorkerResult(result, entry.task.tier, "rank " + std::to_string(from)));
    }
    const bool any_busy = std::any_of(busy.begin(), busy.end(), [](const auto& b) { return b; });
    if (stopping && !any_busy) break;
    if (did_work) {
      backoff.Reset();
    } else {
      backoff.Sleep();
    }
  }
  for (int w = 1; w < world_size_; ++w) Send("", w, kTagStop);
}

void MpiPool::Shutdown() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  if (comm_.joinable()) comm_.join();
}

void RunMpiWorker(const TierRegistry& tiers, int rank) {
  const std::string me = "rank " + std::to_string(rank);
  Backoff backoff;
  for (;;) {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
    if (!flag) {
      backoff.Sleep();
      continue;
    }
    backoff.Reset();
    if (status.MPI_TAG == kTagStop) {
      Receive(0, kTagStop);
      return;
    }
    if (status.MPI_TAG == kTagCancel) {  // for a task already finished: nothing to stop
      Receive(0, kTagCancel);
      continue;
    }
    v1::WorkerTask wire;
    TaskResult result;
    if (!wire.ParseFromString(Receive(0, kTagTask))) {
      result.error = "malformed task message";
    } else {
      const TaskSpec task = FromWorkerTask(wire);
      // Cancellation check: polls for a CANCEL of this task at most once a millisecond.
      bool cancelled = false;
      auto last_poll = std::chrono::steady_clock::now();
      auto check = [&]() {
        if (cancelled) return true;
        const auto now = std::chrono::steady_clock::now();
        if (now - last_poll < std::chrono::milliseconds(1)) return false;
        last_poll = now;
        int pending = 0;
        MPI_Iprobe(0, kTagCancel, MPI_COMM_WORLD, &pending, MPI_STATUS_IGNORE);
        while (pending) {
          const std::string id_bytes = Receive(0, kTagCancel);
          uint64_t id = 0;
          std::copy(id_bytes.begin(), id_bytes.end(), reinterpret_cast<char*>(&id));
          cancelled = cancelled || id == task.task_id;
          MPI_Iprobe(0, kTagCancel, MPI_COMM_WORLD, &pending, MPI_STATUS_IGNORE);
        }
        return cancelled;
      };
      result = RunTask(tiers, task, check, me);
    }
    Send(ToWorkerResult(result).SerializeAsString(), 0, kTagResult);
  }
}

}  // namespace gonogo::server
