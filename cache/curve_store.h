// The traction-curve cache: one SQLite row per curve, committed as soon as it arrives (a crash loses no
// finished curve). Rank 0 is the only writer.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cache/database.h"
#include "solvers/common/traction.h"

namespace gonogo::cache {

struct StoredCurve {
  std::string cache_key;
  TractionRequest request;       // quantised request the curve answers
  TractionCurve curve;
  std::string computed_by;       // "rank N" or "thread"
  double compute_seconds = 0;    // solver wall time, s
  int64_t computed_unix_ms = 0;
  std::string scope;             // "" shared; else cache_key is Scoped(scope, ...) (curve_key.h)
};

struct CurveFilter {
  std::string tier;              // empty: any
  std::string soil_name;         // empty: any
  double min_cone_index_pa = 0;  // 0: unbounded
  double max_cone_index_pa = 0;  // 0: unbounded
  std::string key_prefix;        // empty: any; else only keys that start with it (a scope's)
};

struct CurvePage {
  std::vector<StoredCurve> curves;
  std::vector<int64_t> row_ids;  // of each curve: a page cut short continues before the last kept
  int64_t next_after_id = 0;     // 0 on the last page
};

class CurveStore {
 public:
  explicit CurveStore(Database& db) : db_(db) {}

  std::optional<StoredCurve> Find(const std::string& cache_key);
  // Inserts the curve in its own transaction; a curve already stored under the key is kept.
  // Returns true when a row was written.
  bool Put(const StoredCurve& curve);
  // A stored curve of the same similarity group whose pi-terms match the request's and whose
  // diameter ratio (smaller over larger) is at least `min_scale_ratio`; the closest in size wins.
  std::optional<StoredCurve> FindSimilar(const std::string& similarity_group,
                                         const TractionRequest& quantised, double tolerance,
                                         double min_scale_ratio);
  // Newest first; `before_id` 0 starts at the newest.
  CurvePage List(const CurveFilter& filter, int page_size, int64_t before_id);
  int64_t Count();

 private:
  Database& db_;
};

}  // namespace gonogo::cache
