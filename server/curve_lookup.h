// Answers a traction request from the cache: first its exact key, then (unless disabled) a curve of
// a geometrically similar tyre on the same soil, scaled by seed 001's similarity.
#pragma once

#include <optional>
#include <string>

#include "cache/curve_store.h"
#include "gonogo/v1/mobility.pb.h"
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
                                        bool allow_similarity, const std::string& scope = "");

// The API form of an answer. `request` and `curve` are what is answered; `source` the stored curve
// behind it (the same one, except for a similarity hit).
void FillCurve(const TractionRequest& request, const TractionCurve& curve,
               const cache::StoredCurve& source, bool hit, v1::TractionCurve* out);
void FillCurve(const cache::StoredCurve& stored, bool hit, v1::TractionCurve* out);
void FillAnswer(const TractionRequest& request, const CachedAnswer& answer, v1::TractionCurve* out);

}  // namespace gonogo::server
