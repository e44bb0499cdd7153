// The strain paths an FE run's integration points actually take (seed 000's step 2: the paths met
// by the points of a single-tyre rig, recorded and added to the surrogate's training data).
//
// A PathRecorder is a ConstitutiveModel that answers with another (a DE RVE) and remembers, per
// point, every increment it took and the stress after it: its states carry a shared chain of
// steps (one node per step, no copy per step), and the recorder keeps the newest chain of each
// point. Each state the FE restores or creates is a new point; its history starts at the stress
// its state has before the first increment (one zero increment of the inner model, at the start).
// The answers are the inner model's, bit for bit, so a recorded run is the run.
//
// Where the FE discards an update it asked for, the chain it left is replaced by the next update
// of the same point (which extends the committed chain, not the discarded one). A state restored
// from a checkpoint starts a new point: a resumed run records from where it resumed.
//
// With `internal` (point_driver.h), each step also records what it reads of the inner model's
// state after the step (an RVE's coordination and fabric).
//
// A recorder may also stand in for its inner model inside another model (the fe-ann material
// records its fallen-back points' RVE paths so): Inner() reads the inner state of a recorder's
// state, and RestoreUnrecorded() restores a state whose steps are answered but not recorded (a
// point resumed mid-path, whose path would not start where its history did).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "solvers/ann/point_driver.h"
#include "solvers/ann/strain_history.h"
#include "solvers/material/constitutive.h"

namespace gonogo::ann {

class PathRecorder : public material::ConstitutiveModel {
 public:
  explicit PathRecorder(std::shared_ptr<const material::ConstitutiveModel> inner,
                        InternalVariables internal = {});

  std::string Name() const override { return "recorded " + inner_->Name(); }
  std::unique_ptr<material::MaterialState> InitialState() const override;
  // The inner model's bytes; each restored state is a new point.
  std::unique_ptr<material::MaterialState> RestoreState(const std::string& bytes) const override;
  std::vector<material::PointResponse> Update(const std::vector<material::PointIncrement>& increments,
                                              bool want_tangent) const override;
  material::ElasticModuli InitialElasticModuli() const override;

  // A state of the inner model, answered like any other but never recorded.
  std::unique_ptr<material::MaterialState> RestoreUnrecorded(const std::string& bytes) const;
  // The inner model's state inside a state of this recorder.
  static const material::MaterialState& Inner(const material::MaterialState& recorded);

  // Every point's path so far, in the order the points were made; points that took no step are
  // left out.
  std::vector<StrainHistory> Histories() const;

  struct Step;  // one recorded step (path_recorder.cc)

 private:
  std::unique_ptr<material::MaterialState> Wrap(std::unique_ptr<material::MaterialState> inner) const;

  std::shared_ptr<const material::ConstitutiveModel> inner_;
  InternalVariables internal_;
  mutable std::mutex mutex_;
  mutable std::int64_t next_point_ = 0;
  mutable std::map<std::int64_t, Matrix3> initial_stress_pa_;  // by point
  mutable std::map<std::int64_t, std::vector<double>> initial_internal_;  // by point
  mutable std::map<std::int64_t, std::shared_ptr<const Step>> newest_;  // by point
};

}  // namespace gonogo::ann
