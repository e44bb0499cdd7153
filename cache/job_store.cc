#include "cache/job_store.h"

#include <sstream>

namespace gonogo::cache {

namespace {

constexpr char kColumns[] =
    "id, name, tier, state, fraction_done, tasks_done, tasks_total, cache_hits, message, request, "
    "summary_json, products, created_unix_ms, finished_unix_ms, similarity_hits, kind, owner";

std::string JoinProducts(const std::vector<std::string>& products) {
  std::string out;
  for (const auto& p : products) out += (out.empty() ? "" : "\n") + p;
  return out;
}

JobRecord ReadRow(const Statement& s) {
  JobRecord j;
  j.id = s.Text(0);
  j.name = s.Text(1);
  j.tier = s.Text(2);
  j.state = static_cast<JobState>(s.Int(3));
  j.fraction_done = s.Double(4);
  j.tasks_done = s.Int(5);
  j.tasks_total = s.Int(6);
  j.cache_hits = s.Int(7);
  j.message = s.Text(8);
  j.request = s.Blob(9);
  j.summary_json = s.Text(10);
  std::istringstream products(s.Text(11));
  for (std::string line; std::getline(products, line);) {
    if (!line.empty()) j.products.push_back(line);
  }
  j.created_unix_ms = s.Int(12);
  j.finished_unix_ms = s.Int(13);
  j.similarity_hits = s.Int(14);
  j.kind = s.Text(15);
  j.owner = s.Text(16);
  return j;
}

}  // namespace

bool IsTerminal(JobState s) {
  return s == JobState::kDone || s == JobState::kFailed || s == JobState::kCancelled;
}

const char* JobStateName(JobState s) {
  switch (s) {
    case JobState::kQueued: return "QUEUED";
    case JobState::kRunning: return "RUNNING";
    case JobState::kDone: return "DONE";
    case JobState::kFailed: return "FAILED";
    case JobState::kCancelled: return "CANCELLED";
  }
  return "UNKNOWN";
}

void JobStore::Create(const JobRecord& j) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare(
      "INSERT INTO jobs (id, name, tier, state, message, request, created_unix_ms, kind, owner) "
      "VALUES (?,?,?,?,?,?,?,?,?)");
  s.Bind(1, j.id).Bind(2, j.name).Bind(3, j.tier).Bind(4, static_cast<int64_t>(j.state));
  s.Bind(5, j.message).BindBlob(6, j.request.data(), j.request.size()).Bind(7, j.created_unix_ms);
  s.Bind(8, j.kind).Bind(9, j.owner);
  s.Run();
  tx.Commit();
}

std::optional<JobRecord> JobStore::Get(const std::string& id) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?");
  s.Bind(1, id);
  if (!s.Step()) return std::nullopt;
  return ReadRow(s);
}

std::vector<JobRecord> JobStore::List(int limit, const std::string& owner) {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns + " FROM jobs" +
                            (owner.empty() ? "" : " WHERE owner = ?") +
                            " ORDER BY created_unix_ms DESC, rowid DESC LIMIT ?");
  int next = 1;
  if (!owner.empty()) s.Bind(next++, owner);
  s.Bind(next, static_cast<int64_t>(limit));
  std::vector<JobRecord> jobs;
  while (s.Step()) jobs.push_back(ReadRow(s));
  return jobs;
}

std::vector<JobRecord> JobStore::Unfinished() {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns +
                            " FROM jobs WHERE state IN (1, 2) ORDER BY created_unix_ms, rowid");
  std::vector<JobRecord> jobs;
  while (s.Step()) jobs.push_back(ReadRow(s));
  return jobs;
}

std::vector<JobRecord> JobStore::Ended() {
  std::lock_guard<std::recursive_mutex> lock(db_.mutex());
  Statement s = db_.Prepare(std::string("SELECT ") + kColumns +
                            " FROM jobs WHERE state NOT IN (1, 2) ORDER BY finished_unix_ms, rowid");
  std::vector<JobRecord> jobs;
  while (s.Step()) jobs.push_back(ReadRow(s));
  return jobs;
}

bool JobStore::Delete(const std::string& id) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare("DELETE FROM jobs WHERE id = ?");
  s.Bind(1, id);
  s.Run();
  const bool deleted = db_.Changes() > 0;
  tx.Commit();
  return deleted;
}

void JobStore::SetState(const std::string& id, JobState state, const std::string& message) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare("UPDATE jobs SET state = ?, message = ? WHERE id = ?");
  s.Bind(1, static_cast<int64_t>(state)).Bind(2, message).Bind(3, id);
  s.Run();
  tx.Commit();
}

void JobStore::SetProgress(const std::string& id, const JobProgress& p) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare(
      "UPDATE jobs SET fraction_done = ?, tasks_done = ?, tasks_total = ?, cache_hits = ?, "
      "message = ?, similarity_hits = ? WHERE id = ?");
  s.Bind(1, p.fraction_done).Bind(2, p.tasks_done).Bind(3, p.tasks_total).Bind(4, p.cache_hits);
  s.Bind(5, p.message).Bind(6, p.similarity_hits).Bind(7, id);
  s.Run();
  tx.Commit();
}

void JobStore::Finish(const std::string& id, JobState state, const std::string& message,
                      const std::string& summary_json, const std::vector<std::string>& products,
                      int64_t finished_unix_ms) {
  WriteTransaction tx(db_);
  Statement s = db_.Prepare(
      "UPDATE jobs SET state = ?, message = ?, summary_json = ?, products = ?, "
      "finished_unix_ms = ?, fraction_done = CASE WHEN ? = 3 THEN 1.0 ELSE fraction_done END "
      "WHERE id = ?");
  const auto st = static_cast<int64_t>(state);
  s.Bind(1, st).Bind(2, message).Bind(3, summary_json).Bind(4, JoinProducts(products));
  s.Bind(5, finished_unix_ms).Bind(6, st).Bind(7, id);
  s.Run();
  tx.Commit();
}

}  // namespace gonogo::cache
