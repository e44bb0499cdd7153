// The surrogate at the constitutive seam: a ConstitutiveModel answered by a SurrogateEnsemble,
// falling back to the real model (a DE RVE of the same soil) at a point the ensemble flags.
//
// A point's state: its stress, the strain accumulated since its start (the network's history
// input), the displacement-gradient increments it has taken (so that a fallback can replay
// them), and, once it has fallen back, the real model's state, which answers for it from then on
// unless the point is allowed to return (below).
//
// Fallback: when the ensemble flags a point's increment (surrogate_ensemble.h) and the fallback
// is enabled, a fresh state of the real model replays the point's increments from the start and
// then takes this one; the point's stress jumps to what the real model says its history gives.
// With the fallback disabled, the network answers anyway and the point counts the flag.
//
// Return (AnnMaterialOptions::return_after_steps > 0): a fallen-back point's every increment is
// also put to the ensemble, as the network's input it would have been (the real model's stress,
// the accumulated strain, the carried variables read from the real model's state). After that
// many increments in a row that the ensemble would not have flagged, the point goes back to the
// network from the real model's stress and variables, and the real state is dropped; flagged
// again, it replays its whole history once more. A fallback then costs the steps it is out, not
// the rest of the run. A
// committed state tells whether and when its point fell back (fell_back_at_step), which is what a
// curve reports; the FallbackLog has every fallback and unanswered flag the material made,
// including those of trial updates its caller then discarded (their cost, not their count of
// points), and the seconds the network and the fallbacks took.
//
// A stress the network answers is kept admissible (SurrogateEnsemble::Admissible: no principal
// stress more tensile than the training data's, none for a cohesionless RVE); the log counts the
// answers capped. The tangent a capped point reports is the network's, not the cap's.
//
// A point may start from a state of the real model other than its fresh one (StateFrom: an RVE
// settled at the stress of its depth in an FE bin); its fallback then replays from there.
//
// Recording (AnnMaterialOptions::record_fallback_paths): the real model answers through a
// PathRecorder (path_recorder.h), so that every fallen-back point's path on the real model, from
// the state it started from (its origin) through the replay to its last step there, is kept
// (FallbackPaths): the paths on which the ensemble flagged, answered by the RVE itself, which is
// training data where the model was missing it. The answers are unchanged. A point restored on
// the real model (a resumed run) is answered but not recorded.
//
// An ensemble that carries internal variables (SurrogateEnsemble::carried_variables, e.g. the
// coordination number) needs them read from the real model's state a point starts from
// (AnnMaterialOptions::internal_variables); the point then carries them, each step adding the
// ensemble's increments.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "solvers/ann/path_recorder.h"
#include "solvers/ann/point_driver.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/material/constitutive.h"

namespace gonogo::ann {

struct AnnMaterialOptions {
  bool fallback_enabled = true;
  // The stress of a fresh point when there is no fallback model to ask (Pa, tension positive).
  Matrix3 initial_stress_pa = Matrix3::Zero();
  // Reads the real model's internal variables (tiers::RveFabricVariables for an RVE): required,
  // with the real model, when the ensemble carries any.
  InternalVariables internal_variables;
  // A fallen-back point returns to the network after this many increments in a row the ensemble
  // would not have flagged; 0: never (it stays on the real model).
  int return_after_steps = 0;
  // Keep the fallen-back points' paths on the real model (above; FallbackPaths).
  bool record_fallback_paths = false;
};

// What the points of one material did, for a run's provenance. Thread-safe.
class FallbackLog {
 public:
  struct Event {
    std::int64_t point_step = 0;  // increments the point had taken when it fell back
    double distance = 0;          // the flag's measures
    double relative_spread = 0;
    bool below_pressure_floor = false;  // flagged by the ensemble's pressure floor
    bool beyond_distance = false;       // flagged by the envelope's distance
    bool beyond_spread = false;         // flagged by the members' spread
  };
  void RecordFallback(const Event& event);
  void RecordUnansweredFlag();
  void RecordNetworkCall(double seconds, std::int64_t points);
  void RecordStressReturns(std::int64_t points);  // answers SurrogateEnsemble::Admissible changed
  void RecordFallbackSeconds(double seconds);  // replays and points answered by the real model
  void RecordReturn();  // a fallen-back point went back to the network (in a trial too)
  std::vector<Event> fallbacks() const;
  std::int64_t unanswered_flags() const;
  double network_seconds() const;
  std::int64_t network_point_updates() const;  // point updates the ensemble answered
  std::int64_t stress_returns() const;
  double fallback_seconds() const;
  std::int64_t returns() const;

