#include "server/curve_lookup.h"

#include <algorithm>

#include "cache/curve_key.h"

namespace gonogo::server {

std::optional<CachedAnswer> LookUpCurve(cache::CurveStore& store, const TractionTier& tier,
                                        const TractionRequest& q, const std::string& key,
                                        bool allow_similarity) {
  if (auto exact = store.Find(key)) {
    CachedAnswer a;
    a.curve = exact->curve;
    a.source = std::move(*exact);
    return a;
  }
  if (!allow_similarity) return std::nullopt;
  auto similar = store.FindSimilar(cache::SimilarityGroup(tier.Name(), tier.Version(), q), q,
                                   mobility::kPiTermTolerance, mobility::kMinimumScaleRatio);
  if (!similar) return std::nullopt;
  CachedAnswer a;
  a.curve = mobility::FromDimensionless(
      q, mobility::ToDimensionless(similar->request, similar->curve));
  a.curve.tier = similar->curve.tier;
  a.curve.tier_version = similar->curve.tier_version;
  a.similarity = true;
  a.scale_ratio = q.tyre.diameter_m / similar->request.tyre.diameter_m;
  const double ratio = std::min(a.scale_ratio, 1.0 / a.scale_ratio);
  a.reliability = mobility::ScalabilityTable::Seed001().For(ratio, q.soil.cone_index_pa);
  a.source = std::move(*similar);
  return a;
}

}  // namespace gonogo::server
