// The scale-bridging framework of seed 000, made reusable: the material points of an FE mesh
// distributed over the ranks of a group, with sticky ownership. Group rank 0 runs the FE solver
// and talks to a DistributedPointStore (a material::MaterialPointStore, so the solver does not
// know); every other rank of the group runs ServeRankGroup and owns a share of the points for the
// life of the task. Per FE step only batched increments go down and stresses (and tangents when
// asked) come back; a state crosses MPI only when it migrates to balance the load or is
// checkpointed.
//
//   rank 0:                                      ranks 1..k-1:
//     auto group = std::make_shared<RankGroupLink>(comm);
//     DistributedModel model(group, rve, {});      ServeRankGroup(comm, rve, {threads},
//     fe::ExplicitSolver solver(mesh, model, ...);                on_call);
//     ... solver.Step(dt) ...   (collective)
//     group->Finish();          (the servers return)
//
// Any model works (the points are independent and a state moves as bytes); the DE RVE is why it
// exists. Results do not depend on the group size, the owner of a point or the thread count:
// every point is updated alone, in the same order of operations, wherever it lives.
//
// Messages are point-to-point on the group's communicator, polled with a back-off sleep (a
// blocking wait spins a core at 100 %, which an oversubscribed laptop run cannot afford).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"
#include "solvers/material/point_store.h"

namespace gonogo::bridge {

// Rank 0's end of a serving group: sends commands and collects replies. Not thread-safe (one
// solver drives it). Every method is called on group rank 0 only.
class RankGroupLink {
 public:
  // `communicator` is not owned; it must outlive the link.
  explicit RankGroupLink(MPI_Comm communicator);
  ~RankGroupLink();  // Finish() if not done
  RankGroupLink(const RankGroupLink&) = delete;
  RankGroupLink& operator=(const RankGroupLink&) = delete;

  int size() const { return size_; }
  MPI_Comm communicator() const { return communicator_; }

  // Every server runs its on_call(code) (ServeRankGroup); the caller runs its own part, so a
  // collective operation (the pool's cancellation check) happens on every rank at one point.
  void Call(int code);
  // The servers return from ServeRankGroup. Idempotent.
  void Finish();
  bool finished() const { return finished_; }

  // --- for DistributedPointStore ---------------------------------------------------------------
  void Send(int rank, const std::string& bytes);
  std::string Receive(int rank);  // a reply; polls with back-off
  std::int64_t NewStoreId() { return next_store_id_++; }
  std::int64_t bytes_sent() const { return bytes_sent_; }
  std::int64_t bytes_received() const { return bytes_received_; }

 private:
  MPI_Comm communicator_;
  int size_ = 1;
  bool finished_ = false;
  std::int64_t next_store_id_ = 1;
  std::int64_t bytes_sent_ = 0;
  std::int64_t bytes_received_ = 0;
};

struct ServeOptions {
  int threads = 1;  // OpenMP threads over the points this rank owns
};

// Serves rank 0's stores until it calls Finish(); collective on `communicator`, called on every
// rank but 0. `model` answers for the points this rank owns (the same model as rank 0's, built
// from the same parameters); `on_call` (may be empty) runs for each RankGroupLink::Call. Errors
// of a command (a state that cannot be read, a file that cannot be written) go back to rank 0,
// which throws them; the server keeps serving.
void ServeRankGroup(MPI_Comm communicator, const material::ConstitutiveModel& model,
                    const ServeOptions& options, const std::function<void(int code)>& on_call);

// Load balancing by measured cost: after a commit, when the most loaded rank's last-step point
// seconds exceed the mean by more than `threshold` (a fraction), points move from the most to the
// least loaded rank (each move takes the point whose cost is nearest half the gap) until the
// imbalance is under threshold / 2 or no move helps.
struct BalanceOptions {
  bool enabled = true;
  double threshold = 0.25;        // max / mean - 1 of rank seconds that triggers a rebalance
  // Commits per cost window: a point's cost is the median of its update seconds over the window
  // (one step's wall seconds are at the mercy of time slicing), and a rebalance is considered at
  // the end of each window, on those costs.
  int cost_window_commits = 10;
  bool rank_zero_owns_points = true;  // false: the FE rank keeps no points (a dedicated FE rank)
  int rank_zero_threads = 1;          // OpenMP threads over rank 0's own points
  void Validate(const std::string& field_prefix) const;
};

// One TryUpdate of the store, as measured.
struct StepBalance {
  std::int64_t step = 0;             // TryUpdate calls so far, 1-based
  std::vector<double> rank_seconds;  // point-update seconds per group rank in this step
  double imbalance = 0;              // max / mean - 1 of rank_seconds (0 when balanced)
  double imbalance_after = 0;        // predicted from the same costs after the moves below
  int points_moved = 0;              // migrated after this step's commit
  std::int64_t bytes_sent = 0;       // by rank 0, this step (increments and commands)
  std::int64_t bytes_received = 0;   // by rank 0, this step (responses)
};

class DistributedPointStore : public material::MaterialPointStore {
 public:
  // On group rank 0; `model` answers for rank 0's own points and must outlive the store.
  DistributedPointStore(std::shared_ptr<RankGroupLink> group,
                        const material::ConstitutiveModel& model, BalanceOptions balance);
  ~DistributedPointStore() override;  // the servers drop this store's points

