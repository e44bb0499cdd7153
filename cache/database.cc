#include "cache/database.h"

#include <cstdio>
#include <vector>

#include "solvers/common/traction.h"

namespace gonogo::cache {

namespace {

// Schema migrations, applied in order inside one BEGIN IMMEDIATE transaction each. Entry i takes the
// database from user_version i to i + 1. Never edit a shipped entry: append a new one.
const std::vector<std::string>& Migrations() {
  static const std::vector<std::string> kMigrations = {
      // 0 -> 1: traction curves and jobs.
      R"sql(
      CREATE TABLE curves (
        id INTEGER PRIMARY KEY,
        cache_key TEXT NOT NULL UNIQUE,
        tier TEXT NOT NULL,
        tier_version TEXT NOT NULL,
        soil_name TEXT NOT NULL,
        cone_index_pa REAL NOT NULL,
        diameter_m REAL NOT NULL,
        width_m REAL NOT NULL,
        section_height_m REAL NOT NULL,
        deflection_m REAL NOT NULL,
        rolling_radius_m REAL NOT NULL,
        wheel_load_n REAL NOT NULL,
        points BLOB NOT NULL,
        computed_by TEXT NOT NULL,
        compute_seconds REAL NOT NULL,
        computed_unix_ms INTEGER NOT NULL
      );
      CREATE INDEX curves_by_tier ON curves (tier, soil_name, cone_index_pa);
      CREATE TABLE jobs (
        id TEXT PRIMARY KEY,
        name TEXT NOT NULL,
        tier TEXT NOT NULL,
        state INTEGER NOT NULL,
        fraction_done REAL NOT NULL DEFAULT 0,
        tasks_done INTEGER NOT NULL DEFAULT 0,
        tasks_total INTEGER NOT NULL DEFAULT 0,
        cache_hits INTEGER NOT NULL DEFAULT 0,
        message TEXT NOT NULL DEFAULT '',
        request BLOB NOT NULL,
        summary_json TEXT NOT NULL DEFAULT '',
        products TEXT NOT NULL DEFAULT '',
        created_unix_ms INTEGER NOT NULL,
        finished_unix_ms INTEGER NOT NULL DEFAULT 0
      );
      CREATE INDEX jobs_by_state ON jobs (state);
      )sql",
      // 1 -> 2: Bekker parameters and inflation pressure of the bekker tier's curves.
      R"sql(
      ALTER TABLE curves ADD COLUMN bekker TEXT NOT NULL DEFAULT '';
      ALTER TABLE curves ADD COLUMN inflation_pressure_pa REAL NOT NULL DEFAULT 0;
      )sql",
      // 2 -> 3: the pi-terms of seed 001 for similarity lookups. Rows of earlier versions keep an
      // empty group and are never used as similarity sources.
      R"sql(
      ALTER TABLE curves ADD COLUMN similarity_group TEXT NOT NULL DEFAULT '';
      ALTER TABLE curves ADD COLUMN pi_b_over_d REAL NOT NULL DEFAULT 0;
      ALTER TABLE curves ADD COLUMN pi_delta_over_h REAL NOT NULL DEFAULT 0;
      ALTER TABLE curves ADD COLUMN pi_load_over_bd_pa REAL NOT NULL DEFAULT 0;
      CREATE INDEX curves_by_similarity ON curves (similarity_group, pi_load_over_bd_pa);
      ALTER TABLE curves ADD COLUMN immobile_reason TEXT NOT NULL DEFAULT '';
      ALTER TABLE jobs ADD COLUMN similarity_hits INTEGER NOT NULL DEFAULT 0;
      )sql",
      // 3 -> 4: open soil description. The Bekker text becomes the canonical text of a soil-model
      // parameter set (solvers/common/soil_model.h), and every key and similarity group is rewritten
      // to the v2 form (";bekker=TEXT;" -> ";params=CANONICAL;"), so that each stored curve is found
      // under the key the current code computes for its request: nothing is lost, nothing stale.
      R"sql(
      ALTER TABLE curves ADD COLUMN soil_parameters TEXT NOT NULL DEFAULT '';
      UPDATE curves SET soil_parameters = gonogo_v3_bekker_to_canonical(bekker) WHERE bekker != '';
      UPDATE curves SET
        cache_key = replace(replace(cache_key, ';bekker=' || bekker || ';',
                                    ';params=' || soil_parameters || ';'),
                            'gonogo-curve-v1;', 'gonogo-curve-v2;'),
        similarity_group = replace(replace(similarity_group, ';bekker=' || bekker || ';',
                                           ';params=' || soil_parameters || ';'),
                                   'gonogo-similar-v1;', 'gonogo-similar-v2;');
      ALTER TABLE curves DROP COLUMN bekker;
      )sql",
      // 4 -> 5: jobs of more than one kind (map, curve); older jobs are maps.
      R"sql(
      ALTER TABLE jobs ADD COLUMN kind TEXT NOT NULL DEFAULT 'map';
      )sql",
      // 5 -> 6: RVE strain-path histories, the fe-ann tier's training data (dataset_store.h).
      R"sql(
      CREATE TABLE rve_histories (
        id INTEGER PRIMARY KEY,
        history_key TEXT NOT NULL UNIQUE,
        dataset TEXT NOT NULL,
        soil_name TEXT NOT NULL,
        soil_parameters TEXT NOT NULL,
        fe_de_preset TEXT NOT NULL,
        rve_version TEXT NOT NULL,
        path_kind TEXT NOT NULL,
        path_name TEXT NOT NULL,
        role TEXT NOT NULL,
        seed INTEGER NOT NULL,
        steps INTEGER NOT NULL,
        history BLOB NOT NULL,
        code_version TEXT NOT NULL,
        computed_by TEXT NOT NULL,
        compute_seconds REAL NOT NULL,
        created_unix_ms INTEGER NOT NULL
      );
      CREATE INDEX rve_histories_by_dataset ON rve_histories (dataset, id);
      )sql",
      // 6 -> 7: every job belongs to the identity that submitted it (server/identity.h); jobs
      // stored before belong to the local identity, the only one there was.
      R"sql(
      ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT 'local';
      CREATE INDEX jobs_by_owner ON jobs (owner, created_unix_ms);
      )sql",
      // 7 -> 8: how a surrogate tier's curve answered its points (its fallbacks and when), as
      // curve_store.cc's text; curves stored before have none.
      R"sql(
      ALTER TABLE curves ADD COLUMN surrogate_run TEXT NOT NULL DEFAULT '';
      )sql",
  };
  return kMigrations;
}

