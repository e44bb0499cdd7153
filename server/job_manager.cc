#include "server/job_manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "cache/curve_key.h"
#include "server/convert.h"
#include "server/curve_lookup.h"
#include "server/curve_resolver.h"
#include "server/geo/products.h"
#include "server/job_records.h"
#include "server/map_plan.h"
#include "server/summary.h"
#include "solvers/common/errors.h"
#include "solvers/mobility/soft_soil.h"

namespace gonogo::server {

namespace fs = std::filesystem;

namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::optional<geo::RasterInput> OptionalRaster(const std::string& path) {
  if (path.empty()) return std::nullopt;
  return geo::RasterInput{ReadFile(path)};
}



}  // namespace

JobManager::JobManager(JobManagerConfig config, cache::Database& db, const TierRegistry& tiers,
                       CurveResolver& resolver)
    : config_(std::move(config)), db_(db), jobs_(db), tiers_(tiers), resolver_(resolver) {
  fs::create_directories(fs::path(config_.data_dir) / "jobs");
}

JobManager::~JobManager() { Drain(); }

std::string JobManager::NewJobId() const {
  static thread_local std::mt19937_64 rng(std::random_device{}());
  char buf[32];
  std::snprintf(buf, sizeof buf, "job-%012llx",
                static_cast<unsigned long long>(rng() & 0xffffffffffffULL));
  return buf;
}

std::string JobManager::JobDir(const std::string& id) const {
  return (fs::path(config_.data_dir) / "jobs" / id).string();
}

JobInputs JobManager::InputsOf(const std::string& id) const {
  JobInputs in;
  const fs::path dir = fs::path(JobDir(id)) / "inputs";
  auto pick = [&](const char* name) {
    const fs::path p = dir / name;
    return fs::exists(p) ? p.string() : std::string();
  };
  in.cone_index = pick("cone_index.tif");
  in.slope = pick("slope.tif");
  in.elevation = pick("elevation.tif");
  in.soil_class = pick("soil_class.tif");
  return in;
}

JobManager::ValidatedMap JobManager::Validate(const v1::MapRequest& request,
                                              const JobInputs& inputs) const {
  Require(request.has_vehicle(), "vehicle", "is missing");
  const mobility::VehicleSpec vehicle = VehicleFromProto(request.vehicle());
  const mobility::Criteria criteria = CriteriaFromProto(request.criteria());
  Require(!request.tier().empty(), "tier", "is missing");
  const TractionTier& tier = tiers_.Get(request.tier());
  Require(!inputs.cone_index.empty(), "cone_index", "the cone-index raster is required");
  Require(inputs.slope.empty() != inputs.elevation.empty(), "slope",
          "send exactly one of a slope raster or an elevation raster");
  Require(inputs.soil_class.empty() || request.soil_table().classes_size() > 0, "soil_table",
          "is required with a soil-class raster");
  const auto soil_table = SoilTableOf(request.soil_table());
  if (tier.UsesSoilName()) {
    // Cone-index-only terrain stays on the empirical tier unless the user maps soils.
    Require(!inputs.soil_class.empty(), "soil_class",
            "the " + tier.Name() + " tier needs a soil-class raster and a soil table that names "
            "library soils or gives their parameters");
    for (const auto& [code, info] : soil_table) {
      const std::string field = "soil_table.classes[code " + std::to_string(code) + "]";
      tier.ValidateSoil(SoilState{0, info.name, info.parameters}, field);
      // A soil the tier has no model for is refused now, not when its curve comes up.
      TractionRequest probe;
      probe.soil = SoilState{0, info.name, info.parameters};
      probe.surrogate_model = request.surrogate_model();
      probe.surrogate_guard = FromProto(request.surrogate_guard());
      tier.ResolveChoices(probe, "");
    }
  } else {
    TractionRequest probe;
    probe.surrogate_model = request.surrogate_model();
    probe.surrogate_guard = FromProto(request.surrogate_guard());
    tier.ResolveChoices(probe, "");
  }

  geo::TerrainInputs t;
  t.cone_index.bytes = ReadFile(inputs.cone_index);
  t.slope = OptionalRaster(inputs.slope);
  t.elevation = OptionalRaster(inputs.elevation);
  t.soil_class = OptionalRaster(inputs.soil_class);
  auto terrain = std::make_shared<geo::TerrainLayers>(geo::LoadTerrain(t, config_.limits));
  if (!terrain->soil_class.empty()) {
    for (size_t c = 0; c < terrain->soil_class.size(); ++c) {
      if (terrain->valid[c] && !soil_table.count(terrain->soil_class[c])) {
        throw InputError("soil_class", "class code " + std::to_string(terrain->soil_class[c]) +
                                           " at row " + std::to_string(c / terrain->grid.width) +
                                           " col " + std::to_string(c % terrain->grid.width) +
                                           " is not in the soil table");
      }
    }
  }
  // The work the map makes, bounded before it is accepted.
  MapPlan plan = PlanMap(*terrain, vehicle, soil_table, tier,
                         TractionRequest::SlipSweep(criteria.slip_step), request.surrogate_model(),
                         FromProto(request.surrogate_guard()));
  if (static_cast<int64_t>(plan.tasks.size()) > config_.max_tasks_per_job) {
    throw LimitError("vehicle.axles",
                     "the map needs " + std::to_string(plan.tasks.size()) + " traction curves (" +
                         std::to_string(plan.units.size()) + " terrain units x " +
                         std::to_string(vehicle.axles.size()) +
                         " axles), above the server's limit of " +
                         std::to_string(config_.max_tasks_per_job) +
                         " (gonogo-server --max-tasks-per-job)");
  }
  return {std::move(terrain), std::move(plan)};
}

