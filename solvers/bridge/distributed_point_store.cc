#include "solvers/bridge/distributed_point_store.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "solvers/bridge/wire.h"
#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/material/checkpoint_files.h"

namespace gonogo::bridge {

using material::ConstitutiveModel;
using material::MaterialState;
using material::Matrix3;
using material::PointHandle;
using material::TrialResponse;
using material::UpdateStatus;
namespace checkpoint = material::checkpoint;

using namespace wire;

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

// --- options -----------------------------------------------------------------------------------

void BalanceOptions::Validate(const std::string& field_prefix) const {
  Require(std::isfinite(threshold) && threshold >= 0, field_prefix + "threshold",
          "must be a finite fraction >= 0");
  Require(cost_window_commits >= 1, field_prefix + "cost_window_commits", "must be at least 1");
  Require(rank_zero_threads >= 1, field_prefix + "rank_zero_threads", "must be at least 1");
}

// --- DistributedPointStore ---------------------------------------------------------------------

namespace {

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
    window_seconds_.emplace_back();
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
      window_seconds_[handle].push_back(results[i].seconds);
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
        window_seconds_[handles[k]].push_back(seconds);
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
  if (++commits_in_window_ >= balance_.cost_window_commits) {
    CloseCostWindow();
    if (balance_.enabled && !history_->empty()) Rebalance();
  }
}

void DistributedPointStore::CloseCostWindow() {
  commits_in_window_ = 0;
  for (std::size_t p = 0; p < window_seconds_.size(); ++p) {
    std::vector<double>& samples = window_seconds_[p];
    if (samples.empty()) continue;  // not updated in this window: keep its last cost
    const std::size_t middle = samples.size() / 2;
    std::nth_element(samples.begin(), samples.begin() + middle, samples.end());
    double median = samples[middle];
    if (samples.size() % 2 == 0) {
      median = 0.5 * (median + *std::max_element(samples.begin(), samples.begin() + middle));
    }
    cost_seconds_[p] = median;
    samples.clear();
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
  if (imbalance() <= balance_.threshold) return;
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
