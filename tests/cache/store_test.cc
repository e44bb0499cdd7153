#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>

#include "cache/curve_key.h"
#include "cache/curve_store.h"
#include "cache/dataset_store.h"
#include "cache/database.h"
#include "cache/job_store.h"

namespace gonogo::cache {
namespace {

namespace fs = std::filesystem;

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("gonogo-cache-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "gonogo.sqlite").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  StoredCurve Curve(double ci_pa, int64_t t_ms) {
    StoredCurve c;
    c.request.soil.cone_index_pa = ci_pa;
    c.request.tyre = TyreGeometry{1.011, 0.335, 0.2178, 0.0327, 0.4728};
    c.request.wheel_load_n = 14513;
    c.request.slips = {0, 0.5, 1};
    c.request = Quantise(c.request);
    c.cache_key = CurveKey("empirical", "empirical-1", c.request);
    c.curve.tier = "empirical";
    c.curve.tier_version = "empirical-1";
    for (double s : c.request.slips) {
      c.curve.points.push_back({s, 1000 * s - 100, 5000 * s, 0.01, 0.5 * s, 1000 * s, 100});
    }
    c.computed_by = "rank 1";
    c.compute_seconds = 1e-5;
    c.computed_unix_ms = t_ms;
    return c;
  }

  fs::path dir_;
  std::string path_;
};

TEST_F(StoreTest, NewFileIsMigratedToTheCurrentSchemaInWalMode) {
  Database db(path_);
  EXPECT_EQ(db.SchemaVersion(), 8);
  Statement s = db.Prepare("PRAGMA journal_mode");
  ASSERT_TRUE(s.Step());
  EXPECT_EQ(s.Text(0), "wal");
}

TEST_F(StoreTest, AVersionOneFileIsMigratedAndKeepsItsCurves) {
  // A cache written by schema version 1 (before Bekker parameters were stored).
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path_.c_str(), &raw), SQLITE_OK);
  const char* v1 = R"sql(
    CREATE TABLE curves (id INTEGER PRIMARY KEY, cache_key TEXT NOT NULL UNIQUE, tier TEXT NOT NULL,
      tier_version TEXT NOT NULL, soil_name TEXT NOT NULL, cone_index_pa REAL NOT NULL,
      diameter_m REAL NOT NULL, width_m REAL NOT NULL, section_height_m REAL NOT NULL,
      deflection_m REAL NOT NULL, rolling_radius_m REAL NOT NULL, wheel_load_n REAL NOT NULL,
      points BLOB NOT NULL, computed_by TEXT NOT NULL, compute_seconds REAL NOT NULL,
      computed_unix_ms INTEGER NOT NULL);
    CREATE TABLE jobs (id TEXT PRIMARY KEY, name TEXT NOT NULL, tier TEXT NOT NULL,
      state INTEGER NOT NULL, fraction_done REAL NOT NULL DEFAULT 0,
      tasks_done INTEGER NOT NULL DEFAULT 0, tasks_total INTEGER NOT NULL DEFAULT 0,
      cache_hits INTEGER NOT NULL DEFAULT 0, message TEXT NOT NULL DEFAULT '',
      request BLOB NOT NULL, summary_json TEXT NOT NULL DEFAULT '',
      products TEXT NOT NULL DEFAULT '', created_unix_ms INTEGER NOT NULL,
      finished_unix_ms INTEGER NOT NULL DEFAULT 0);
    INSERT INTO curves VALUES (1, 'old-key', 'empirical', 'empirical-1', '', 149000, 1.011, 0.335,
      0.2178, 0.0327, 0.4728, 14513, x'', 'thread', 0.001, 77);
    INSERT INTO jobs (id, name, tier, state, request, created_unix_ms)
      VALUES ('job-old', 'old map', 'empirical', 3, x'', 78);
    PRAGMA user_version = 1;)sql";
  ASSERT_EQ(sqlite3_exec(raw, v1, nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);

  Database db(path_);
  EXPECT_EQ(db.SchemaVersion(), 8);
  CurveStore store(db);
  auto old = store.Find("old-key");
  ASSERT_TRUE(old.has_value());
  EXPECT_EQ(old->computed_unix_ms, 77);
  EXPECT_FALSE(old->request.soil.parameters.has_value());
  EXPECT_EQ(old->request.tyre.inflation_pressure_pa, 0.0);
  EXPECT_FALSE(old->curve.surrogate_run.has_value());
  // Jobs from before identities belong to the one identity there was.
  const auto job = JobStore(db).Get("job-old");
  ASSERT_TRUE(job.has_value());
  EXPECT_EQ(job->owner, "local");
  EXPECT_EQ(job->kind, "map");
}

