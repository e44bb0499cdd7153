// The server end of a rank group (ServeRankGroup): the points this rank holds for group rank 0's
// stores, and the commands that reach them (wire.h).
#include <map>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "solvers/bridge/distributed_point_store.h"
#include "solvers/bridge/wire.h"
#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/material/checkpoint_files.h"

namespace gonogo::bridge {

using material::ConstitutiveModel;
using material::MaterialState;
using material::Matrix3;
using material::PointHandle;
namespace checkpoint = material::checkpoint;
using namespace wire;

namespace {

// --- the server side ----------------------------------------------------------------------------

// A handle list as SendHandlesTo writes it (ByteWriter::PutVector).
std::vector<PointHandle> GetHandles(ByteReader& in) {
  std::uint64_t count = 0;
  in.Get(count);
  std::vector<PointHandle> handles(count);
  for (PointHandle& handle : handles) in.Get(handle);
  return handles;
}

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
      case Command::kCreate:
        for (PointHandle handle : GetHandles(in)) {
          store.points[handle].committed = model_.InitialState();
        }
        return {};
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
        for (PointHandle handle : GetHandles(in)) {
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

void ServeRankGroup(MPI_Comm communicator, const ConstitutiveModel& model,
                    const ServeOptions& options, const std::function<void(int code)>& on_call) {
  Server(communicator, model, options, on_call).Run();
}

}  // namespace gonogo::bridge