v1::Job JobManager::Submit(const std::string& id, const std::string& owner,
                           const v1::MapRequest& request) {
  cache::JobRecord rec;
  rec.id = id;
  rec.owner = owner;
  rec.kind = cache::kMapJob;
  rec.name = request.name();
  rec.tier = request.tier();
  rec.request = request.SerializeAsString();
  return Enqueue(std::move(rec));
}

v1::Job JobManager::Enqueue(cache::JobRecord rec) {
  const std::string id = rec.id;
  rec.state = cache::JobState::kQueued;
  rec.message = "queued";
  rec.created_unix_ms = NowMs();
  {
    // The count and the insertion under one lock, so that concurrent submissions cannot overfill.
    std::lock_guard<std::mutex> lock(mutex_);
    int queued_of_owner = 0;
    for (const std::string& queued : queue_) queued_of_owner += live_[queued]->owner == rec.owner;
    if (static_cast<int>(queue_.size()) >= config_.max_queued_jobs) {
      throw LimitError("jobs", "the server's queue holds its limit of " +
                                   std::to_string(config_.max_queued_jobs) +
                                   " jobs (gonogo-server --max-queued-jobs); try again later");
    }
    if (queued_of_owner >= config_.max_queued_jobs_per_identity) {
      throw LimitError("jobs", "you have " + std::to_string(queued_of_owner) +
                                   " jobs queued, the limit per identity "
                                   "(gonogo-server --max-queued-per-identity); wait for some to "
                                   "start or cancel them");
    }
    jobs_.Create(rec);
    auto live = std::make_shared<Live>();
    live->status = StatusOf(rec);
    live->owner = rec.owner;
    live_[id] = live;
    queue_.push_back(id);
  }
  changed_.notify_all();
  return JobOf(rec);
}

int JobManager::CollectOrphanUploads() {
  const fs::path jobs_dir = fs::path(config_.data_dir) / "jobs";
  if (!fs::exists(jobs_dir)) return 0;
  std::vector<fs::path> orphans;
  for (const auto& entry : fs::directory_iterator(jobs_dir)) {
    if (!jobs_.Get(entry.path().filename().string())) orphans.push_back(entry.path());
  }
  for (const fs::path& orphan : orphans) fs::remove_all(orphan);
  return static_cast<int>(orphans.size());
}

int JobManager::ResumeUnfinished() {
  int n = 0;
  for (const cache::JobRecord& rec : jobs_.Unfinished()) {
    jobs_.SetState(rec.id, cache::JobState::kQueued, "resumed after a restart");
    cache::JobRecord queued = rec;
    queued.state = cache::JobState::kQueued;
    queued.message = "resumed after a restart";
    std::lock_guard<std::mutex> lock(mutex_);
    auto live = std::make_shared<Live>();
    live->status = StatusOf(queued);
    live->owner = rec.owner;
    live_[rec.id] = live;
    queue_.push_back(rec.id);
    ++n;
  }
  return n;
}

void JobManager::Start() {
  for (int i = 0; i < std::max(1, config_.max_concurrent_jobs); ++i) {
    threads_.emplace_back([this] { Loop(); });
  }
  threads_.emplace_back([this] { RetentionLoop(); });
}