TEST_F(StoreTest, BekkerParametersRoundTrip) {
  StoredCurve c = Curve(0, 5);
  c.request.soil.soil_name = "LETE sand";
  c.request.soil.parameters = BekkerParameters{0.7, 5270, 1515040, 1300, 31.1, 0.0115}.ToSoilModel();
  c.request.tyre.inflation_pressure_pa = 200000;
  c.request = Quantise(c.request);
  c.cache_key = CurveKey("bekker", "bekker-1", c.request);
  Database db(path_);
  CurveStore store(db);
  ASSERT_TRUE(store.Put(c));
  auto back = store.Find(c.cache_key);
  ASSERT_TRUE(back.has_value() && back->request.soil.parameters.has_value());
  EXPECT_DOUBLE_EQ(back->request.soil.parameters->Get("kphi"), 1515040);
  EXPECT_DOUBLE_EQ(back->request.soil.parameters->Get("shear_deformation_m"), 0.0115);
  EXPECT_DOUBLE_EQ(back->request.tyre.inflation_pressure_pa, 200000);
  EXPECT_EQ(CurveKey("bekker", "bekker-1", Quantise(back->request)), c.cache_key)
      << "a stored curve's request gives back its own key";
}

TEST_F(StoreTest, FindSimilarNeedsTheSameGroupMatchingPiTermsAndAnAllowedScale) {
  Database db(path_);
  CurveStore store(db);
  StoredCurve full = Curve(149000, 1);  // d 1.011 m, W 14513 N
  ASSERT_TRUE(store.Put(full));
  auto scaled = [&](double k, double load_factor) {
    TractionRequest r = full.request;
    r.tyre.diameter_m *= k;
    r.tyre.width_m *= k;
    r.tyre.section_height_m *= k;
    r.tyre.deflection_m *= k;
    r.tyre.rolling_radius_m *= k;
    r.wheel_load_n *= k * k * load_factor;
    return Quantise(r);
  };
  const std::string group = SimilarityGroup("empirical", "empirical-1", full.request);
  auto hit = store.FindSimilar(group, scaled(0.7, 1.0), 0.01, 0.5);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->cache_key, full.cache_key);
  EXPECT_FALSE(store.FindSimilar(group, scaled(0.7, 1.05), 0.01, 0.5)) << "5 % more pressure";
  EXPECT_FALSE(store.FindSimilar(group, scaled(0.4, 1.0), 0.01, 0.5)) << "scale below the limit";
  EXPECT_FALSE(store.FindSimilar(SimilarityGroup("empirical", "empirical-2", full.request),
                                 scaled(0.7, 1.0), 0.01, 0.5))
      << "another tier version is another group";
  TractionRequest other_soil = scaled(0.7, 1.0);
  other_soil.soil.cone_index_pa = 300000;
  other_soil = Quantise(other_soil);
  EXPECT_FALSE(store.FindSimilar(SimilarityGroup("empirical", "empirical-1", other_soil),
                                 other_soil, 0.01, 0.5))
      << "another soil";
}

TEST_F(StoreTest, RefusesADatabaseNewerThanTheCode) {
  { Database db(path_); }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(path_.c_str(), &raw), SQLITE_OK);
  sqlite3_exec(raw, "PRAGMA user_version=99", nullptr, nullptr, nullptr);
  sqlite3_close(raw);
  EXPECT_THROW(Database db(path_), DatabaseError);
}

TEST_F(StoreTest, CurvesSurviveReopeningAndRoundTripExactly) {
  const StoredCurve c = Curve(149000, 42);
  {
    Database db(path_);
    CurveStore store(db);
    EXPECT_TRUE(store.Put(c));
    EXPECT_FALSE(store.Put(Curve(149000, 99))) << "an existing key is kept, not overwritten";
  }
  Database db(path_);
  CurveStore store(db);
  auto found = store.Find(c.cache_key);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->computed_unix_ms, 42);
  EXPECT_EQ(found->computed_by, "rank 1");
  ASSERT_EQ(found->curve.points.size(), 3u);
  EXPECT_DOUBLE_EQ(found->curve.points[1].drawbar_pull_n, 400);
  EXPECT_DOUBLE_EQ(found->curve.points[2].torque_nm, 5000);
  EXPECT_DOUBLE_EQ(found->request.tyre.rolling_radius_m, 0.4728);
  EXPECT_EQ(found->request.slips, c.request.slips);
  EXPECT_FALSE(store.Find("no such key").has_value());
}

