// Tiers that probe the service itself rather than the soil, registered only when gonogo-server runs
// with --diagnostic-tiers (tests, and an operator checking a new cluster's MPI set-up):
//
//   diagnostic-rank-group      asks for 2 ranks; on a rank group it checks the group's
//                              communicator (size, an all-reduce), holds the group for
//                              kGroupHoldMs while polling cancellation collectively, and answers
//                              with the empirical tier's curve computed by the group's rank 0.
//                              Alone (thread pool, or one worker) it does the same on one rank.
//   diagnostic-numerical-failure  throws NumericalError, as a solver that cannot converge does.
//   diagnostic-slow-curve      declares an hour a curve (so queries on it become jobs), takes
//                              kSlowCurveMs, reporting progress and polling cancellation, and
//                              answers with the empirical tier's curve.
#pragma once

#include "solvers/common/tier.h"

namespace gonogo {

namespace tiers {
inline constexpr int kGroupHoldMs = 2000;
inline constexpr int kSlowCurveMs = 1500;
}

void RegisterDiagnosticTiers(TierRegistry& registry);

}  // namespace gonogo