namespace {
// Bytes of the regular files under `dir` (0 when it does not exist).
int64_t DirectoryBytes(const fs::path& dir) {
  std::error_code ec;
  int64_t bytes = 0;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec)) bytes += static_cast<int64_t>(it->file_size(ec));
  }
  return bytes;
}
}  // namespace

int64_t JobManager::Delete(const std::string& id) {
  const std::optional<cache::JobRecord> rec = jobs_.Get(id);
  if (!rec) throw InputError("job_id", "no job '" + id + "'");
  if (!cache::IsTerminal(rec->state)) {
    throw PreconditionError("job_id", "job '" + id + "' is " + cache::JobStateName(rec->state) +
                                          "; cancel it first");
  }
  const int64_t bytes = DirectoryBytes(JobDir(id));
  // The record first: a crash between the two leaves files that the next start collects
  // (CollectOrphanUploads), never a record without its files.
  jobs_.Delete(id);
  std::error_code ignored;
  fs::remove_all(JobDir(id), ignored);
  spdlog::info("job {} deleted ({} bytes of files)", id, bytes);
  return bytes;
}

int JobManager::SweepRetention() {
  const std::vector<cache::JobRecord> ended = jobs_.Ended();  // the longest ended first
  const int64_t now = NowMs();
  int deleted = 0;
  std::vector<std::pair<std::string, int64_t>> kept;  // id, bytes; oldest first
  int64_t kept_bytes = 0;
  for (const cache::JobRecord& rec : ended) {
    const double age_days = (now - rec.finished_unix_ms) / 86'400'000.0;
    if (config_.keep_jobs_days > 0 && age_days > config_.keep_jobs_days) {
      Delete(rec.id);
      ++deleted;
      continue;
    }
    kept.emplace_back(rec.id, DirectoryBytes(JobDir(rec.id)));
    kept_bytes += kept.back().second;
  }
  for (size_t i = 0; config_.keep_jobs_bytes > 0 && kept_bytes > config_.keep_jobs_bytes && i < kept.size(); ++i) {
    Delete(kept[i].first);
    kept_bytes -= kept[i].second;
    ++deleted;
  }
  if (deleted > 0) spdlog::info("retention: deleted {} ended jobs (gonogo-server --keep-jobs-days, --keep-jobs-gib)", deleted);
  return deleted;
}

void JobManager::RetentionLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  do {
    lock.unlock();
    try {
      SweepRetention();
    } catch (const std::exception& e) {
      spdlog::error("retention sweep failed: {}", e.what());
    }
    lock.lock();
  } while (!changed_.wait_for(lock, std::chrono::milliseconds(config_.retention_sweep_ms),
                              [this] { return stopping_; }));
}

void JobManager::Drain() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  for (std::thread& t : threads_) t.join();
  threads_.clear();
}

void JobManager::Loop() {
  for (;;) {
    std::string id;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
    }
    RunJob(id);
  }
}

void JobManager::ReportProgress(const std::string& id, v1::JobStatus& status,
                                const std::string& message, bool persist) {
  status.set_state(v1::JOB_STATE_RUNNING);
  status.set_message(message);
  Publish(id, status);
  if (persist) {
    jobs_.SetProgress(id, {status.fraction_done(), status.tasks_done(), status.tasks_total(),
                           status.cache_hits(), status.similarity_hits(), message});
  }
}

void JobManager::Finish(const std::string& id, cache::JobState state, const std::string& message,
                        const std::string& summary, const std::vector<std::string>& products) {
  jobs_.Finish(id, state, message, summary, products, NowMs());
  Publish(id, StatusOf(*jobs_.Get(id)));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    live_.erase(id);  // watchers read ended jobs from the database
  }
  if (state == cache::JobState::kFailed) {
    spdlog::warn("job {} {}: {}", id, cache::JobStateName(state), message);
  } else {
    spdlog::info("job {} {}: {}", id, cache::JobStateName(state), message);
  }
}

void JobManager::Requeue(const std::string& id) {
  jobs_.SetState(id, cache::JobState::kQueued, "interrupted by a shutdown; resumes at next start");
  if (auto rec = jobs_.Get(id)) Publish(id, StatusOf(*rec));
  spdlog::info("job {} interrupted by the shutdown; queued for the next start", id);
}

void JobManager::Publish(const std::string& id, const v1::JobStatus& status) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = live_.find(id);
    if (it == live_.end()) return;
    it->second->status = status;
    it->second->version++;
  }
  changed_.notify_all();
}