// An fe-ann curve's provenance (how many points fell back, and when) is kept with it; every other
// tier's curve has none.
TEST_F(StoreTest, ASurrogateCurvesRunRoundTripsExactly) {
  StoredCurve c = Curve(149000, 42);
  SurrogateRun& run = c.curve.surrogate_run.emplace();
  run.fe_steps = 900;
  run.fallbacks = 3;
  run.fallback_point_steps = {449, 450, 637};
  run.fallbacks_flagged.below_pressure_floor = 2;
  run.fallbacks_flagged.beyond_distance = 1;
  run.fallbacks_flagged.beyond_spread = 3;
  run.returns = 1;
  run.unanswered_flags = 7;
  run.fallback_paths_kept = 3;
  run.network_point_updates = 114041;
  run.network_seconds = 2.2812345678901234;
  run.fallback_seconds = 1.0e-3 / 3;
  Database db(path_);
  CurveStore store(db);
  ASSERT_TRUE(store.Put(c));
  ASSERT_TRUE(store.Put(Curve(160000, 43)));
  const std::optional<StoredCurve> found = store.Find(c.cache_key);
  ASSERT_TRUE(found.has_value());
  ASSERT_TRUE(found->curve.surrogate_run.has_value());
  const SurrogateRun& back = *found->curve.surrogate_run;
  EXPECT_EQ(back.fe_steps, 900);
  EXPECT_EQ(back.fallbacks, 3);
  EXPECT_EQ(back.fallback_point_steps, (std::vector<std::int64_t>{449, 450, 637}));
  EXPECT_EQ(back.fallbacks_flagged.below_pressure_floor, 2);
  EXPECT_EQ(back.fallbacks_flagged.beyond_distance, 1);
  EXPECT_EQ(back.fallbacks_flagged.beyond_spread, 3);
  EXPECT_EQ(back.returns, 1);
  EXPECT_EQ(back.unanswered_flags, 7);
  EXPECT_EQ(back.fallback_paths_kept, 3);
  EXPECT_EQ(back.network_point_updates, 114041);
  EXPECT_EQ(back.network_seconds, run.network_seconds);
  EXPECT_EQ(back.fallback_seconds, run.fallback_seconds);
  EXPECT_FALSE(store.Find(Curve(160000, 43).cache_key)->curve.surrogate_run.has_value());

  // No fallback at all is a run too, not an absent one.
  StoredCurve none = Curve(170000, 44);
  none.curve.surrogate_run.emplace().fe_steps = 900;
  ASSERT_TRUE(store.Put(none));
  const std::optional<StoredCurve> none_back = store.Find(none.cache_key);
  ASSERT_TRUE(none_back->curve.surrogate_run.has_value());
  EXPECT_EQ(none_back->curve.surrogate_run->fallbacks, 0);
  EXPECT_TRUE(none_back->curve.surrogate_run->fallback_point_steps.empty());

  // A damaged line is refused by name, not read as no fallback.
  db.Exec("UPDATE curves SET surrogate_run = 'fe_steps=900 fallbacks=x' WHERE cache_key = '" +
          c.cache_key + "'");
  try {
    store.Find(c.cache_key);
    ADD_FAILURE() << "a damaged surrogate run was read";
  } catch (const DatabaseError& e) {
    EXPECT_NE(std::string(e.what()).find("surrogate run"), std::string::npos) << e.what();
  }
}

TEST_F(StoreTest, ListFiltersAndPagesNewestFirst) {
  Database db(path_);
  CurveStore store(db);
  for (int i = 0; i < 7; ++i) store.Put(Curve(100e3 * (i + 1), i));
  EXPECT_EQ(store.Count(), 7);
  CurvePage p1 = store.List({}, 3, 0);
  ASSERT_EQ(p1.curves.size(), 3u);
  EXPECT_GT(p1.curves[0].request.soil.cone_index_pa, p1.curves[2].request.soil.cone_index_pa);
  ASSERT_NE(p1.next_after_id, 0);
  CurvePage p2 = store.List({}, 3, p1.next_after_id);
  CurvePage p3 = store.List({}, 3, p2.next_after_id);
  EXPECT_EQ(p2.curves.size(), 3u);
  EXPECT_EQ(p3.curves.size(), 1u);
  EXPECT_EQ(p3.next_after_id, 0);
  CurveFilter f;
  f.min_cone_index_pa = 250e3;
  f.max_cone_index_pa = 450e3;
  EXPECT_EQ(store.List(f, 50, 0).curves.size(), 2u);
  f = {};
  f.tier = "bekker";
  EXPECT_TRUE(store.List(f, 50, 0).curves.empty());
}

