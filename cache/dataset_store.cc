#include "cache/dataset_store.h"

#include <cstdio>

namespace gonogo::cache {

namespace {

constexpr char kColumns[] =
    "history_key, dataset, soil_name, soil_parameters, fe_de_preset, rve_version, path_kind, "
    "path_name, role, seed, steps, history, code_version, computed_by, compute_seconds, "
    "created_unix_ms";

StoredHistory ReadRow(const Statement& s) {
  StoredHistory h;
  h.history_key = s.Text(0);
  h.dataset = s.Text(1);
  h.soil_name = s.Text(2);
  h.soil_parameters = s.Text(3);
  h.fe_de_preset = s.Text(4);
  h.rve_version = s.Text(5);
  h.path_kind = s.Text(6);
  h.path_name = s.Text(7);
  h.role = s.Text(8);
  h.seed = s.Int(9);
  h.steps = s.Int(10);
  h.history = s.Blob(11);
  h.code_version = s.Text(12);
  h.computed_by = s.Text(13);
  h.compute_seconds = s.Double(14);
  h.created_unix_ms = s.Int(15);
  return h;
}

}  // namespace

std::string DatasetId(const std::string& soil_name, const std::string& fe_de_preset,
                      const std::string& soil_parameters) {
  std::uint32_t hash = 2166136261u;  // FNV-1a, 32 bit: names parameter sets apart, not a secret
  for (unsigned char byte : soil_parameters) hash = (hash ^ byte) * 16777619u;
  char hex[9];
  std::snprintf(hex, sizeof hex, "%08x", hash);
  return soil_name + "-" + fe_de_preset + "-" + hex;
}

bool DatasetStore::Put(const StoredHistory& h) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare(std::string("INSERT OR IGNORE INTO rve_histories (") + kColumns +
                            ") VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  s.Bind(1, h.history_key).Bind(2, h.dataset).Bind(3, h.soil_name).Bind(4, h.soil_parameters);
  s.Bind(5, h.fe_de_preset).Bind(6, h.rve_version).Bind(7, h.path_kind).Bind(8, h.path_name);
  s.Bind(9, h.role).Bind(10, h.seed).Bind(11, h.steps);
  s.BindBlob(12, h.history.data(), h.history.size());
  s.Bind(13, h.code_version).Bind(14, h.computed_by).Bind(15, h.compute_seconds);
  s.Bind(16, h.created_unix_ms);
  s.Run();
  const bool stored = db_.Changes() > 0;
  tx.Commit();
  return stored;
}

bool DatasetStore::Has(const std::string& key) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare("SELECT 1 FROM rve_histories WHERE history_key = ?");
  s.Bind(1, key);
  return s.Step();
}

bool DatasetStore::HasKind(const std::string& dataset, const std::string& path_kind) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(
      "SELECT 1 FROM rve_histories WHERE dataset = ?1 AND path_kind = ?2 LIMIT 1");
  s.Bind(1, dataset).Bind(2, path_kind);
  return s.Step();
}

std::optional<StoredHistory> DatasetStore::Find(const std::string& key) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns +
                            " FROM rve_histories WHERE history_key = ?");
  s.Bind(1, key);
  if (!s.Step()) return std::nullopt;
  return ReadRow(s);
}

std::vector<DatasetSummary> DatasetStore::List(const std::string& soil_name) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(
      "SELECT dataset, min(soil_name), min(soil_parameters), min(fe_de_preset), "
      "min(rve_version), count(*), sum(role = 'training'), sum(role = 'held-out'), sum(steps), "
      "sum(length(history)), sum(compute_seconds), min(created_unix_ms), max(created_unix_ms) "
      "FROM rve_histories WHERE ?1 = '' OR soil_name = ?1 GROUP BY dataset "
      "ORDER BY max(created_unix_ms) DESC, dataset");
  s.Bind(1, soil_name);
  std::vector<DatasetSummary> out;
  while (s.Step()) {
    DatasetSummary d;
    d.dataset = s.Text(0);
    d.soil_name = s.Text(1);
    d.soil_parameters = s.Text(2);
    d.fe_de_preset = s.Text(3);
    d.rve_version = s.Text(4);
    d.histories = s.Int(5);
    d.training_histories = s.Int(6);
    d.held_out_histories = s.Int(7);
    d.steps = s.Int(8);
    d.bytes = s.Int(9);
    d.compute_seconds = s.Double(10);
    d.first_unix_ms = s.Int(11);
    d.last_unix_ms = s.Int(12);
    out.push_back(std::move(d));
  }
  return out;
}

std::vector<StoredHistory> DatasetStore::Histories(const std::string& dataset,
                                                   const std::string& role,
                                                   const std::string& path_kind) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns +
                            " FROM rve_histories WHERE dataset = ?1 AND (?2 = '' OR role = ?2) "
                            "AND (?3 = '' OR path_kind = ?3) ORDER BY id");
  s.Bind(1, dataset).Bind(2, role).Bind(3, path_kind);
  std::vector<StoredHistory> out;
  while (s.Step()) out.push_back(ReadRow(s));
  return out;
}

}  // namespace gonogo::cache