std::optional<v1::Job> JobManager::GetJob(const std::string& id) {
  auto rec = jobs_.Get(id);
  if (!rec) return std::nullopt;
  v1::Job job = JobOf(*rec);
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = live_.find(id);
  if (it != live_.end() && !cache::IsTerminal(rec->state)) *job.mutable_status() = it->second->status;
  return job;
}

std::vector<v1::Job> JobManager::ListJobs(int limit, const std::string& owner) {
  std::vector<v1::Job> out;
  for (const auto& rec : jobs_.List(limit, owner)) {
    v1::Job job = JobOf(rec);
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = live_.find(rec.id);
    if (it != live_.end() && !cache::IsTerminal(rec.state)) *job.mutable_status() = it->second->status;
    out.push_back(std::move(job));
  }
  return out;
}

v1::Job JobManager::Cancel(const std::string& id) {
  auto rec = jobs_.Get(id);
  Require(rec.has_value(), "job_id", "no job '" + id + "'");
  if (cache::IsTerminal(rec->state)) return *GetJob(id);
  bool queued = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = live_.find(id);
    if (it != live_.end()) it->second->cancel_requested = true;
    auto q = std::find(queue_.begin(), queue_.end(), id);
    if (q != queue_.end()) {
      queue_.erase(q);
      queued = true;
    }
  }
  if (queued) {
    Finish(id, cache::JobState::kCancelled, "cancelled before it started", "", {});
    std::error_code ignored;
    fs::remove_all(JobDir(id), ignored);  // its uploaded inputs: nothing of it is left
  }
  changed_.notify_all();
  return *GetJob(id);
}

bool JobManager::stopping() {
  std::lock_guard<std::mutex> lock(mutex_);
  return stopping_;
}

std::optional<std::pair<v1::JobStatus, uint64_t>> JobManager::WaitStatus(const std::string& id,
                                                                         uint64_t seen,
                                                                         int timeout_ms) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    auto it = live_.find(id);
    if (it != live_.end()) {
      auto live = it->second;
      changed_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                        [&] {
                          // While draining, a running job is waited for until it is QUEUED again;
                          // a queued one answers at once, so that its watcher can end.
                          return live->version != seen ||
                                 (stopping_ && live->status.state() != v1::JOB_STATE_RUNNING);
                        });
      return std::make_pair(live->status, live->version);
    }
  }
  auto rec = jobs_.Get(id);
  if (!rec) return std::nullopt;
  return std::make_pair(StatusOf(*rec), uint64_t{1});
}

