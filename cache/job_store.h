// Persistent jobs: maps, and traction curves too long to answer within one RPC. Every state change is committed at once, so a restarted server knows which
// jobs to resume (QUEUED and RUNNING) and which are finished.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cache/database.h"

namespace gonogo::cache {

// Numbering matches gonogo.v1.JobState.
enum class JobState { kQueued = 1, kRunning = 2, kDone = 3, kFailed = 4, kCancelled = 5 };

bool IsTerminal(JobState state);
const char* JobStateName(JobState state);

inline constexpr char kMapJob[] = "map";      // request: a serialised gonogo.v1.MapRequest
inline constexpr char kCurveJob[] = "curve";  // request: a serialised GetTractionCurveRequest
inline constexpr char kTrainJob[] = "train";  // request: a serialised TrainSurrogateRequest

struct JobRecord {
  std::string id;
  std::string kind = kMapJob;
  std::string owner = "local";  // the identity that submitted it (server/identity.h)
  std::string name;
  std::string tier;
  JobState state = JobState::kQueued;
  double fraction_done = 0;
  int64_t tasks_done = 0;
  int64_t tasks_total = 0;
  int64_t cache_hits = 0;
  int64_t similarity_hits = 0;
  std::string message;
  std::string request;       // serialised request, opaque to the store
  std::string summary_json;  // set when DONE
  std::vector<std::string> products;
  int64_t created_unix_ms = 0;
  int64_t finished_unix_ms = 0;
};

struct JobProgress {
  double fraction_done = 0;
  int64_t tasks_done = 0;
  int64_t tasks_total = 0;
  int64_t cache_hits = 0;
  int64_t similarity_hits = 0;
  std::string message;
};

class JobStore {
 public:
  explicit JobStore(Database& db) : db_(db) {}

  void Create(const JobRecord& job);
  std::optional<JobRecord> Get(const std::string& id);
  // Newest first; with a non-empty `owner`, that identity's jobs only.
  std::vector<JobRecord> List(int limit, const std::string& owner = "");
  // Jobs a restarted server must resume, oldest first.
  std::vector<JobRecord> Unfinished();
  // Ended jobs (DONE, FAILED, CANCELLED), the longest ended first.
  std::vector<JobRecord> Ended();
  // Removes the record; false when there was none.
  bool Delete(const std::string& id);
  void SetState(const std::string& id, JobState state, const std::string& message);
  void SetProgress(const std::string& id, const JobProgress& progress);
  // Moves the job to a terminal state with its summary and products.
  void Finish(const std::string& id, JobState state, const std::string& message,
              const std::string& summary_json, const std::vector<std::string>& products,
              int64_t finished_unix_ms);

 private:
  Database& db_;
};

}  // namespace gonogo::cache