 private:
  mutable std::mutex mutex_;
  std::vector<Event> fallbacks_;
  std::int64_t unanswered_flags_ = 0;
  double network_seconds_ = 0;
  std::int64_t network_point_updates_ = 0;
  std::int64_t stress_returns_ = 0;
  double fallback_seconds_ = 0;
  std::int64_t returns_ = 0;
};

// The increments a point has taken, newest first, shared between a state and the states made
// from it (a step appends one node: no copy of the history per step).
struct IncrementNode {
  Matrix3 increment = Matrix3::Zero();
  std::shared_ptr<const IncrementNode> previous;
  std::int64_t count = 1;  // nodes from this one back to the first
  ~IncrementNode();        // unlinks its chain iteratively (no deep recursion)
};

class AnnState : public material::MaterialState {
 public:
  std::unique_ptr<material::MaterialState> Clone() const override;
  std::string Serialize() const override;
  std::int64_t steps() const { return history ? history->count : 0; }
  std::vector<Matrix3> Increments() const;  // oldest first

  Matrix3 stress_pa = Matrix3::Zero();
  Vector6 accumulated_strain = Vector6::Zero();  // engineering shears
  Eigen::VectorXd internal_variables;            // the ensemble's carried ones
  std::shared_ptr<const IncrementNode> history;  // dH taken, for a fallback's replay
  std::int64_t flags = 0;                        // increments the ensemble flagged
  // Set while the point is fallen back: the real model's state answers for it.
  std::unique_ptr<material::MaterialState> fallback;
  std::int64_t fell_back_at_step = -1;  // the steps it had taken at its latest fallback
  // On the real model: its increments in a row the ensemble would not have flagged (the return).
  std::int64_t unflagged_on_fallback = 0;
  // The real model's state the point started from (its bytes, shared by the points that started
  // alike); null: the real model's fresh state.
  std::shared_ptr<const std::string> origin;
};

class AnnMaterial : public material::ConstitutiveModel {
 public:
  // `fallback` may be null only with options.fallback_enabled false (InputError("fallback", ...)
  // otherwise), and only for an ensemble that carries no internal variables
  // (InputError("internal_variables", ...), as for a reader that does not read them).
  AnnMaterial(std::shared_ptr<const SurrogateEnsemble> ensemble,
              std::shared_ptr<const material::ConstitutiveModel> fallback,
              AnnMaterialOptions options = {});

  std::string Name() const override { return "ann-surrogate"; }
  std::unique_ptr<material::MaterialState> InitialState() const override;
  // Throws InputError("material.state", ...) for bytes that are not an AnnState of this model.
  std::unique_ptr<material::MaterialState> RestoreState(const std::string& bytes) const override;
  // A point that starts where the real model's state `real_state_bytes` is: its stress, no
  // accumulated strain, and a fallback that replays from that state. Throws InputError
  // ("material.state", ...) for bytes the real model does not read, NumericalError when the real
  // model cannot take a zero increment there.
  std::unique_ptr<AnnState> StateFrom(const std::string& real_state_bytes) const;
  // The network's points in one batched ensemble call; points on the fallback in one batched
  // call of the real model; fallbacks replayed one point at a time.
  std::vector<material::PointResponse> Update(const std::vector<material::PointIncrement>& increments,
                                              bool want_tangent) const override;

  const FallbackLog& log() const { return *log_; }
  // With record_fallback_paths: each fallen-back point's path on the real model (a StrainHistory
  // from the point's origin, its carried internal variables recorded by their names), one per
  // point: a path that is the start of another (a point that returned and fell back again, or
  // an update its caller discarded) is left out. Empty without recording.
  std::vector<StrainHistory> FallbackPaths() const;
  const SurrogateEnsemble& ensemble() const { return *ensemble_; }

 private:
  material::PointResponse FallBack(const AnnState& committed, const Matrix3& increment,
                                   bool want_tangent) const;
  // Whether the ensemble would flag each fallen-back point's increment (all true with the return
  // off), in one batched call.
  std::vector<bool> WouldFlag(const std::vector<material::PointIncrement>& increments,
                              const std::vector<std::size_t>& on_fallback) const;
  // The carried internal variables of a state of the real model (as `real_` answers it).
  Eigen::VectorXd CarriedOf(const material::MaterialState& real_state) const;
  // The real model's own state inside a state `real_` made.
  const material::MaterialState& RealStateOf(const material::MaterialState& state) const;

  std::shared_ptr<const SurrogateEnsemble> ensemble_;
  std::shared_ptr<const material::ConstitutiveModel> fallback_;
  // Recording, the recorder over fallback_; what answers a fallen-back point: recorder_ or
  // fallback_.
  std::shared_ptr<const PathRecorder> recorder_;
  std::shared_ptr<const material::ConstitutiveModel> real_;
  AnnMaterialOptions options_;
  Matrix3 initial_stress_pa_ = Matrix3::Zero();
  InternalVariables carried_reader_;  // options' reader narrowed to the carried variables
  Eigen::VectorXd initial_internal_variables_;
  // One copy of each distinct origin (the points of one depth share theirs).
  std::shared_ptr<const std::string> Intern(std::string bytes) const;

  std::shared_ptr<FallbackLog> log_ = std::make_shared<FallbackLog>();
  mutable std::mutex intern_mutex_;
  mutable std::unordered_multimap<std::size_t, std::shared_ptr<const std::string>> origins_;  // by hash
};

}  // namespace gonogo::ann
