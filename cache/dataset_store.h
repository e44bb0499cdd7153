// The fe-ann tier's training data: RVE strain-path histories (solvers/ann/strain_history.h), one
// row each, stored as the compact blob SerializeHistory makes, with their provenance: the soil (its
// catalogue name and the canonical text of its parameters), the fe-de configuration whose RVE
// numerics ran the path, the RVE's code version, the path (kind, name, seed), the role the recipe
// that asked for it gave it (training or held-out), the code version, the rank that computed it and
// how long it took. A history is found again by its key (what it is: soil, configuration, RVE
// version and path specification), so that every later training on the same soil reuses it.
//
// A dataset is the histories of one soil and configuration: "<soil>-<preset>-<8 hex of the soil's
// parameters>". The store keeps the blobs opaque; the server parses and exports them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cache/database.h"

namespace gonogo::cache {

inline constexpr char kTrainingRole[] = "training";
inline constexpr char kHeldOutRole[] = "held-out";

struct StoredHistory {
  std::string history_key;
  std::string dataset;
  std::string soil_name;
  std::string soil_parameters;
  std::string fe_de_preset;
  std::string rve_version;
  std::string path_kind;  // "triaxial", "random-walk", ...
  std::string path_name;  // "triaxial 10 kPa"
  std::string role;       // kTrainingRole or kHeldOutRole
  int64_t seed = 0;
  int64_t steps = 0;
  std::string history;    // SerializeHistory's bytes
  std::string code_version;
  std::string computed_by;
  double compute_seconds = 0;
  int64_t created_unix_ms = 0;
};

struct DatasetSummary {
  std::string dataset;
  std::string soil_name;
  std::string soil_parameters;
  std::string fe_de_preset;
  std::string rve_version;
  int64_t histories = 0;
  int64_t training_histories = 0;
  int64_t held_out_histories = 0;
  int64_t steps = 0;
  int64_t bytes = 0;
  double compute_seconds = 0;
  int64_t first_unix_ms = 0;
  int64_t last_unix_ms = 0;
};

// The dataset id of a soil at a configuration; `soil_parameters` is the canonical text.
std::string DatasetId(const std::string& soil_name, const std::string& fe_de_preset,
                      const std::string& soil_parameters);

class DatasetStore {
 public:
  explicit DatasetStore(Database& db) : db_(db) {}

  // Stores one history (committed at once); true when it was stored, false when its key already
  // was (that copy is left as it is: the same path on the same RVE is the same history).
  bool Put(const StoredHistory& history);
  // Whether a history of this key is stored (without reading it).
  bool Has(const std::string& history_key);
  std::optional<StoredHistory> Find(const std::string& history_key);
  // Datasets, newest first; `soil_name` non-empty: that soil's.
  std::vector<DatasetSummary> List(const std::string& soil_name = "");
  // A dataset's histories in the order they were stored; `role` non-empty: that role's;
  // `path_kind` non-empty: that kind's.
  std::vector<StoredHistory> Histories(const std::string& dataset, const std::string& role = "",
                                       const std::string& path_kind = "");
  // Whether the dataset holds a history of `path_kind` (without reading any).
  bool HasKind(const std::string& dataset, const std::string& path_kind);

 private:
  Database& db_;
};

}  // namespace gonogo::cache