TEST_F(StoreTest, JobsPersistTheirStateAndUnfinishedOnesAreFound) {
  {
    Database db(path_);
    JobStore jobs(db);
    for (int i = 0; i < 3; ++i) {
      JobRecord j;
      j.id = "job-" + std::to_string(i);
      j.name = "map " + std::to_string(i);
      j.tier = "empirical";
      j.request = std::string("\x01\x00\x02", 3);
      j.created_unix_ms = 1000 + i;
      jobs.Create(j);
    }
    jobs.SetState("job-1", JobState::kRunning, "computing");
    jobs.SetProgress("job-1", {0.5, 10, 20, 4, 3, "computing 10/20"});
    jobs.Finish("job-2", JobState::kDone, "done", "{}", {"gonogo.tif", "summary.json"}, 5000);
  }
  Database db(path_);
  JobStore jobs(db);
  auto j1 = jobs.Get("job-1");
  ASSERT_TRUE(j1.has_value());
  EXPECT_EQ(j1->state, JobState::kRunning);
  EXPECT_EQ(j1->tasks_done, 10);
  EXPECT_EQ(j1->cache_hits, 4);
  EXPECT_EQ(j1->similarity_hits, 3);
  EXPECT_EQ(j1->request, std::string("\x01\x00\x02", 3)) << "binary requests survive";
  auto unfinished = jobs.Unfinished();
  ASSERT_EQ(unfinished.size(), 2u);
  EXPECT_EQ(unfinished[0].id, "job-0");
  EXPECT_EQ(unfinished[1].id, "job-1");
  auto done = jobs.Get("job-2");
  EXPECT_EQ(done->products, (std::vector<std::string>{"gonogo.tif", "summary.json"}));
  EXPECT_DOUBLE_EQ(done->fraction_done, 1.0);
  EXPECT_EQ(jobs.List(2).front().id, "job-2");
  EXPECT_FALSE(jobs.Get("job-9").has_value());
}

TEST_F(StoreTest, HistoriesPersistGroupIntoDatasetsAndKeepTheirFirstCopy) {
  const std::string sand = DatasetId("sand", "tiny", "dem-hertz-mindlin:grains=100");
  const std::string other = DatasetId("sand", "tiny", "dem-hertz-mindlin:grains=200");
  EXPECT_NE(sand, other) << "another parameter set is another dataset";
  EXPECT_EQ(sand.rfind("sand-tiny-", 0), 0u) << sand;
  const std::string blob("GNGHIS01\x00\x01\xff", 11);
  {
    Database db(path_);
    DatasetStore store(db);
    for (int k = 0; k < 3; ++k) {
      StoredHistory h;
      h.history_key = "key-" + std::to_string(k);
      h.dataset = k < 2 ? sand : other;
      h.soil_name = "sand";
      h.soil_parameters = "p";
      h.fe_de_preset = "tiny";
      h.rve_version = "fe-de-1-tiny";
      h.path_kind = "triaxial";
      h.path_name = "triaxial " + std::to_string(k);
      h.role = k == 1 ? kHeldOutRole : kTrainingRole;
      h.seed = k;
      h.steps = 10 + k;
      h.history = blob;
      h.computed_by = "rank 1";
      h.compute_seconds = 0.5;
      h.created_unix_ms = 1000 + k;
      store.Put(h);
    }
    StoredHistory again = *store.Find("key-0");
    again.computed_by = "rank 7";
    store.Put(again);  // the same key again: the first copy stays
  }
  Database db(path_);
  DatasetStore store(db);
  const auto found = store.Find("key-0");
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->history, blob) << "binary histories survive";
  EXPECT_EQ(found->computed_by, "rank 1");
  EXPECT_FALSE(store.Find("key-9").has_value());
  EXPECT_TRUE(store.Has("key-0"));
  EXPECT_FALSE(store.Has("key-9"));
  const std::vector<DatasetSummary> all = store.List();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].dataset, other) << "newest first";
  EXPECT_EQ(all[1].dataset, sand);
  EXPECT_EQ(all[1].histories, 2);
  EXPECT_EQ(all[1].training_histories, 1);
  EXPECT_EQ(all[1].held_out_histories, 1);
  EXPECT_EQ(all[1].steps, 21);
  EXPECT_EQ(all[1].bytes, 22);
  EXPECT_DOUBLE_EQ(all[1].compute_seconds, 1.0);
  EXPECT_EQ(all[1].first_unix_ms, 1000);
  EXPECT_EQ(all[1].last_unix_ms, 1001);
  EXPECT_TRUE(store.List("clay").empty());
  EXPECT_EQ(store.Histories(sand).size(), 2u);
  ASSERT_EQ(store.Histories(sand, kHeldOutRole).size(), 1u);
  EXPECT_EQ(store.Histories(sand, kHeldOutRole)[0].path_name, "triaxial 1");
}

}  // namespace
}  // namespace gonogo::cache
