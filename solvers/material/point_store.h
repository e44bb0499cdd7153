// Material points addressed by handle, with trial states the caller commits or discards: the form
// of the constitutive seam a solver talks to, so that a point's state may live elsewhere (another
// rank, a GPU, an RVE server) and never has to be handed back and forth with every increment.
//
// Protocol, per step of an explicit solver (solvers/fe/explicit_solver.cc):
//   responses = store.TryUpdate(handles, increments, want_tangent);  // trial states, kept aside
//   if every response is kOk:  store.Commit(handles);                // trials become committed
//   else:                      store.Discard(handles);               // committed ones untouched
// A trial always starts from the committed state: a second TryUpdate of a point before Commit or
// Discard replaces its trial, so "discard, then try again" gives the same response bit for bit.
//
// Handles are opaque integers the store hands out in Create; they stay valid for the store's
// lifetime. The local store below keeps every state in this process; a distributed store would
// keep each point on its owning rank, and then every call is collective on its communicator
// (MPI-style, as MFEM's parallel classes say it) and the handles are global.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"

namespace gonogo::material {

using PointHandle = std::int64_t;

// What TryUpdate returns for one point: PointResponse without the state, which stays in the store.
struct TrialResponse {
  UpdateStatus status = UpdateStatus::kFailed;
  std::string reason;                  // set when status is kFailed
  Matrix3 stress_pa = Matrix3::Zero();  // Cauchy stress of the trial state, Pa, tension positive
  bool has_tangent = false;
  Voigt6x6 tangent_pa = Voigt6x6::Zero();  // d sigma / d eps, Voigt, engineering shears, Pa
};

class MaterialPointStore {
 public:
  virtual ~MaterialPointStore() = default;

  // The model whose points these are (ConstitutiveModel::Name()).
  virtual std::string ModelName() const = 0;
  virtual std::int64_t size() const = 0;  // points created so far

  // `count` fresh points (the model's InitialState); returns their handles in order.
  virtual std::vector<PointHandle> Create(std::int64_t count) = 0;

  // One trial per handle from its committed state and its displacement-gradient increment
  // (constitutive.h conventions). @param[in] handles distinct, from Create; @param[in]
  // displacement_gradient_increments one per handle. Returns one response per handle, in order.
  // A failed point keeps no trial. Results do not depend on how the batch is split.
  // Throws std::out_of_range for an unknown handle, std::invalid_argument for mismatched sizes.
  virtual std::vector<TrialResponse> TryUpdate(
      const std::vector<PointHandle>& handles,
      const std::vector<Matrix3>& displacement_gradient_increments, bool want_tangent) = 0;

  // The trials become the committed states. Throws std::logic_error when a handle has no
  // successful trial (a caller must not commit a failed step); nothing is committed then.
  virtual void Commit(const std::vector<PointHandle>& handles) = 0;
  // Drops the trials of these handles (none is fine); committed states stay as they were.
  virtual void Discard(const std::vector<PointHandle>& handles) = 0;

  // The committed state as bytes (MaterialState::Serialize), for checkpoints and for moving a
  // point to another store; Restore replaces the committed state (and drops any trial). Restore
  // throws gonogo::InputError for bytes the model cannot read.
  virtual std::string Serialize(PointHandle handle) const = 0;
  virtual void Restore(PointHandle handle, const std::string& bytes) = 0;

  // Checkpoint `generation` of every committed state in `directory` (which must exist), in the
  // files of checkpoint_files.h, each written atomically, the manifest last; then generation - 2
  // is removed, so the last two complete generations stay (a caller that records the generation
  // in its own state file after this returns can always find the one it names). The default
  // writes every point from this process (points file of rank 0); a distributed store has every
  // rank write its own. Throws std::runtime_error naming the file when a write fails.
  virtual void WriteCheckpoint(const std::string& directory, std::uint64_t generation);
  // Replaces every committed state with checkpoint `generation` of `directory` (written by a
  // store of any distribution with the same number of points and model) and drops the trials.
  // Throws InputError("checkpoint", ...) for a missing, foreign or damaged checkpoint; nothing
  // is replaced then.
  virtual void ReadCheckpoint(const std::string& directory, std::uint64_t generation);
};

// The store of any ConstitutiveModel in this process: committed and trial MaterialStates side by
// side, updated through the model's batched Update (so OpenMP threads and bit-identical results
// carry over). The model must outlive the store.
class LocalPointStore : public MaterialPointStore {
 public:
  explicit LocalPointStore(const ConstitutiveModel& model) : model_(model) {}

  std::string ModelName() const override { return model_.Name(); }
  std::int64_t size() const override { return static_cast<std::int64_t>(committed_.size()); }
  std::vector<PointHandle> Create(std::int64_t count) override;
  std::vector<TrialResponse> TryUpdate(const std::vector<PointHandle>& handles,
                                       const std::vector<Matrix3>& displacement_gradient_increments,
                                       bool want_tangent) override;
  void Commit(const std::vector<PointHandle>& handles) override;
  void Discard(const std::vector<PointHandle>& handles) override;
  std::string Serialize(PointHandle handle) const override;
  void Restore(PointHandle handle, const std::string& bytes) override;

  // The committed state itself, for models and tests in this process.
  const MaterialState& committed(PointHandle handle) const;

 private:
  std::size_t Index(PointHandle handle) const;  // throws std::out_of_range

  const ConstitutiveModel& model_;
  std::vector<std::unique_ptr<MaterialState>> committed_;  // (points) never null
  std::vector<std::unique_ptr<MaterialState>> trial_;      // (points) null: no pending trial
  std::vector<PointIncrement> scratch_;                    // one batch of TryUpdate
};

}  // namespace gonogo::material
