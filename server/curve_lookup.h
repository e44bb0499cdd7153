// Answers a traction request from the cache: first its exact key, then (unless disabled) a curve of
// a geometrically similar tyre on the same soil, scaled by seed 001's similarity.
#pragma once

#include <optional>
#include <string>

#include "cache/curve_store.h"
#include "solvers/common/tier.h"
#include "solvers/mobility/similarity.h"

namespace gonogo::server {

struct CachedAnswer {
  cache::StoredCurve source;  // the stored curve used (its key, computing rank, time)
  TractionCurve curve;        // the answer: the stored curve itself, or scaled to the request
  bool similarity = false;
  double scale_ratio = 1;     // requested diameter / source diameter
  std::optional<mobility::ScalabilityRecord> reliability;
};

std::optional<CachedAnswer> LookUpCurve(cache::CurveStore& store, const TractionTier& tier,
                                        const TractionRequest& quantised, const std::string& key,
                                        bool allow_similarity);

}  // namespace gonogo::server
