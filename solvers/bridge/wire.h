// The messages between group rank 0 (RankGroupLink, DistributedPointStore) and the point servers
// of a rank group (ServeRankGroup): tags, commands, framing, and the per-point work both ends do
// alike. Internal to solvers/bridge.
//
// A command is a ByteWriter message, CommandHeader(command, store id) then its payload, sent on
// kTagCommand; a reply (kTagReply) is OkReply(payload) or ErrorReply(why); a migrating point's
// state goes from owner to owner on kTagState (StateMessage).
#pragma once

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "solvers/common/byte_stream.h"
#include "solvers/material/constitutive.h"
#include "solvers/material/point_store.h"

namespace gonogo::bridge::wire {

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

// The next message from `source` with `tag`, polled with MPI_Iprobe and Backoff (a rank blocked
// in MPI_Recv spins a core at 100 %).
std::string ReceivePolling(MPI_Comm comm, int source, int tag);
// Throws LimitError for a message beyond MPI's 2 GiB count.
void SendBytes(MPI_Comm comm, int dest, int tag, const std::string& bytes);

ByteWriter CommandHeader(Command command, std::int64_t store_id);
std::string OkReply(const std::string& payload = {});
std::string ErrorReply(const std::string& message);
// The payload of a reply after its status byte, or the server's error thrown.
std::string ExpectOk(const std::string& reply);

// One point's update, alone, timed: the unit of work wherever the point lives, so that the
// result does not depend on where or with which other points it runs.
struct PointResult {
  material::TrialResponse trial;
  std::unique_ptr<material::MaterialState> state;
  double seconds = 0;
};
// Every point alone, on `threads` OpenMP threads (dynamic schedule); a throwing model gives a
// kFailed response with its message.
std::vector<PointResult> UpdatePoints(const material::ConstitutiveModel& model,
                                      const std::vector<const material::MaterialState*>& committed,
                                      const std::vector<material::Matrix3>& increments,
                                      bool want_tangent, int threads);
void PutTrial(ByteWriter& out, const PointResult& result);
void GetTrial(ByteReader& in, material::TrialResponse& trial, double& seconds);

// A migrating point's message: its handle, whether its state could be read, then the state or
// why not. The receiver always gets one message per move, so a failure cannot leave it waiting.
std::string StateMessage(material::PointHandle handle,
                         const std::function<std::string()>& serialize);
// The state in a StateMessage for `expected`; throws when it carries an error or another point.
std::string StateFromMessage(const std::string& message, material::PointHandle expected);

// The points of `wanted` from checkpoint `generation` of `directory`, restored through `model`.
std::unordered_map<material::PointHandle, std::unique_ptr<material::MaterialState>>
LoadCheckpointPoints(const material::ConstitutiveModel& model, const std::string& directory,
                     std::uint64_t generation, const std::vector<material::PointHandle>& wanted);

}  // namespace gonogo::bridge::wire
