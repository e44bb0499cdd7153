// The curve half of the job manager: traction-curve queries run as jobs (SubmitCurve), for tiers
// whose curves take minutes (server/curve_resolver.h kLongQuerySeconds) or whenever a client asks.
#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "server/convert.h"
#include "server/curve_lookup.h"
#include "server/curve_resolver.h"
#include "server/job_manager.h"
#include "server/job_records.h"
#include "solvers/common/errors.h"

namespace gonogo::server {

namespace fs = std::filesystem;

v1::Job JobManager::SubmitCurve(const std::string& id, const std::string& owner,
                                const v1::GetTractionCurveRequest& request) {
  Require(!request.tier().empty(), "tier", "is missing");
  const TractionTier& tier = tiers_.Get(request.tier());
  Require(request.has_tyre(), "tyre", "is missing");
  CurveResolver::Prepare(tier, FromProto(request));  // validates before anything is persisted
  cache::JobRecord rec;
  rec.id = id;
  rec.owner = owner;
  rec.kind = cache::kCurveJob;
  rec.name = "traction curve";
  rec.tier = tier.Name();
  rec.request = request.SerializeAsString();
  return Enqueue(std::move(rec));
}

// A curve job: one task through the resolver, the solver's progress as the job's, the curve as its
// summary (JSON) and products (curve.json, curve.csv).
void JobManager::RunCurveJob(const cache::JobRecord& rec, const std::shared_ptr<Live>& live) {
  const std::string id = rec.id;
  std::mutex status_mutex;  // the solver's progress arrives on a pool thread
  v1::JobStatus status = StatusOf(rec);
  auto last_persist = std::chrono::steady_clock::now();
  // Persisted at most every 250 ms: the solver may report often.
  auto report = [&](double fraction, const std::string& message, bool force) {
    std::lock_guard<std::mutex> lock(status_mutex);
    status.set_fraction_done(fraction);
    const auto now = std::chrono::steady_clock::now();
    const bool persist = force || now - last_persist > std::chrono::milliseconds(250);
    if (persist) last_persist = now;
    ReportProgress(id, status, message, persist);
  };
  try {
    jobs_.SetState(id, cache::JobState::kRunning, "looking up the cache");
    v1::GetTractionCurveRequest request;
    Require(request.ParseFromString(rec.request), "request", "stored request is unreadable");
    const TractionTier& tier = tiers_.Get(request.tier());
    const CurveTask task = CurveResolver::Prepare(tier, FromProto(request));
    status.set_tasks_total(1);
    report(0.0, "looking up the cache", true);
    ResolveOptions options;
    options.allow_similarity = !request.disable_similarity();
    options.debug_delay_ms = config_.task_delay_ms;
    options.stop = [&] {
      std::lock_guard<std::mutex> lock(mutex_);
      return stopping_ || live->cancel_requested.load();
    };
    options.discard = [&] { return live->cancel_requested.load(); };
    options.scope = CurveScope(rec.owner);
    options.after_lookups = [&](const std::vector<Resolution>& found) {
      if (!found.front().ok()) report(0.0, "computing the traction curve on the pool", true);
    };
    options.on_task_progress = [&](size_t, double fraction, const std::string& note) {
      report(std::clamp(fraction, 0.0, 1.0),
             "computing the traction curve: " + std::to_string(static_cast<int>(100 * fraction)) +
                 " %" + (note.empty() ? std::string() : "; " + note),
             false);
    };
    const Resolution answer = resolver_.Resolve(tier, {task}, options).front();
    bool stopping;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping = stopping_;
    }
    if (live->cancel_requested) return Finish(id, cache::JobState::kCancelled, "cancelled", "", {});
    if (stopping && answer.source == CurveSource::kCancelled) {
      return Requeue(id);
    }
    if (!answer.ok()) {
      return Finish(id, cache::JobState::kFailed,
                    std::string(ErrorKindName(answer.error_kind)) + ": " + answer.error, "", {});
    }
    if (!answer.curve.immobile_reason.empty()) {
      return Finish(id, cache::JobState::kFailed,
                    std::string(ErrorKindName(ErrorKind::kCannotCarry)) + ": " +
                        answer.curve.immobile_reason,
                    "", {});
    }
    v1::TractionCurve curve;
    FillResolved(task.request, answer, &curve);
    std::string json;
    google::protobuf::util::JsonPrintOptions json_options;
    json_options.add_whitespace = true;
    json_options.preserve_proto_field_names = true;
    google::protobuf::util::MessageToJsonString(curve, &json, json_options);
    const fs::path out_dir = fs::path(JobDir(id)) / "out";
    fs::create_directories(out_dir);
    std::ofstream(out_dir / "curve.json") << json << "\n";
    std::ofstream csv(out_dir / "curve.csv");
    csv << "slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency,gross_traction_n,"
           "motion_resistance_n\n";
    for (const v1::TractionPoint& p : curve.points()) {
      csv << p.slip() << "," << p.drawbar_pull_n() << "," << p.torque_nm() << "," << p.sinkage_m()
          << "," << p.tractive_efficiency() << "," << p.gross_traction_n() << ","
          << p.motion_resistance_n() << "\n";
    }
    csv.close();
    {
      std::lock_guard<std::mutex> lock(status_mutex);
      status.set_tasks_done(1);
      status.set_cache_hits(answer.source == CurveSource::kCacheExact ? 1 : 0);
      status.set_similarity_hits(answer.source == CurveSource::kCacheSimilar ? 1 : 0);
      jobs_.SetProgress(id, {1.0, 1, 1, status.cache_hits(), status.similarity_hits(), "done"});
    }
    Finish(id, cache::JobState::kDone, "done", json, {"curve.csv", "curve.json"});
  } catch (const std::exception& e) {
    Finish(id, cache::JobState::kFailed, e.what(), "", {});
  }
}

}  // namespace gonogo::server
