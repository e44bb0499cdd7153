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
#include "server/curve_resolver.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// Throws InputError naming the field for bad requests, a scale's task failure with its kind
// (NumericalError, ...), and std::runtime_error when the study was not finished by `deadline` or
// `abandon` turned true.
v1::ScalabilityReport RunScalabilityStudy(const v1::ScalabilityRequest& request,
                                          const TierRegistry& tiers, CurveResolver& resolver,
                                          std::chrono::steady_clock::time_point deadline,
                                          const std::function<bool()>& abandon,
                                          const std::string& curve_scope = "");

}  // namespace gonogo::server
