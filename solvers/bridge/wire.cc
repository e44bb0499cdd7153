#include "solvers/bridge/wire.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "solvers/common/errors.h"
#include "solvers/material/checkpoint_files.h"

namespace gonogo::bridge::wire {

using material::ConstitutiveModel;
using material::MaterialState;
using material::Matrix3;
using material::PointHandle;
using material::PointIncrement;
using material::PointResponse;
using material::TrialResponse;
using material::UpdateStatus;
namespace checkpoint = material::checkpoint;

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

std::string OkReply(const std::string& payload) {
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

}  // namespace gonogo::bridge::wire