// SQL function for migration 3 -> 4: schema-3 Bekker text "n=..,kc=..,kphi=..,c=..,phi_deg=..,K=.."
// to the canonical text of the bekker soil model. NULL for text it cannot read, which fails the
// migration (NOT NULL column) rather than keep a curve under a key nobody computes.
void BekkerTextToCanonical(sqlite3_context* context, int, sqlite3_value** argv) {
  const auto* text = reinterpret_cast<const char*>(sqlite3_value_text(argv[0]));
  BekkerParameters b;
  if (text == nullptr ||
      std::sscanf(text, "n=%lf,kc=%lf,kphi=%lf,c=%lf,phi_deg=%lf,K=%lf", &b.n, &b.kc, &b.kphi,
                  &b.cohesion_pa, &b.friction_angle_deg, &b.shear_deformation_m) != 6) {
    sqlite3_result_null(context);
    return;
  }
  const std::string canonical = CanonicalText(b.ToSoilModel());
  sqlite3_result_text(context, canonical.c_str(), static_cast<int>(canonical.size()),
                      SQLITE_TRANSIENT);
}

void Check(sqlite3* db, int rc, const std::string& what) {
  if (rc != SQLITE_OK && rc != SQLITE_DONE && rc != SQLITE_ROW) {
    throw DatabaseError(what + ": " + sqlite3_errmsg(db));
  }
}

}  // namespace