  std::string ModelName() const override { return model_.Name(); }
  std::int64_t size() const override { return static_cast<std::int64_t>(owner_.size()); }
  // New points go round-robin over the owning ranks.
  std::vector<material::PointHandle> Create(std::int64_t count) override;
  std::vector<material::TrialResponse> TryUpdate(
      const std::vector<material::PointHandle>& handles,
      const std::vector<material::Matrix3>& displacement_gradient_increments,
      bool want_tangent) override;
  // Commits, then rebalances when BalanceOptions say so.
  void Commit(const std::vector<material::PointHandle>& handles) override;
  void Discard(const std::vector<material::PointHandle>& handles) override;
  std::string Serialize(material::PointHandle handle) const override;
  void Restore(material::PointHandle handle, const std::string& bytes) override;

  int Owner(material::PointHandle handle) const;
  std::vector<std::int64_t> PointsPerRank() const;
  const std::vector<StepBalance>& balance_history() const { return *history_; }
  // Cleared (set to nullptr) when this store is destroyed, if it still points here.
  void set_registration(std::shared_ptr<DistributedPointStore*> slot) {
    registration_ = std::move(slot);
  }
  // Where the per-step balance records go (default: the store's own list); a model shares one
  // list between its stores so the records outlive them.
  void set_history(std::shared_ptr<std::vector<StepBalance>> history) {
    history_ = std::move(history);
  }

  // MaterialPointStore's checkpoints, each rank writing its own points file
  // (points.<generation>.<rank>.bin), rank 0 the manifest once all are in; the group's ranks
  // must share the directory's file system. Reading stages every rank's share and applies it
  // only when all were read, so a damaged checkpoint changes nothing. Collective through the link.
  void WriteCheckpoint(const std::string& directory, std::uint64_t generation) override;
  void ReadCheckpoint(const std::string& directory, std::uint64_t generation) override;

 private:
  void CloseCostWindow();
  void Rebalance();
  std::vector<int> OwningRanks() const;

  std::shared_ptr<RankGroupLink> group_;
  const material::ConstitutiveModel& model_;
  BalanceOptions balance_;
  std::int64_t id_ = 0;
  int next_owner_ = 0;  // index into OwningRanks() of the next created point
  std::vector<int> owner_;                       // (points) group rank
  std::vector<char> has_trial_;                  // (points) a successful trial waits for commit
  std::vector<double> cost_seconds_;             // (points) median over the last cost window
  std::vector<std::vector<double>> window_seconds_;  // (points) update seconds in this window
  // Rank 0's own points: committed and trial states.
  std::vector<std::unique_ptr<material::MaterialState>> local_committed_;  // (points) null if remote
  std::vector<std::unique_ptr<material::MaterialState>> local_trial_;
  std::shared_ptr<std::vector<StepBalance>> history_ =
      std::make_shared<std::vector<StepBalance>>();
  int commits_in_window_ = 0;
  std::shared_ptr<DistributedPointStore*> registration_;
};

// A model whose points live on a rank group: its MakePointStore gives a DistributedPointStore on
// the link; everything else is the inner model's (what the solver asks of a fresh point on rank 0).
class DistributedModel : public material::ConstitutiveModel {
 public:
  DistributedModel(std::shared_ptr<RankGroupLink> group,
                   std::shared_ptr<const material::ConstitutiveModel> inner, BalanceOptions balance)
      : group_(std::move(group)), inner_(std::move(inner)), balance_(balance) {}

  std::string Name() const override { return inner_->Name(); }
  std::unique_ptr<material::MaterialState> InitialState() const override {
    return inner_->InitialState();
  }
  std::unique_ptr<material::MaterialState> RestoreState(const std::string& bytes) const override {
    return inner_->RestoreState(bytes);
  }
  std::vector<material::PointResponse> Update(const std::vector<material::PointIncrement>& increments,
                                              bool want_tangent) const override {
    return inner_->Update(increments, want_tangent);
  }
  material::ElasticModuli InitialElasticModuli() const override {
    return inner_->InitialElasticModuli();
  }
  std::unique_ptr<material::MaterialPointStore> MakePointStore() const override;

  // The most recently made store that still lives (its solver owns it), for reports (balance
  // history) and checkpoints; nullptr when none.
  DistributedPointStore* current_store() const { return *current_store_; }
  // Every TryUpdate of every store this model made, in order.
  const std::vector<StepBalance>& balance_history() const { return *history_; }

 private:
  std::shared_ptr<RankGroupLink> group_;
  std::shared_ptr<const material::ConstitutiveModel> inner_;
  BalanceOptions balance_;
  // Shared with the stores, which clear it when they are destroyed.
  std::shared_ptr<DistributedPointStore*> current_store_ =
      std::make_shared<DistributedPointStore*>(nullptr);
  std::shared_ptr<std::vector<StepBalance>> history_ =
      std::make_shared<std::vector<StepBalance>>();
};

}  // namespace gonogo::bridge
