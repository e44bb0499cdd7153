// The scaled-tyre study of seed 001 (sections 5-6, Tables 4 and 6-8) for any tier: a tyre and its
// geometric scale models, loads by equal W/(b d), on one soil; every curve computed or taken from
// its exact cache key (never from similarity, which would make the comparison circular); the
// percentage of each scale's points inside the full-scale one-standard-deviation band for D/W,
// T/(rW) and efficiency; and a plot of the three against slip.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

#include "cache/curve_store.h"
#include "gonogo/v1/mobility.pb.h"
#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// Throws InputError naming the field for bad requests.
v1::ScalabilityReport RunScalabilityStudy(const v1::ScalabilityRequest& request,
                                          const TierRegistry& tiers, WorkerPool& pool,
                                          cache::CurveStore& curves,
                                          std::atomic<uint64_t>& next_task_id,
                                          std::chrono::steady_clock::time_point deadline,
                                          const std::function<bool()>& abandon);

}  // namespace gonogo::server
