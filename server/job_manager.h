// Map jobs on rank 0: persistence, the scheduler thread, progress for watchers, cancellation, resume
// after a restart and draining on SIGTERM (ARCHITECTURE sections 2 and 5).
//
// Up to max_concurrent_jobs scheduler threads take jobs in submission order. For each job one plans
// the traction tasks (one per terrain unit and axle) and hands them to the CurveResolver (cache,
// then the worker pool, every finished curve committed as it arrives), then evaluates every cell and
// writes the products. Jobs running at once share the pool, whose two-lane queue keeps a long job's
// tasks from blocking a short one's. gRPC handlers only enqueue and read status; they never wait for
// a solver.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "cache/curve_store.h"
#include "cache/database.h"
#include "cache/job_store.h"
#include "gonogo/v1/mobility.pb.h"
#include "server/curve_resolver.h"
#include "server/geo/terrain.h"
#include "server/map_plan.h"
#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

struct JobManagerConfig {
  std::string data_dir;
  uint32_t task_delay_ms = 0;   // fault-injection delay added to every task (tests, demos)
  int max_concurrent_jobs = 2;  // map jobs that run at once; the rest wait QUEUED
  geo::GeoLimits limits;
  // The fe-de configuration the server runs (its RVE numerics make the fe-ann training data) and
  // the fe-ann model registry (solvers/tiers/surrogate_registry.h); empty: no training jobs.
  std::string fe_de_preset = "default";
  std::string models_dir;
  // Bounds on what the queue may hold (README "Security and limits"); a submission beyond one is
  // refused with LimitError naming it.
  int64_t max_tasks_per_job = 50'000;   // traction tasks of one map: terrain units x axles
  int max_queued_jobs = 1'000;          // QUEUED jobs of every identity together
  int max_queued_jobs_per_identity = 100;
  // Retention of ended jobs (their records, inputs and products; curves stay in the cache): older
  // than this many days, or, oldest first, beyond this many bytes of job files. 0: no such limit.
  double keep_jobs_days = 30;
  int64_t keep_jobs_bytes = 50LL << 30;
  int retention_sweep_ms = 3'600'000;  // between sweeps; one also runs at Start()
  // Traction curves are physics, shared by every identity; false keeps each identity's to itself
  // (--private-curves).
  bool share_curves = true;
};

// Paths of a job's stored input rasters (empty when not sent).
struct JobInputs {
  std::string cone_index, slope, elevation, soil_class;
};

class JobManager {
 public:
  JobManager(JobManagerConfig config, cache::Database& db, const TierRegistry& tiers,
             CurveResolver& resolver);
  ~JobManager();

  // Directory for a new job's inputs, and a fresh job id.
  std::string NewJobId() const;
  std::string JobDir(const std::string& job_id) const;
  const std::string& data_dir() const { return config_.data_dir; }

  // A map request's terrain, loaded, and its plan (terrain units and traction tasks).
  struct ValidatedMap {
    std::shared_ptr<geo::TerrainLayers> terrain;
    MapPlan plan;
  };
  // Validates everything a job needs before it is accepted: vehicle, criteria, tier, soil table, the
  // rasters themselves and the number of traction tasks they make. Throws InputError / LimitError
  // naming the field. Returns the loaded terrain and its plan, which the job's run goes on with.
  ValidatedMap Validate(const v1::MapRequest& request, const JobInputs& inputs) const;
  // Removes the directories under jobs/ that belong to no job: uploads a crash or a kill cut short.
  // Call before serving; returns how many it removed.
  int CollectOrphanUploads();
  // Persists the job (QUEUED), owned by the identity `owner`, and queues it. A queued job holds no
  // terrain in memory: its run reads the stored inputs. Throws LimitError when the queue is full.
  v1::Job Submit(const std::string& job_id, const std::string& owner, const v1::MapRequest& request);
  // Validates a curve query (tier, tyre, load, soil: InputError naming the field) and persists it
  // as a job of kind "curve" (QUEUED).
  v1::Job SubmitCurve(const std::string& job_id, const std::string& owner,
                      const v1::GetTractionCurveRequest& request);
  // Validates a training request (soil, recipe, base model: InputError naming the field) and
  // persists it as a job of kind "train" (QUEUED); server/train_job.cc.
  v1::Job SubmitTraining(const std::string& job_id, const std::string& owner,
                         const v1::TrainSurrogateRequest& request);
  // Re-queues the jobs a previous run left QUEUED or RUNNING. Call once, before Start().
  int ResumeUnfinished();
  void Start();
  // Stops the scheduler: the running job's outstanding tasks are cancelled and the job goes back to
  // QUEUED, so the next start resumes it; finished curves are already committed.
  void Drain();

  std::optional<v1::Job> GetJob(const std::string& job_id);
  // Newest first; with a non-empty `owner`, that identity's jobs only.
  std::vector<v1::Job> ListJobs(int limit, const std::string& owner);
  // Throws InputError("job_id") when unknown; returns the job after the request. A job cancelled
  // before it started leaves no files.
  v1::Job Cancel(const std::string& job_id);
  // Deletes an ended job: its record and files. Returns the bytes freed. InputError("job_id") when
  // unknown; PreconditionError while it is queued or running.
  int64_t Delete(const std::string& job_id);
  // Applies the retention limits (JobManagerConfig::keep_jobs_*); returns how many jobs it deleted.
  int SweepRetention();
  // The curve-cache scope of `owner` (ResolveOptions::scope): "" while curves are shared.
  std::string CurveScope(const std::string& owner) const { return config_.share_curves ? "" : owner; }
  // True once Drain() has begun.
  bool stopping();
  // Waits until the job's status changes from `seen_version` or `timeout_ms` passes; returns the
  // current status and its version. Unknown job: nullopt.
  std::optional<std::pair<v1::JobStatus, uint64_t>> WaitStatus(const std::string& job_id,
                                                               uint64_t seen_version,
                                                               int timeout_ms);

 private:
  struct Live {  // in-memory state of a queued or running job
    v1::JobStatus status;
    uint64_t version = 1;
    std::atomic<bool> cancel_requested{false};
    std::string owner;
  };
  void Loop();
  void RetentionLoop();
  void RunJob(const std::string& job_id);
  void RunCurveJob(const cache::JobRecord& record, const std::shared_ptr<Live>& live);
  void RunTrainJob(const cache::JobRecord& record, const std::shared_ptr<Live>& live);
  // Persists a new QUEUED job and queues it; LimitError when the queue is full.
  v1::Job Enqueue(cache::JobRecord record);
  void Publish(const std::string& job_id, const v1::JobStatus& status);
  // Sets a running job's message, publishes `status` to watchers and, with `persist`, writes its
  // progress to the job store.
  void ReportProgress(const std::string& job_id, v1::JobStatus& status, const std::string& message,
                      bool persist);
  // A running job the drain interrupted: QUEUED again (persisted, published to watchers), so that
  // the next start resumes it.
  void Requeue(const std::string& job_id);
  // Moves a job to its end state (persisted, published to watchers, logged).
  void Finish(const std::string& job_id, cache::JobState state, const std::string& message,
              const std::string& summary, const std::vector<std::string>& products);
  JobInputs InputsOf(const std::string& job_id) const;

  JobManagerConfig config_;
  cache::Database& db_;
  cache::JobStore jobs_;
  const TierRegistry& tiers_;
  CurveResolver& resolver_;

  std::mutex mutex_;
  std::condition_variable changed_;     // any job status changed, or a job was queued
  std::deque<std::string> queue_;
  std::map<std::string, std::shared_ptr<Live>> live_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace gonogo::server
