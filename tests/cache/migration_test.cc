// A curve cache written by the previous schema (version 3: Bekker text, "gonogo-curve-v1" keys) is
// migrated on open and still serves every curve it held, under the key the current code computes
// for the same request, with the numbers the current tiers compute: no curve lost, none stale.
//
// data/curves_schema_v3.sqlite was written by gonogo-server at schema 3 (commit bf47aba) from three
// `gonogo curve` queries:
//   curve --tier bekker --bekker n=0.79,kc=102000,kphi=5301000,c=1300,phi_deg=31.1,K=0.0115
//         --wheel-diameter 1.011 --wheel-width 0.335 --wheel-load 14513
//   curve --tier bekker --soil lete_sand --wheel-diameter 1.011 --wheel-width 0.335 --wheel-load 14513
//   curve --tier empirical --cone-index 300 --wheel-diameter 1.011 --wheel-width 0.335
//         --section-height 0.2178 --deflection 0.0327 --wheel-load 13438
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "cache/curve_key.h"
#include "cache/curve_store.h"
#include "cache/database.h"
#include "solvers/mobility/similarity.h"
#include "solvers/tiers/builtin_tiers.h"

namespace gonogo::cache {
namespace {

namespace fs = std::filesystem;

TractionRequest RigidWheelRequest() {
  TractionRequest r;
  r.tyre = TyreGeometry{1.011, 0.335, 1.011 / 4, 0.0, 0.0};  // the CLI's rigid wheel: h = d/4
  r.wheel_load_n = 14513;
  r.slips = TractionRequest::SlipSweep(0.05);
  return r;
}

TEST(Migration, SchemaThreeCacheIsServedUnderTheCurrentKeysWithTheCurrentNumbers) {
  const fs::path source =
      fs::path(std::getenv("GONOGO_SOURCE_DIR")) / "tests/cache/data/curves_schema_v3.sqlite";
  const fs::path dir = fs::temp_directory_path() / ("gonogo-migration-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path path = dir / "gonogo.sqlite";
  fs::copy_file(source, path);

  Database db(path.string());
  EXPECT_EQ(db.SchemaVersion(), 8);
  CurveStore store(db);
  EXPECT_EQ(store.List(CurveFilter{}, 100, 0).curves.size(), 3u) << "no curve lost";

  TierRegistry tiers;
  RegisterBuiltinTiers(tiers);
  TractionRequest explicit_bekker = RigidWheelRequest();
  explicit_bekker.soil.parameters =
      BekkerParameters{0.79, 102000, 5301000, 1300, 31.1, 0.0115}.ToSoilModel();
  TractionRequest named_bekker = RigidWheelRequest();
  named_bekker.soil.soil_name = "lete_sand";
  TractionRequest empirical;
  empirical.soil.cone_index_pa = 300e3;
  empirical.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0.0};
  empirical.wheel_load_n = 13438;
  empirical.slips = TractionRequest::SlipSweep(0.05);

  for (const auto& [tier_name, request] : {std::make_pair("bekker", explicit_bekker),
                                           std::make_pair("bekker", named_bekker),
                                           std::make_pair("empirical", empirical)}) {
    const TractionTier& tier = tiers.Get(tier_name);
    TractionRequest r = request;
    r.soil = SoilForTier(tier, r.soil);
    const TractionRequest q = Quantise(r);
    const std::string key = CurveKey(tier.Name(), tier.Version(), q);
    EXPECT_EQ(key.rfind("gonogo-curve-v2;", 0), 0u);
    const auto stored = store.Find(key);
    ASSERT_TRUE(stored.has_value()) << "not found under the current key: " << key;
    EXPECT_EQ(stored->request.soil.parameters, q.soil.parameters);
    // The stored numbers are the ones the current tier computes for the key's request.
    const TractionCurve now = tier.Compute(q);
    ASSERT_EQ(stored->curve.points.size(), now.points.size());
    for (size_t i = 0; i < now.points.size(); ++i) {
      EXPECT_DOUBLE_EQ(stored->curve.points[i].drawbar_pull_n, now.points[i].drawbar_pull_n) << i;
      EXPECT_DOUBLE_EQ(stored->curve.points[i].torque_nm, now.points[i].torque_nm) << i;
      EXPECT_DOUBLE_EQ(stored->curve.points[i].sinkage_m, now.points[i].sinkage_m) << i;
    }
    // Its similarity group was rewritten too: the curve still answers for similar tyres.
    const auto similar = store.FindSimilar(SimilarityGroup(tier.Name(), tier.Version(), q), q,
                                           mobility::kPiTermTolerance,
                                           mobility::kMinimumScaleRatio);
    ASSERT_TRUE(similar.has_value()) << key;
    EXPECT_EQ(similar->cache_key, key);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gonogo::cache
