#include "solvers/bridge/distributed_point_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/material/checkpoint_files.h"

namespace gonogo::bridge {

using material::ConstitutiveModel;
using material::MaterialState;
using material::Matrix3;
using material::PointHandle;
using material::PointIncrement;
using material::PointResponse;
using material::TrialResponse;
using material::UpdateStatus;
namespace checkpoint = material::checkpoint;

namespace {

// Tags on the group's communicator.
enum Tag : int { kTagCommand = 101, kTagReply = 102, kTagState = 103 };

enum class Command : std::uint32_t {
  kOpen = 1,
  kClose,
  kCreate,
  kTry,
  kCommit,
  kDiscard,
  kSerialize,
  kRestore,
  kMigrate,
  kWriteCheckpoint,
  kReadCheckpoint,
  kApplyCheckpoint,
  kDropCheckpoint,
  kCall,
  kFinish,
};


// Back-off for polling: 20 us doubling to 2 ms, so an idle server costs nothing and a busy group
// answers within a fraction of a DE increment.
class Backoff {
 public:
  void Sleep() {
    std::this_thread::sleep_for(std::chrono::microseconds(us_));
    us_ = std::min(us_ * 2, 2000);
  }

 private:
  int us_ = 20;
};

std::string ReceivePolling(MPI_Comm comm, int source, int tag) {
  Backoff backoff;
  MPI_Status status;
  for (;;) {
    int flag = 0;
    MPI_Iprobe(source, tag, comm, &flag, &status);
    if (flag) break;
    backoff.Sleep();
  }
  int bytes = 0;
  MPI_Get_count(&status, MPI_BYTE, &bytes);
  std::string buffer(static_cast<std::size_t>(bytes), '\0');
  MPI_Recv(buffer.data(), bytes, MPI_BYTE, status.MPI_SOURCE, tag, comm, MPI_STATUS_IGNORE);
  return buffer;
}

void SendBytes(MPI_Comm comm, int dest, int tag, const std::string& bytes) {
  if (bytes.size() > static_cast<std::size_t>(INT32_MAX)) {
    throw LimitError("message", "one message of " + std::to_string(bytes.size()) +
                                    " bytes exceeds MPI's 2 GiB count limit");
  }
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, dest, tag, comm);
}

ByteWriter CommandHeader(Command command, std::int64_t store_id) {
  ByteWriter out;
  out.Put(static_cast<std::uint32_t>(command));
  out.Put(store_id);
  return out;
}

std::string OkReply(const std::string& payload = {}) {
  ByteWriter out;
  out.Put(static_cast<std::uint8_t>(1));
  std::string bytes = out.Take();
  return bytes + payload;
}

std::string ErrorReply(const std::string& message) {
  ByteWriter out;
  out.Put(static_cast<std::uint8_t>(0));
  out.PutBlob(message);
  return out.Take();
}

// One point's update, alone, timed: the unit of work wherever the point lives, so that the
// result does not depend on where or with which other points it runs.
struct PointResult {
  TrialResponse trial;
  std::unique_ptr<MaterialState> state;
  double seconds = 0;
};

std::vector<PointResult> UpdatePoints(const ConstitutiveModel& model,
                                      const std::vector<const MaterialState*>& committed,
                                      const std::vector<Matrix3>& increments, bool want_tangent,
                                      int threads) {
  const int count = static_cast<int>(committed.size());
  std::vector<PointResult> results(committed.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::max(1, threads))
  for (int k = 0; k < count; ++k) {
    PointResult& result = results[k];
    const auto start = std::chrono::steady_clock::now();
    try {
      std::vector<PointIncrement> one(1);
      one[0].displacement_gradient_increment = increments[k];
      one[0].committed = committed[k];
      std::vector<PointResponse> responses = model.Update(one, want_tangent);
      PointResponse& response = responses.at(0);
      result.trial.status = response.status;
      result.trial.reason = std::move(response.reason);
      result.trial.stress_pa = response.stress_pa;
      result.trial.has_tangent = response.has_tangent;
      if (response.has_tangent) result.trial.tangent_pa = response.tangent_pa;
      if (response.status == UpdateStatus::kOk && response.state == nullptr) {
        result.trial.status = UpdateStatus::kFailed;
        result.trial.reason = model.Name() + " returned kOk without a state";
      }
      if (result.trial.status == UpdateStatus::kOk) result.state = std::move(response.state);
    } catch (const std::exception& e) {
      result.trial.status = UpdateStatus::kFailed;
      result.trial.reason = e.what();
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return results;
}

void PutTrial(ByteWriter& out, const PointResult& result) {
  out.Put(static_cast<std::uint8_t>(result.trial.status == UpdateStatus::kOk ? 1 : 0));
  out.PutBlob(result.trial.reason);
  out.Put(result.trial.stress_pa);
  out.Put(static_cast<std::uint8_t>(result.trial.has_tangent ? 1 : 0));
  if (result.trial.has_tangent) {
    for (int k = 0; k < 36; ++k) out.Put(result.trial.tangent_pa.data()[k]);
  }
  out.Put(result.seconds);
}

void GetTrial(ByteReader& in, TrialResponse& trial, double& seconds) {
  std::uint8_t ok = 0, has_tangent = 0;
  in.Get(ok);
  trial.status = ok ? UpdateStatus::kOk : UpdateStatus::kFailed;
  in.GetBlob(trial.reason);
  in.Get(trial.stress_pa);
  in.Get(has_tangent);
  trial.has_tangent = has_tangent != 0;
  if (trial.has_tangent) {
    for (int k = 0; k < 36; ++k) in.Get(trial.tangent_pa.data()[k]);
  }
  in.Get(seconds);
}

// A migrating point's message: its handle, whether its state could be read, then the state or
// why not. The receiver always gets one message per move, so a failure cannot leave it waiting.
std::string StateMessage(PointHandle handle, const std::function<std::string()>& serialize) {
  ByteWriter out;
  out.Put(static_cast<std::int64_t>(handle));
  try {
    std::string state = serialize();
    out.Put(static_cast<std::uint8_t>(1));
    out.PutBlob(state);
  } catch (const std::exception& e) {
    out.Put(static_cast<std::uint8_t>(0));
    out.PutBlob(std::string("point ") + std::to_string(handle) + ": " + e.what());
  }
  return out.Take();
}

// The state in a StateMessage for `expected`; throws when it carries an error or another point.
std::string StateFromMessage(const std::string& message, PointHandle expected) {
  ByteReader in(message);
  std::int64_t handle = 0;
  std::uint8_t ok = 0;
  std::string payload;
  in.Get(handle);
  in.Get(ok);
  in.GetBlob(payload);
  if (handle != expected) throw std::logic_error("migration out of order");
  if (!ok) throw std::runtime_error(payload);
  return payload;
}

// The points of `wanted` from a checkpoint, restored through `model`.
std::unordered_map<PointHandle, std::unique_ptr<MaterialState>> LoadCheckpointPoints(
    const ConstitutiveModel& model, const std::string& directory, std::uint64_t generation,
    const std::vector<PointHandle>& wanted) {
  const checkpoint::Manifest manifest = checkpoint::ReadManifest(directory, generation);
  std::unordered_map<PointHandle, std::unique_ptr<MaterialState>> loaded;
  for (auto& [handle, bytes] : checkpoint::LoadPointBytes(directory, manifest, wanted)) {
    loaded[handle] = model.RestoreState(bytes);
  }
  return loaded;
}

// --- the server side ----------------------------------------------------------------------------

struct ServedPoint {
  std::unique_ptr<MaterialState> committed;
  std::unique_ptr<MaterialState> trial;
};

struct ServedStore {
  std::map<PointHandle, ServedPoint> points;
  std::unordered_map<PointHandle, std::unique_ptr<MaterialState>> staged;  // a checkpoint read
};

class Server {
 public:
  Server(MPI_Comm comm, const ConstitutiveModel& model, const ServeOptions& options,
         const std::function<void(int)>& on_call)
      : comm_(comm), model_(model), options_(options), on_call_(on_call) {
    MPI_Comm_rank(comm_, &rank_);
  }

  void Run() {
    Backoff backoff;
    for (;;) {
      int flag = 0;
      MPI_Iprobe(0, kTagCommand, comm_, &flag, MPI_STATUS_IGNORE);
      if (!flag) {
        backoff.Sleep();
        continue;
      }
      backoff = Backoff();
      const std::string message = ReceivePolling(comm_, 0, kTagCommand);
      ByteReader in(message);
      std::uint32_t raw = 0;
      std::int64_t store_id = 0;
      in.Get(raw);
      in.Get(store_id);
      const auto command = static_cast<Command>(raw);
      if (command == Command::kFinish) return;
      if (command == Command::kCall) {
        std::int32_t code = 0;
        in.Get(code);
        if (on_call_) on_call_(code);
        continue;
      }
      Handle(command, store_id, in);
    }
  }

 private:
  // Commands with a reply answer every time, with the error of this command or of an earlier
  // command that had none (pending_error_).
  static bool HasReply(Command command) {
    switch (command) {
      case Command::kTry:
      case Command::kSerialize:
      case Command::kRestore:
      case Command::kMigrate:
      case Command::kWriteCheckpoint:
      case Command::kReadCheckpoint:
        return true;
      default:
        return false;
    }
  }

  void Handle(Command command, std::int64_t store_id, ByteReader& in) {
    std::string reply;
    try {
      reply = Execute(command, store_id, in);
    } catch (const std::exception& e) {
      if (!HasReply(command)) {
        if (pending_error_.empty()) pending_error_ = "rank " + std::to_string(rank_) + ": " + e.what();
        return;
      }
      reply = ErrorReply("rank " + std::to_string(rank_) + ": " + e.what());
    }
    if (!HasReply(command)) return;
    if (!pending_error_.empty()) {
      reply = ErrorReply(pending_error_);
      pending_error_.clear();
    }
    SendBytes(comm_, 0, kTagReply, reply);
  }

  ServedPoint& Point(ServedStore& store, PointHandle handle) {
    auto found = store.points.find(handle);
    if (found == store.points.end()) {
      throw std::out_of_range("point " + std::to_string(handle) + " is not on this rank");
    }
    return found->second;
  }

  std::string Execute(Command command, std::int64_t store_id, ByteReader& in) {
    if (command == Command::kOpen) {
      stores_[store_id];
      return {};
    }
    auto found = stores_.find(store_id);
    if (found == stores_.end()) throw std::logic_error("no store " + std::to_string(store_id));
    ServedStore& store = found->second;
    switch (command) {
      case Command::kClose:
        stores_.erase(found);
        return {};
      case Command::kCreate: {
        std::uint64_t count = 0;
        in.Get(count);
        for (std::uint64_t k = 0; k < count; ++k) {
          std::int64_t handle = 0;
          in.Get(handle);
          store.points[handle].committed = model_.InitialState();
        }
        return {};
      }
      case Command::kTry: {
        std::uint8_t want_tangent = 0;
        std::uint64_t count = 0;
        in.Get(want_tangent);
        in.Get(count);
        std::vector<PointHandle> handles(count);
        std::vector<const MaterialState*> committed(count);
        std::vector<Matrix3> increments(count);
        for (std::uint64_t k = 0; k < count; ++k) {
          std::int64_t handle = 0;
          in.Get(handle);
          in.Get(increments[k]);
          handles[k] = handle;
          committed[k] = Point(store, handle).committed.get();
        }
        std::vector<PointResult> results =
            UpdatePoints(model_, committed, increments, want_tangent != 0, options_.threads);
        ByteWriter out;
        for (std::uint64_t k = 0; k < count; ++k) {
          PutTrial(out, results[k]);
          Point(store, handles[k]).trial = std::move(results[k].state);
        }
        return OkReply(out.Take());
      }
      case Command::kCommit:
      case Command::kDiscard: {
        std::uint64_t count = 0;
        in.Get(count);
        for (std::uint64_t k = 0; k < count; ++k) {
          std::int64_t handle = 0;
          in.Get(handle);
          ServedPoint& point = Point(store, handle);
          if (command == Command::kCommit) {
            if (point.trial == nullptr) {
              throw std::logic_error("commit of point " + std::to_string(handle) +
                                     ", which has no trial here");
            }
            point.committed = std::move(point.trial);
          } else {
            point.trial.reset();
          }
        }
        return {};
      }
      case Command::kSerialize: {
        std::int64_t handle = 0;
        in.Get(handle);
        ByteWriter out;
        out.PutBlob(Point(store, handle).committed->Serialize());
        return OkReply(out.Take());
      }
      case Command::kRestore: {
        std::int64_t handle = 0;
        std::string bytes;
        in.Get(handle);
        in.GetBlob(bytes);
        ServedPoint& point = Point(store, handle);
        point.committed = model_.RestoreState(bytes);
        point.trial.reset();
        return OkReply();
      }
      case Command::kMigrate:
        Migrate(store, in);
        return OkReply();
      case Command::kWriteCheckpoint: {
        std::string directory;
        std::uint64_t generation = 0;
        in.GetBlob(directory);
        in.Get(generation);
        std::vector<std::pair<PointHandle, std::string>> points;
        for (const auto& [handle, point] : store.points) {
          points.emplace_back(handle, point.committed->Serialize());
        }
        checkpoint::WriteFileAtomically(checkpoint::PointsFile(directory, generation, rank_),
                                        checkpoint::PointsFileBytes(model_.Name(), points));
        return OkReply();
      }
      case Command::kReadCheckpoint: {
        std::string directory;
        std::uint64_t generation = 0;
        in.GetBlob(directory);
        in.Get(generation);
        std::vector<PointHandle> wanted;
        for (const auto& [handle, point] : store.points) wanted.push_back(handle);
        store.staged = LoadCheckpointPoints(model_, directory, generation, wanted);
        return OkReply();
      }
      case Command::kApplyCheckpoint:
        for (auto& [handle, state] : store.staged) {
          ServedPoint& point = Point(store, handle);
          point.committed = std::move(state);
          point.trial.reset();
        }
        store.staged.clear();
        return {};
      case Command::kDropCheckpoint:
        store.staged.clear();
        return {};
      default:
        throw std::logic_error("unknown command " + std::to_string(static_cast<int>(command)));
    }
  }

  // Moves listed as (handle, from, to): states this rank gives are sent first (non-blocking),
  // then those it takes are received in list order (MPI keeps the order between two ranks).
  void Migrate(ServedStore& store, ByteReader& in) {
    std::uint64_t count = 0;
    in.Get(count);
    std::vector<std::string> outgoing;
    std::vector<MPI_Request> requests;
    std::vector<std::pair<PointHandle, int>> incoming;
    std::vector<PointHandle> given;
    outgoing.reserve(count);
    for (std::uint64_t k = 0; k < count; ++k) {
      std::int64_t handle = 0;
      std::int32_t from = 0, to = 0;
      in.Get(handle);
      in.Get(from);
      in.Get(to);
      if (from == rank_) {
        outgoing.push_back(
            StateMessage(handle, [&] { return Point(store, handle).committed->Serialize(); }));
        given.push_back(handle);
        requests.emplace_back();
        MPI_Isend(outgoing.back().data(), static_cast<int>(outgoing.back().size()), MPI_BYTE, to,
                  kTagState, comm_, &requests.back());
      } else if (to == rank_) {
        incoming.emplace_back(handle, from);
      }
    }
    std::string error;
    for (const auto& [handle, from] : incoming) {
      const std::string message = ReceivePolling(comm_, from, kTagState);
      try {
        store.points[handle].committed = model_.RestoreState(StateFromMessage(message, handle));
      } catch (const std::exception& e) {
        if (error.empty()) error = e.what();
      }
    }
    MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
    if (!error.empty()) throw std::runtime_error("migration: " + error);
    for (PointHandle handle : given) store.points.erase(handle);
  }

  MPI_Comm comm_;
  const ConstitutiveModel& model_;
  ServeOptions options_;
  const std::function<void(int)>& on_call_;
  int rank_ = 0;
  std::map<std::int64_t, ServedStore> stores_;
  std::string pending_error_;
};

}  // namespace

// --- RankGroupLink -----------------------------------------------------------------------------

RankGroupLink::RankGroupLink(MPI_Comm communicator) : communicator_(communicator) {
  MPI_Comm_size(communicator_, &size_);
  int rank = 0;
  MPI_Comm_rank(communicator_, &rank);
  if (rank != 0) throw std::logic_error("RankGroupLink lives on group rank 0 only");
}

RankGroupLink::~RankGroupLink() {
  try {
    Finish();
  } catch (...) {
  }
}

void RankGroupLink::Send(int rank, const std::string& bytes) {
  SendBytes(communicator_, rank, kTagCommand, bytes);
  bytes_sent_ += static_cast<std::int64_t>(bytes.size());
}

std::string RankGroupLink::Receive(int rank) {
  std::string bytes = ReceivePolling(communicator_, rank, kTagReply);
  bytes_received_ += static_cast<std::int64_t>(bytes.size());
  return bytes;
}

void RankGroupLink::Call(int code) {
  ByteWriter out = CommandHeader(Command::kCall, 0);
  out.Put(static_cast<std::int32_t>(code));
  const std::string bytes = out.Take();
  for (int r = 1; r < size_; ++r) Send(r, bytes);
}

void RankGroupLink::Finish() {
  if (finished_) return;
  finished_ = true;
  const std::string bytes = CommandHeader(Command::kFinish, 0).Take();
  for (int r = 1; r < size_; ++r) Send(r, bytes);
}

void ServeRankGroup(MPI_Comm communicator, const ConstitutiveModel& model,
                    const ServeOptions& options, const std::function<void(int code)>& on_call) {
  Server(communicator, model, options, on_call).Run();
}

// --- options -----------------------------------------------------------------------------------

void BalanceOptions::Validate(const std::string& field_prefix) const {
  Require(std::isfinite(threshold) && threshold >= 0, field_prefix + "threshold",
          "must be a finite fraction >= 0");
  Require(min_commits_between >= 1, field_prefix + "min_commits_between", "must be at least 1");
  Require(rank_zero_threads >= 1, field_prefix + "rank_zero_threads", "must be at least 1");
}

// --- DistributedPointStore ---------------------------------------------------------------------

namespace {

// The payload of a reply after its status byte, or the server's error thrown.
std::string ExpectOk(const std::string& reply) {
  ByteReader in(reply);
  std::uint8_t ok = 0;
  in.Get(ok);
  if (!ok) {
    std::string message;
    in.GetBlob(message);
    throw std::runtime_error("point server " + message);
  }
  return reply.substr(1);
}

// Reads one reply from every server (or those marked in `only`), keeping the first error in
// `first_error` (unless it already holds one): every reply is read even after an error, so no
// message is left behind for the next command.
void CollectReplies(RankGroupLink& group, const std::vector<char>* only, std::string& first_error) {
  for (int r = 1; r < group.size(); ++r) {
    if (only != nullptr && !(*only)[r]) continue;
    try {
      ExpectOk(group.Receive(r));
    } catch (const std::exception& e) {
      if (first_error.empty()) first_error = e.what();
    }
  }
}

// One `command` per server with the handles it holds among `per_rank` (indexed by group rank;
// rank 0's own are not sent).
void SendHandlesTo(RankGroupLink& group, Command command, std::int64_t store_id,
                   const std::vector<std::vector<PointHandle>>& per_rank) {
  for (int r = 1; r < group.size(); ++r) {
    if (per_rank[r].empty()) continue;
    ByteWriter out = CommandHeader(command, store_id);
    out.PutVector(per_rank[r]);
    group.Send(r, out.Take());
  }
}

}  // namespace

DistributedPointStore::DistributedPointStore(std::shared_ptr<RankGroupLink> group,
                                             const ConstitutiveModel& model, BalanceOptions balance)
    : group_(std::move(group)), model_(model), balance_(balance) {
  balance_.Validate("balance.");
  Require(balance_.rank_zero_owns_points || group_->size() > 1, "balance.rank_zero_owns_points",
          "must be true on a group of one rank");
  id_ = group_->NewStoreId();
  const std::string open = CommandHeader(Command::kOpen, id_).Take();
  for (int r = 1; r < group_->size(); ++r) group_->Send(r, open);
}

DistributedPointStore::~DistributedPointStore() {
  if (registration_ && *registration_ == this) *registration_ = nullptr;
  if (group_->finished()) return;
  try {
    const std::string close = CommandHeader(Command::kClose, id_).Take();
    for (int r = 1; r < group_->size(); ++r) group_->Send(r, close);
  } catch (...) {
  }
}

std::vector<int> DistributedPointStore::OwningRanks() const {
  std::vector<int> ranks;
  for (int r = balance_.rank_zero_owns_points ? 0 : 1; r < group_->size(); ++r) ranks.push_back(r);
  return ranks;
}

int DistributedPointStore::Owner(PointHandle handle) const {
  if (handle < 0 || handle >= size()) {
    throw std::out_of_range(model_.Name() + " distributed point store: no point with handle " +
                            std::to_string(handle));
  }
  return owner_[static_cast<std::size_t>(handle)];
}

std::vector<std::int64_t> DistributedPointStore::PointsPerRank() const {
  std::vector<std::int64_t> counts(group_->size(), 0);
  for (int owner : owner_) ++counts[owner];
  return counts;
}

std::vector<PointHandle> DistributedPointStore::Create(std::int64_t count) {
  if (count < 0) throw std::invalid_argument("point store: a negative count of points");
  const std::vector<int> ranks = OwningRanks();
  std::vector<PointHandle> handles;
  std::vector<std::vector<PointHandle>> per_rank(group_->size());
  for (std::int64_t k = 0; k < count; ++k) {
    const PointHandle handle = size();
    const int owner = ranks[next_owner_];
    next_owner_ = (next_owner_ + 1) % static_cast<int>(ranks.size());
    owner_.push_back(owner);
    has_trial_.push_back(0);
    cost_seconds_.push_back(0);
    local_committed_.push_back(owner == 0 ? model_.InitialState() : nullptr);
    local_trial_.emplace_back();
    per_rank[owner].push_back(handle);
    handles.push_back(handle);
  }
  SendHandlesTo(*group_, Command::kCreate, id_, per_rank);
  return handles;
}

std::vector<TrialResponse> DistributedPointStore::TryUpdate(
    const std::vector<PointHandle>& handles, const std::vector<Matrix3>& increments,
    bool want_tangent) {
  if (handles.size() != increments.size()) {
    throw std::invalid_argument("point store: " + std::to_string(handles.size()) +
                                " handles but " + std::to_string(increments.size()) +
                                " increments");
  }
  const std::int64_t sent_before = group_->bytes_sent();
  const std::int64_t received_before = group_->bytes_received();
  const int ranks = group_->size();
  std::vector<std::vector<std::size_t>> positions(ranks);  // indices into `handles` per owner
  for (std::size_t k = 0; k < handles.size(); ++k) positions[Owner(handles[k])].push_back(k);

  // Down: one batch per server; then rank 0's own share while the servers work.
  for (int r = 1; r < ranks; ++r) {
    if (positions[r].empty()) continue;
    ByteWriter out = CommandHeader(Command::kTry, id_);
    out.Put(static_cast<std::uint8_t>(want_tangent ? 1 : 0));
    out.Put(static_cast<std::uint64_t>(positions[r].size()));
    for (std::size_t k : positions[r]) {
      out.Put(static_cast<std::int64_t>(handles[k]));
      out.Put(increments[k]);
    }
    group_->Send(r, out.Take());
  }
  std::vector<TrialResponse> trials(handles.size());
  StepBalance balance;
  balance.step = history_->empty() ? 1 : history_->back().step + 1;
  balance.rank_seconds.assign(ranks, 0.0);
  {
    std::vector<const MaterialState*> committed;
    std::vector<Matrix3> own_increments;
    for (std::size_t k : positions[0]) {
      committed.push_back(local_committed_[handles[k]].get());
      own_increments.push_back(increments[k]);
    }
    std::vector<PointResult> results = UpdatePoints(model_, committed, own_increments,
                                                    want_tangent, balance_.rank_zero_threads);
    for (std::size_t i = 0; i < positions[0].size(); ++i) {
      const std::size_t k = positions[0][i];
      const PointHandle handle = handles[k];
      trials[k] = std::move(results[i].trial);
      cost_seconds_[handle] = results[i].seconds;
      balance.rank_seconds[0] += results[i].seconds;
      local_trial_[handle] = std::move(results[i].state);
    }
  }
  // Up: the servers' responses, in the order their points were sent.
  std::string first_error;
  for (int r = 1; r < ranks; ++r) {
    if (positions[r].empty()) continue;
    const std::string reply = group_->Receive(r);
    try {
      const std::string payload = ExpectOk(reply);
      ByteReader in(payload);
      for (std::size_t k : positions[r]) {
        double seconds = 0;
        GetTrial(in, trials[k], seconds);
        cost_seconds_[handles[k]] = seconds;
        balance.rank_seconds[r] += seconds;
      }
    } catch (const std::exception& e) {
      if (first_error.empty()) first_error = e.what();
    }
  }
  if (!first_error.empty()) throw std::runtime_error(first_error);
  for (std::size_t k = 0; k < handles.size(); ++k) {
    has_trial_[handles[k]] = trials[k].status == UpdateStatus::kOk ? 1 : 0;
  }
  double max_seconds = 0, sum_seconds = 0;
  const std::vector<int> owning = OwningRanks();
  for (int r : owning) {
    max_seconds = std::max(max_seconds, balance.rank_seconds[r]);
    sum_seconds += balance.rank_seconds[r];
  }
  const double mean_seconds = sum_seconds / static_cast<double>(owning.size());
  balance.imbalance = mean_seconds > 0 ? max_seconds / mean_seconds - 1 : 0;
  balance.imbalance_after = balance.imbalance;
  balance.bytes_sent = group_->bytes_sent() - sent_before;
  balance.bytes_received = group_->bytes_received() - received_before;
  history_->push_back(std::move(balance));
  return trials;
}

void DistributedPointStore::Commit(const std::vector<PointHandle>& handles) {
  for (PointHandle handle : handles) {
    Owner(handle);  // throws std::out_of_range for an unknown handle
    if (!has_trial_[handle]) {
      throw std::logic_error(model_.Name() + " point store: commit of point " +
                             std::to_string(handle) + ", which has no successful trial");
    }
  }
  std::vector<std::vector<PointHandle>> per_rank(group_->size());
  for (PointHandle handle : handles) {
    if (!has_trial_[handle]) continue;  // listed twice
    has_trial_[handle] = 0;
    const int owner = owner_[handle];
    if (owner == 0) {
      local_committed_[handle] = std::move(local_trial_[handle]);
    } else {
      per_rank[owner].push_back(handle);
    }
  }
  SendHandlesTo(*group_, Command::kCommit, id_, per_rank);
  ++commits_since_rebalance_;
  if (balance_.enabled && commits_since_rebalance_ >= balance_.min_commits_between &&
      !history_->empty() && history_->back().imbalance > balance_.threshold) {
    Rebalance();
  }
}

void DistributedPointStore::Discard(const std::vector<PointHandle>& handles) {
  std::vector<std::vector<PointHandle>> per_rank(group_->size());
  for (PointHandle handle : handles) {
    const int owner = Owner(handle);
    has_trial_[handle] = 0;
    if (owner == 0) {
      local_trial_[handle].reset();
    } else {
      per_rank[owner].push_back(handle);
    }
  }
  SendHandlesTo(*group_, Command::kDiscard, id_, per_rank);
}

std::string DistributedPointStore::Serialize(PointHandle handle) const {
  const int owner = Owner(handle);
  if (owner == 0) return local_committed_[handle]->Serialize();
  ByteWriter out = CommandHeader(Command::kSerialize, id_);
  out.Put(static_cast<std::int64_t>(handle));
  group_->Send(owner, out.Take());
  const std::string payload = ExpectOk(group_->Receive(owner));
  ByteReader in(payload);
  std::string bytes;
  in.GetBlob(bytes);
  return bytes;
}

void DistributedPointStore::Restore(PointHandle handle, const std::string& bytes) {
  const int owner = Owner(handle);
  has_trial_[handle] = 0;
  if (owner == 0) {
    local_committed_[handle] = model_.RestoreState(bytes);
    local_trial_[handle].reset();
    return;
  }
  ByteWriter out = CommandHeader(Command::kRestore, id_);
  out.Put(static_cast<std::int64_t>(handle));
  out.PutBlob(bytes);
  group_->Send(owner, out.Take());
  const std::string reply = group_->Receive(owner);
  ByteReader in(reply);
  std::uint8_t ok = 0;
  in.Get(ok);
  if (!ok) {
    std::string message;
    in.GetBlob(message);
    throw InputError("state", message);
  }
}

void DistributedPointStore::Rebalance() {
  commits_since_rebalance_ = 0;
  const std::vector<int> owning = OwningRanks();
  std::vector<double> load(group_->size(), 0.0);
  for (std::size_t p = 0; p < owner_.size(); ++p) load[owner_[p]] += cost_seconds_[p];
  double sum = 0;
  for (int r : owning) sum += load[r];
  if (sum <= 0) return;
  const double mean = sum / static_cast<double>(owning.size());
  auto imbalance = [&] {
    double max_load = 0;
    for (int r : owning) max_load = std::max(max_load, load[r]);
    return max_load / mean - 1;
  };
  // Greedy moves from the most to the least loaded rank.
  std::vector<std::tuple<PointHandle, int, int>> moves;
  std::vector<int> new_owner = owner_;
  const std::size_t max_moves = owner_.size();
  while (imbalance() > 0.5 * balance_.threshold && moves.size() < max_moves) {
    int most = owning.front(), least = owning.front();
    for (int r : owning) {
      if (load[r] > load[most]) most = r;
      if (load[r] < load[least]) least = r;
    }
    const double gap = load[most] - load[least];
    PointHandle best = -1;
    double best_distance = 0;
    for (std::size_t p = 0; p < new_owner.size(); ++p) {
      // A point moves at most once per rebalance: the move list names where it is now.
      if (owner_[p] != most || new_owner[p] != most || cost_seconds_[p] <= 0 ||
          cost_seconds_[p] >= gap) {
        continue;
      }
      const double distance = std::abs(cost_seconds_[p] - 0.5 * gap);
      if (best < 0 || distance < best_distance) {
        best = static_cast<PointHandle>(p);
        best_distance = distance;
      }
    }
    if (best < 0) break;  // no single move lowers the larger of the two loads
    new_owner[best] = least;
    load[most] -= cost_seconds_[best];
    load[least] += cost_seconds_[best];
    moves.emplace_back(best, most, least);
  }
  if (moves.empty()) return;

  // The move list to every rank involved; rank 0 does its part alongside.
  ByteWriter list;
  list.Put(static_cast<std::uint64_t>(moves.size()));
  for (const auto& [handle, from, to] : moves) {
    list.Put(static_cast<std::int64_t>(handle));
    list.Put(static_cast<std::int32_t>(from));
    list.Put(static_cast<std::int32_t>(to));
  }
  const std::string list_bytes = list.Take();
  std::vector<char> involved(group_->size(), 0);
  for (const auto& [handle, from, to] : moves) involved[from] = involved[to] = 1;
  for (int r = 1; r < group_->size(); ++r) {
    if (involved[r]) group_->Send(r, CommandHeader(Command::kMigrate, id_).Take() + list_bytes);
  }
  std::vector<std::string> outgoing;
  outgoing.reserve(moves.size());
  std::vector<MPI_Request> requests;
  for (const auto& [handle, from, to] : moves) {
    if (from != 0) continue;
    outgoing.push_back(StateMessage(handle, [&, h = handle] {
      if (local_committed_[h] == nullptr) throw std::logic_error("not on rank 0");
      return local_committed_[h]->Serialize();
    }));
    requests.emplace_back();
    MPI_Isend(outgoing.back().data(), static_cast<int>(outgoing.back().size()), MPI_BYTE, to,
              kTagState, group_->communicator(), &requests.back());
  }
  for (const auto& [handle, from, to] : moves) {
    if (to != 0) continue;
    const std::string message = ReceivePolling(group_->communicator(), from, kTagState);
    local_committed_[handle] = model_.RestoreState(StateFromMessage(message, handle));
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  for (const auto& [handle, from, to] : moves) {
    if (from == 0) local_committed_[handle].reset();
  }
  std::string first_error;
  CollectReplies(*group_, &involved, first_error);
  if (!first_error.empty()) throw std::runtime_error(first_error);
  owner_ = std::move(new_owner);
  StepBalance& last = history_->back();
  last.points_moved = static_cast<int>(moves.size());
  last.imbalance_after = imbalance();
}

void DistributedPointStore::WriteCheckpoint(const std::string& directory,
                                            std::uint64_t generation) {
  ByteWriter command = CommandHeader(Command::kWriteCheckpoint, id_);
  command.PutBlob(directory);
  command.Put(generation);
  const std::string bytes = command.Take();
  for (int r = 1; r < group_->size(); ++r) group_->Send(r, bytes);
  std::string first_error;
  try {
    std::vector<std::pair<checkpoint::Handle, std::string>> points;
    for (std::size_t p = 0; p < owner_.size(); ++p) {
      if (owner_[p] == 0) points.emplace_back(p, local_committed_[p]->Serialize());
    }
    checkpoint::WriteFileAtomically(checkpoint::PointsFile(directory, generation, 0),
                                    checkpoint::PointsFileBytes(model_.Name(), points));
  } catch (const std::exception& e) {
    first_error = e.what();
  }
  CollectReplies(*group_, nullptr, first_error);
  if (!first_error.empty()) throw std::runtime_error("checkpoint not written: " + first_error);
  checkpoint::Manifest manifest;
  manifest.generation = generation;
  manifest.model_name = model_.Name();
  manifest.files = static_cast<std::uint32_t>(group_->size());
  manifest.points = static_cast<std::uint64_t>(size());
  checkpoint::WriteFileAtomically(checkpoint::ManifestFile(directory, generation),
                                  checkpoint::ManifestBytes(manifest));
  // The directory is shared by the group (one file system), so rank 0 removes the files of
  // every rank.
  if (generation >= 2) checkpoint::RemoveGeneration(directory, generation - 2);
}

void DistributedPointStore::ReadCheckpoint(const std::string& directory,
                                           std::uint64_t generation) {
  const checkpoint::Manifest manifest = checkpoint::ReadManifest(directory, generation);
  Require(manifest.model_name == model_.Name(), "checkpoint",
          "holds points of '" + manifest.model_name + "', not '" + model_.Name() + "'");
  Require(manifest.points == static_cast<std::uint64_t>(size()), "checkpoint",
          "holds " + std::to_string(manifest.points) + " points; this store has " +
              std::to_string(size()));
  ByteWriter command = CommandHeader(Command::kReadCheckpoint, id_);
  command.PutBlob(directory);
  command.Put(generation);
  const std::string bytes = command.Take();
  for (int r = 1; r < group_->size(); ++r) group_->Send(r, bytes);
  std::string first_error;
  std::unordered_map<PointHandle, std::unique_ptr<MaterialState>> own;
  try {
    std::vector<PointHandle> wanted;
    for (std::size_t p = 0; p < owner_.size(); ++p) {
      if (owner_[p] == 0) wanted.push_back(static_cast<PointHandle>(p));
    }
    own = LoadCheckpointPoints(model_, directory, generation, wanted);
  } catch (const std::exception& e) {
    first_error = e.what();
  }
  CollectReplies(*group_, nullptr, first_error);
  const std::string finish =
      CommandHeader(first_error.empty() ? Command::kApplyCheckpoint : Command::kDropCheckpoint,
                    id_)
          .Take();
  for (int r = 1; r < group_->size(); ++r) group_->Send(r, finish);
  if (!first_error.empty()) throw InputError("checkpoint", first_error);
  for (auto& [handle, state] : own) {
    local_committed_[handle] = std::move(state);
    local_trial_[handle].reset();
  }
  std::fill(has_trial_.begin(), has_trial_.end(), 0);
}

std::unique_ptr<material::MaterialPointStore> DistributedModel::MakePointStore() const {
  auto store = std::make_unique<DistributedPointStore>(group_, *inner_, balance_);
  store->set_registration(current_store_);
  store->set_history(history_);
  *current_store_ = store.get();
  return store;
}

}  // namespace gonogo::bridge
