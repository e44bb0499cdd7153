#include "server/curve_lookup.h"

#include <algorithm>

#include "cache/curve_key.h"
#include "server/convert.h"

namespace gonogo::server {

std::optional<CachedAnswer> LookUpCurve(cache::CurveStore& store, const TractionTier& tier,
                                        const TractionRequest& q, const std::string& key,
                                        bool allow_similarity, const std::string& scope) {
  if (auto exact = store.Find(key)) {
    CachedAnswer a;
    a.curve = exact->curve;
    a.source = std::move(*exact);
    return a;
  }
  if (!allow_similarity) return std::nullopt;
  auto similar = store.FindSimilar(cache::Scoped(scope, cache::SimilarityGroup(tier.Name(), tier.VersionFor(q), q)), q,
                                   mobility::kPiTermTolerance, mobility::kMinimumScaleRatio);
  if (!similar) return std::nullopt;
  CachedAnswer a;
  a.curve = mobility::FromDimensionless(
      q, mobility::ToDimensionless(similar->request, similar->curve));
  a.curve.tier = similar->curve.tier;
  a.curve.tier_version = similar->curve.tier_version;
  a.curve.immobile_reason = similar->curve.immobile_reason;
  a.similarity = true;
  a.scale_ratio = q.tyre.diameter_m / similar->request.tyre.diameter_m;
  const double ratio = std::min(a.scale_ratio, 1.0 / a.scale_ratio);
  a.reliability = mobility::ScalabilityTable::Seed001().For(ratio, q.soil.cone_index_pa);
  a.source = std::move(*similar);
  return a;
}

// `request` and `curve` are what is answered; `source` the stored curve behind it (the same one,
// except for a similarity hit).
void FillCurve(const TractionRequest& request, const TractionCurve& curve,
               const cache::StoredCurve& source, bool hit, v1::TractionCurve* out) {
  *out->mutable_tyre() = ToProto(request.tyre);
  out->set_wheel_load_n(request.wheel_load_n);
  *out->mutable_soil() = ToProto(request.soil);
  for (const TractionPoint& p : curve.points) *out->add_points() = ToProto(p);
  for (const mobility::DimensionlessPoint& p : mobility::ToDimensionless(request, curve)) {
    v1::DimensionlessPoint* q = out->add_dimensionless();
    q->set_slip(p.slip);
    q->set_drawbar_pull_coefficient(p.drawbar_pull_coefficient);
    q->set_gross_traction_coefficient(p.gross_traction_coefficient);
    q->set_sinkage_over_diameter(p.sinkage_over_diameter);
    q->set_tractive_efficiency(p.tractive_efficiency);
  }
  const mobility::PiTerms pi = mobility::ComputePiTerms(request);
  out->mutable_pi_terms()->set_width_over_diameter(pi.width_over_diameter);
  out->mutable_pi_terms()->set_deflection_over_height(pi.deflection_over_height);
  out->mutable_pi_terms()->set_load_over_bd_pa(pi.load_over_bd_pa);
  v1::Provenance* prov = out->mutable_provenance();
  prov->set_tier(source.curve.tier);
  prov->set_tier_version(source.curve.tier_version);
  prov->set_cache_key(source.cache_key);
  prov->set_cache_hit(hit);
  prov->set_computed_by(source.computed_by);
  prov->set_compute_seconds(source.compute_seconds);
  prov->set_computed_unix_ms(source.computed_unix_ms);
  prov->set_surrogate_model(source.request.surrogate_model);
  if (source.curve.surrogate_run) {
    *prov->mutable_surrogate_run() = ToProto(*source.curve.surrogate_run);
  }
}

void FillCurve(const cache::StoredCurve& s, bool hit, v1::TractionCurve* out) {
  FillCurve(s.request, s.curve, s, hit, out);
}

void FillAnswer(const TractionRequest& request, const CachedAnswer& a, v1::TractionCurve* out) {
  FillCurve(request, a.curve, a.source, true, out);
  if (!a.similarity) return;
  v1::Provenance* prov = out->mutable_provenance();
  prov->set_similarity_hit(true);
  prov->set_similarity_scale_ratio(a.scale_ratio);
  if (a.reliability) {
    v1::SimilarityReliability* r = prov->mutable_reliability();
    r->set_reference_soil(a.reliability->soil);
    r->set_reference_scale(a.reliability->scale);
    r->set_drawbar_pull_pct(a.reliability->drawbar_pull_pct);
    r->set_gross_traction_pct(a.reliability->gross_traction_pct);
    r->set_efficiency_pct(a.reliability->efficiency_pct);
  }
}

}  // namespace gonogo::server
