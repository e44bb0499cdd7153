#include "server/mpi_pool.h"

#include <mpi.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>

#include "server/convert.h"
#include "server/task_runner.h"

namespace gonogo::server {

namespace {

enum Tag : int { kTagTask = 1, kTagResult = 2, kTagCancel = 3, kTagStop = 4, kTagProgress = 5,
             kTagHello = 6 };

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
      queue_.Push(Entry{std::move(task), std::move(done)});
      return;
    }
  }
  done(CancelledResult(task.task_id, kShuttingDown));
}

void MpiPool::Cancel(uint64_t task_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  cancels_.push_back(task_id);
}

namespace {

std::string RanksLabel(const std::vector<int>& ranks) {
  std::string label = ranks.size() == 1 ? "rank " : "ranks ";
  for (size_t i = 0; i < ranks.size(); ++i) label += (i ? "," : "") + std::to_string(ranks[i]);
  return label;
}

}  // namespace

void MpiPool::CommLoop() {
  // busy[w]: the task world rank w is working on (shared by the members of a group).
  std::vector<std::shared_ptr<Running>> busy(world_size_);
  std::vector<bool> checked_in(world_size_, false);
  std::map<uint64_t, std::shared_ptr<Running>> running;  // by task id
  int next_group_tag = 1;
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
        if (auto e = queue_.Remove(id)) cancelled_queued.push_back(std::move(*e));
      }
      if (stopping) {
        for (Entry& e : queue_.TakeAll()) cancelled_queued.push_back(std::move(e));
      }
      // Dispatch: the next task goes to the lowest free ranks when enough are free; a group that
      // does not fit holds the free ranks until it does.
      std::vector<int> free_ranks;
      for (int w = 1; w < world_size_; ++w) {
        if (checked_in[w] && !busy[w]) free_ranks.push_back(w);
      }
      while (const Entry* next = queue_.Peek()) {
        const int wanted = std::clamp(next->task.needs.ranks, 1, world_size_ - 1);
        // Until every rank has checked in, a group may not find its ranks yet: it waits.
        if (static_cast<int>(free_ranks.size()) < wanted) break;
        auto task = std::make_shared<Running>();
        task->entry = queue_.Pop();
        task->ranks.assign(free_ranks.begin(), free_ranks.begin() + wanted);
        free_ranks.erase(free_ranks.begin(), free_ranks.begin() + wanted);
        task->outstanding = wanted;
        v1::WorkerTask wire = ToWorkerTask(task->entry.task);
        if (wanted > 1) {
          for (int r : task->ranks) wire.add_group_ranks(r);
          wire.set_group_tag(next_group_tag);
          next_group_tag = next_group_tag % 30000 + 1;  // within the guaranteed MPI_TAG_UB
        }
        if (wanted > 1) {
          spdlog::debug("task {} ({}) to the rank group {}", task->entry.task.task_id,
                        task->entry.task.tier, RanksLabel(task->ranks));
        }
        const std::string bytes = wire.SerializeAsString();
        for (int r : task->ranks) {
          busy[r] = task;
          to_send.emplace_back(r, bytes);
        }
        running[task->entry.task.task_id] = task;
      }
    }
    bool did_work = !to_send.empty() || !cancelled_queued.empty();
    for (Entry& e : cancelled_queued) {
      e.done(CancelledResult(e.task.task_id, stopping ? kShuttingDown : "cancelled"));
    }
    for (const auto& [rank, bytes] : to_send) Send(bytes, rank, kTagTask);
    // Cancellation of running tasks (every member of a group), and of all of them while stopping.
    for (auto& [id, task] : running) {
      if (task->cancel_sent) continue;
      if (stopping || std::find(cancels.begin(), cancels.end(), id) != cancels.end()) {
        for (int r : task->ranks) {
          Send(std::string(reinterpret_cast<const char*>(&id), sizeof id), r, kTagCancel);
        }
        task->cancel_sent = true;
      }
    }
    // Worker ranks checking in.
    for (;;) {
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagHello, MPI_COMM_WORLD, &flag, &status);
      if (!flag) break;
      int from = 0;
      Receive(status.MPI_SOURCE, kTagHello, &from);
      did_work = true;
      if (!checked_in[from]) {
        checked_in[from] = true;
        const int ready = ++ready_workers_;
        spdlog::debug("rank {} checked in ({} of {})", from, ready, world_size_ - 1);
      }
    }
    // Progress reports of running tasks.
    for (;;) {
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagProgress, MPI_COMM_WORLD, &flag, &status);
      if (!flag) break;
      v1::WorkerProgress progress;
      progress.ParseFromString(Receive(status.MPI_SOURCE, kTagProgress));
      did_work = true;
      auto it = running.find(progress.task_id());
      if (it != running.end() && it->second->entry.task.progress) {
        it->second->entry.task.progress(progress.fraction(), progress.note());
      }
    }
    // Results: a task ends when every member has reported; the leader's result is its answer.
    for (;;) {
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &status);
      if (!flag) break;
      int from = 0;
      v1::WorkerResult result;
      result.ParseFromString(Receive(status.MPI_SOURCE, kTagResult, &from));
      did_work = true;
      std::shared_ptr<Running> task = std::move(busy[from]);
      if (!task) continue;
      const std::string label = RanksLabel(task->ranks);
      if (from == task->ranks.front()) {
        task->leader_result = FromWorkerResult(result, task->entry.task.tier, label);
      } else if (!result.ok() && task->leader_result.ok) {
        // A member failed where the leader did not: the task failed.
        task->leader_result = FromWorkerResult(result, task->entry.task.tier, label);
      }
      if (--task->outstanding > 0) continue;
      running.erase(task->entry.task.task_id);
      task->entry.done(std::move(task->leader_result));
    }
    if (stopping && running.empty()) break;
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