void JobManager::RunJob(const std::string& id) {
  auto rec = jobs_.Get(id);
  std::shared_ptr<Live> live;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    live = live_[id];
    if (!live) live = live_[id] = std::make_shared<Live>();
  }
  if (!rec || cache::IsTerminal(rec->state)) return;
  spdlog::info("job {} ({}, tier {}) started", id, rec->kind, rec->tier);
  if (rec->kind == cache::kCurveJob) return RunCurveJob(*rec, live);
  if (rec->kind == cache::kTrainJob) return RunTrainJob(*rec, live);

  const auto started = std::chrono::steady_clock::now();
  v1::JobStatus status = StatusOf(*rec);
  auto report = [&](const std::string& message, bool persist) {
    ReportProgress(id, status, message, persist);
  };

  try {
    jobs_.SetState(id, cache::JobState::kRunning, "loading terrain");
    report("loading terrain", false);
    v1::MapRequest request;
    Require(request.ParseFromString(rec->request), "request", "stored request is unreadable");
    // The terrain loaded and planned as at submission: the inputs are re-read, not held in memory
    // while the job waited.
    const ValidatedMap validated = Validate(request, InputsOf(id));
    const std::shared_ptr<geo::TerrainLayers>& terrain = validated.terrain;
    const MapPlan& plan = validated.plan;
    const mobility::VehicleSpec vehicle = VehicleFromProto(request.vehicle());
    const mobility::Criteria criteria = CriteriaFromProto(request.criteria());
    const TractionTier& tier = tiers_.Get(request.tier());
    const size_t total = plan.tasks.size();
    std::vector<TractionCurve> curves(total);
    size_t done = 0, hits = 0, similar = 0;
    double smallest_ratio = 1;
    std::map<std::string, int64_t> computed_by;
    std::string failure;
    auto last_persist = std::chrono::steady_clock::now();
    auto show_progress = [&](bool force) {
      status.set_tasks_done(static_cast<uint32_t>(done));
      status.set_fraction_done(0.05 + 0.85 * (total ? double(done) / total : 1.0));
      const bool persist =
          force || std::chrono::steady_clock::now() - last_persist > std::chrono::milliseconds(250);
      if (persist) last_persist = std::chrono::steady_clock::now();
      report("computing traction curves: " + std::to_string(done) + "/" + std::to_string(total),
             persist);
    };
    ResolveOptions options;
    options.allow_similarity = !request.disable_similarity();
    options.debug_delay_ms = config_.task_delay_ms;
    options.stop_on_failure = true;
    options.stop = [&] {
      std::lock_guard<std::mutex> lock(mutex_);
      return stopping_ || live->cancel_requested.load();
    };
    options.discard = [&] { return live->cancel_requested.load(); };
    options.scope = CurveScope(rec->owner);
    options.after_lookups = [&](const std::vector<Resolution>& found) {
      for (const Resolution& r : found) {
        if (!r.ok()) continue;
        ++done;
        if (r.source == CurveSource::kCacheSimilar) {
          ++similar;
          smallest_ratio =
              std::min({smallest_ratio, r.cached->scale_ratio, 1.0 / r.cached->scale_ratio});
        } else {
          ++hits;
        }
      }
      status.set_tasks_total(static_cast<uint32_t>(total));
      status.set_tasks_done(static_cast<uint32_t>(done));
      status.set_cache_hits(static_cast<uint32_t>(hits));
      status.set_similarity_hits(static_cast<uint32_t>(similar));
      status.set_fraction_done(0.05 + 0.85 * (total ? double(done) / total : 1.0));
      report(std::to_string(plan.units.size()) + " terrain units, " + std::to_string(total) +
                 " traction tasks, " + std::to_string(hits) + " from the cache, " +
                 std::to_string(similar) + " from similar tyres",
             true);
    };
    options.on_task_end = [&](size_t i, const Resolution& r) {
      if (r.source == CurveSource::kComputed) {
        computed_by[r.stored.computed_by]++;
        ++done;
      } else if (r.source == CurveSource::kFailed && failure.empty()) {
        failure = "traction task failed (" + tier.Name() + ", cone index " +
                  std::to_string(plan.tasks[i].soil.cone_index_pa) + " Pa, " +
                  ErrorKindName(r.error_kind) + "): " + r.error;
      }
      show_progress(false);
    };
    std::vector<CurveTask> tasks(total);
    for (size_t i = 0; i < total; ++i) tasks[i] = CurveTask{plan.tasks[i], plan.task_keys[i]};
    std::vector<Resolution> resolved = resolver_.Resolve(tier, tasks, options);
    for (size_t i = 0; i < total; ++i) curves[i] = std::move(resolved[i].curve);

    bool stopping;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping = stopping_;
    }
    if (live->cancel_requested) return Finish(id, cache::JobState::kCancelled, "cancelled", "", {});
    if (!failure.empty()) return Finish(id, cache::JobState::kFailed, failure, "", {});
    if (stopping) {
      return Requeue(id);
    }

    report("evaluating cells", true);
    const double vci_pa =
        tier.Name() == "empirical" ? mobility::VehicleConeIndexPa(vehicle, criteria.passes) : 0.0;
    const MapVerdicts verdicts = EvaluateMap(plan, *terrain, vehicle, criteria, curves, vci_pa);

    report("writing products", false);
    const fs::path out_dir = fs::path(JobDir(id)) / "out";
    fs::create_directories(out_dir);
    // A map's curves share one guard, so any of its requests names its version.
    const std::string tier_version =
        plan.tasks.empty() ? tier.Version() : tier.VersionFor(plan.tasks.front());
    SummaryInputs si{id, request, tier.Name(), tier_version, resolver_.pool().Describe(), plan, *terrain,
                     verdicts, total, total - hits - similar, hits, similar, smallest_ratio,
                     computed_by, vci_pa, criteria,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()};
    const std::string summary = BuildSummaryJson(si);
    const std::vector<std::string> products =
        WriteJobProducts(si, summary, UtcNowRfc3339(), out_dir.string());
    status.set_fraction_done(1.0);
    Finish(id, cache::JobState::kDone, "done", summary, products);
  } catch (const std::exception& e) {
    Finish(id, cache::JobState::kFailed, e.what(), "", {});
  }
}

}  // namespace gonogo::server
