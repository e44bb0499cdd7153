// The training tasks of a TrainSurrogate job (server/train_job.cc), each run on a worker of the
// pool as a traction task is (TaskSpec::training), so that a training spreads over the ranks:
//   - an RVE strain path: one laboratory path (solvers/ann/lab_paths.h) on a soil's DE RVE at the
//     RVE numerics of an fe-de configuration; its answer is the path's history (SerializeHistory);
//   - an ensemble member: one stress surrogate (solvers/ann/stress_surrogate.h) trained, or
//     fine-tuned from a registered model's member, on the histories it carries; its answer is the
//     member's TorchScript bytes. Cancellation is checked before every epoch;
//   - an fe-de rig run with every point's path recorded (seed 000's step 2), alone on the worker;
//     its answer is a RigPathsOutput with the paths kept (evenly spread over the bin).
#pragma once

#include <string>

#include "gonogo/v1/worker.pb.h"
#include "solvers/ann/lab_paths.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// The answer of `work` on the calling thread; throws InputError for work it cannot read and
// CancelledError when `context` is cancelled.
std::string RunTrainingWork(const v1::TrainingWork& work, const ComputeContext& context);

v1::RvePathWork ToProto(const ann::LabPathSpec& spec);
ann::LabPathSpec LabPathSpecOf(const v1::RvePathWork& work);

}  // namespace gonogo::server