namespace {

// Drains CANCEL messages from rank 0; true when one names `task_id`.
bool ReceiveCancels(uint64_t task_id) {
  bool mine = false;
  int pending = 0;
  MPI_Iprobe(0, kTagCancel, MPI_COMM_WORLD, &pending, MPI_STATUS_IGNORE);
  while (pending) {
    const std::string id_bytes = Receive(0, kTagCancel);
    uint64_t id = 0;
    std::copy(id_bytes.begin(), id_bytes.end(), reinterpret_cast<char*>(&id));
    mine = mine || id == task_id;
    MPI_Iprobe(0, kTagCancel, MPI_COMM_WORLD, &pending, MPI_STATUS_IGNORE);
  }
  return mine;
}

// The communicator of a task's rank group; MPI_COMM_NULL for a one-rank task. Collective on the
// group's members only.
MPI_Comm GroupCommunicator(const v1::WorkerTask& wire) {
  if (wire.group_ranks_size() < 2) return MPI_COMM_NULL;
  MPI_Group world_group = MPI_GROUP_NULL, group = MPI_GROUP_NULL;
  MPI_Comm_group(MPI_COMM_WORLD, &world_group);
  MPI_Group_incl(world_group, wire.group_ranks_size(), wire.group_ranks().data(), &group);
  MPI_Comm comm = MPI_COMM_NULL;
  MPI_Comm_create_group(MPI_COMM_WORLD, group, wire.group_tag(), &comm);
  MPI_Group_free(&group);
  MPI_Group_free(&world_group);
  return comm;
}

TaskResult RunWorkerTask(const TierRegistry& tiers, const v1::WorkerTask& wire, int rank) {
  const TaskSpec task = FromWorkerTask(wire);
  const MPI_Comm comm = GroupCommunicator(wire);
  const bool leader = wire.group_ranks_size() < 2 || wire.group_ranks(0) == rank;
  ComputeContext context;
  context.communicator = comm;
  context.threads = task.needs.threads;
  context.checkpoint_dir = task.checkpoint_dir;
  bool cancelled = false;
  auto last_poll = std::chrono::steady_clock::now();
  if (comm == MPI_COMM_NULL) {
    // Polls for a CANCEL of this task at most once a millisecond.
    context.cancelled = [&]() {
      const auto now = std::chrono::steady_clock::now();
      if (cancelled || now - last_poll < std::chrono::milliseconds(1)) return cancelled;
      last_poll = now;
      cancelled = ReceiveCancels(task.task_id) || cancelled;
      return cancelled;
    };
  } else {
    // Collective: every member polls its own CANCEL and the group agrees (logical or), so all
    // members stop at the same call.
    context.cancelled = [&]() {
      int mine = (ReceiveCancels(task.task_id) || cancelled) ? 1 : 0;
      int any = 0;
      MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, comm);
      cancelled = any != 0;
      return cancelled;
    };
  }
  // Outlives the progress callback, which captures it (at most two reports a second).
  auto last_report = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  std::string latest_note;  // the tier's, sent with its next fraction
  if (leader) {
    context.progress_note = [&](const std::string& note) { latest_note = note; };
    context.progress = [&](double fraction) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_report < std::chrono::milliseconds(500)) return;
      last_report = now;
      v1::WorkerProgress p;
      p.set_task_id(task.task_id);
      p.set_fraction(fraction);
      p.set_note(latest_note);
      Send(p.SerializeAsString(), 0, kTagProgress);
    };
  }
  // computed_by is not sent: rank 0 labels the result with the ranks it dispatched to.
  TaskResult result = RunTask(tiers, task, context, "rank " + std::to_string(rank));
  if (comm != MPI_COMM_NULL) {
    MPI_Comm comm_to_free = comm;
    MPI_Comm_free(&comm_to_free);
  }
  return result;
}

}  // namespace

void RunMpiWorker(const TierRegistry& tiers, int rank) {
  Send("", 0, kTagHello);
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
      result.error_kind = ErrorKind::kInternal;
      result.error = "malformed task message";
    } else {
      result = RunWorkerTask(tiers, wire, rank);
    }
    Send(ToWorkerResult(result).SerializeAsString(), 0, kTagResult);
  }
}

}  // namespace gonogo::server