Statement::Statement(sqlite3* db, const std::string& sql) : db_(db) {
  Check(db_, sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt_, nullptr), "prepare");
}
Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::Bind(int i, int64_t v) {
  Check(db_, sqlite3_bind_int64(stmt_, i, v), "bind");
  return *this;
}
Statement& Statement::Bind(int i, double v) {
  Check(db_, sqlite3_bind_double(stmt_, i, v), "bind");
  return *this;
}
Statement& Statement::Bind(int i, const std::string& t) {
  Check(db_, sqlite3_bind_text(stmt_, i, t.data(), static_cast<int>(t.size()), SQLITE_TRANSIENT),
        "bind");
  return *this;
}
Statement& Statement::BindBlob(int i, const void* data, size_t bytes) {
  Check(db_, sqlite3_bind_blob(stmt_, i, data, static_cast<int>(bytes), SQLITE_TRANSIENT), "bind");
  return *this;
}
Statement& Statement::BindNull(int i) {
  Check(db_, sqlite3_bind_null(stmt_, i), "bind");
  return *this;
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  Check(db_, rc, "step");
  return rc == SQLITE_ROW;
}
void Statement::Run() {
  while (Step()) {
  }
}

int64_t Statement::Int(int c) const { return sqlite3_column_int64(stmt_, c); }
double Statement::Double(int c) const { return sqlite3_column_double(stmt_, c); }
std::string Statement::Text(int c) const {
  const auto* p = sqlite3_column_text(stmt_, c);
  return p ? std::string(reinterpret_cast<const char*>(p), sqlite3_column_bytes(stmt_, c)) : "";
}
std::string Statement::Blob(int c) const {
  const void* p = sqlite3_column_blob(stmt_, c);
  return p ? std::string(static_cast<const char*>(p), sqlite3_column_bytes(stmt_, c)) : "";
}
bool Statement::IsNull(int c) const { return sqlite3_column_type(stmt_, c) == SQLITE_NULL; }

Database::Database(const std::string& path) : path_(path) {
  const int rc = sqlite3_open_v2(path.c_str(), &db_,
                                 SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                                 nullptr);
  if (rc != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw DatabaseError("cannot open " + path + ": " + msg);
  }
  sqlite3_busy_timeout(db_, 10000);
  sqlite3_create_function_v2(db_, "gonogo_v3_bekker_to_canonical", 1,
                             SQLITE_UTF8 | SQLITE_DETERMINISTIC, nullptr, BekkerTextToCanonical,
                             nullptr, nullptr, nullptr);
  Exec("PRAGMA journal_mode=WAL");
  // NORMAL is durable across application crashes in WAL mode; only power loss can drop the last commits.
  Exec("PRAGMA synchronous=NORMAL");
  Exec("PRAGMA foreign_keys=ON");
  Migrate();
}

Database::~Database() { sqlite3_close(db_); }

void Database::Exec(const std::string& sql) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw DatabaseError(msg);
  }
}

int Database::SchemaVersion() {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  Statement s(db_, "PRAGMA user_version");
  s.Step();
  return static_cast<int>(s.Int(0));
}

void Database::Migrate() {
  const int known = static_cast<int>(Migrations().size());
  WriteTransaction tx(*this);
  const int version = SchemaVersion();
  if (version > known) {
    throw DatabaseError(path_ + " has schema version " + std::to_string(version) +
                        ", newer than this gonogo (" + std::to_string(known) +
                        "); refusing to open it");
  }
  for (int v = version; v < known; ++v) {
    Exec(Migrations()[v]);
    Exec("PRAGMA user_version=" + std::to_string(v + 1));
  }
  tx.Commit();
}

WriteTransaction::WriteTransaction(Database& db) : db_(db), lock_(db.mutex()) {
  db_.Exec("BEGIN IMMEDIATE");
}
WriteTransaction::~WriteTransaction() {
  if (!done_) {
    try {
      db_.Exec("ROLLBACK");
    } catch (...) {
    }
  }
}
void WriteTransaction::Commit() {
  db_.Exec("COMMIT");
  done_ = true;
}

}  // namespace gonogo::cache
