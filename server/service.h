// The gRPC MobilityService. Handlers validate, persist and read; solver work goes to the worker pool
// through the JobManager, never onto a handler thread. Errors are mapped to gRPC codes in one place
// (server/status.h).
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "cache/curve_store.h"
#include "gonogo/v1/mobility.grpc.pb.h"
#include "server/curve_resolver.h"
#include "server/identity.h"
#include "server/job_manager.h"
#include "server/request_convert.h"
#include "server/stall_watch.h"
#include "server/worker_pool.h"
#include "solvers/common/tier.h"

namespace gonogo::server {

// Bounds on what one request may cost (README "Security and limits"; gonogo-server's options).
struct ServiceLimits {
  int64_t max_upload_bytes = 512LL << 20;  // all rasters of one job together (--max-upload-mib)
  // GetTractionCurve's wait for the pool: an fe-classic curve takes minutes on one core
  // (--curve-timeout-s).
  int curve_timeout_ms = 30 * 60 * 1000;
  // Messages of one upload, empty ones included (--max-upload-chunks).
  int64_t max_upload_chunks = 8192;
  // A list answer stops adding entries at this size, under the 4 MiB a gRPC client accepts by
  // default; ListTractionCurves then pages on, ListJobs returns the newest that fit.
  size_t max_page_bytes = 3 << 20;
  // An upload or download stream that moves no message for this long is cancelled
  // (--stream-stall-s).
  int stream_stall_ms = 60'000;
};

class MobilityServiceImpl final : public v1::MobilityService::Service {
 public:
  // `models_dir`: the fe-ann tier's model registry (solvers/tiers/surrogate_registry.h); empty:
  // none. Every call is identified by `authenticator` (server/identity.h) before anything else.
  MobilityServiceImpl(JobManager& jobs, cache::Database& db, const TierRegistry& tiers,
                      CurveResolver& resolver, const Authenticator& authenticator,
                      ServiceLimits limits, std::string models_dir = "");

  // While draining, new work is refused with UNAVAILABLE.
  void SetDraining() { draining_ = true; }

  grpc::Status SubmitMap(grpc::ServerContext*, grpc::ServerReader<v1::SubmitMapRequest>*,
                         v1::Job*) override;
  grpc::Status WatchJob(grpc::ServerContext*, const v1::WatchJobRequest*,
                        grpc::ServerWriter<v1::JobStatus>*) override;
  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job*) override;
  grpc::Status ListJobs(grpc::ServerContext*, const v1::ListJobsRequest*,
                        v1::ListJobsResponse*) override;
  grpc::Status CancelJob(grpc::ServerContext*, const v1::CancelJobRequest*, v1::Job*) override;
  grpc::Status DeleteJob(grpc::ServerContext*, const v1::DeleteJobRequest*,
                         v1::DeleteJobResponse*) override;
  grpc::Status DownloadResult(grpc::ServerContext*, const v1::DownloadResultRequest*,
                              grpc::ServerWriter<v1::ResultChunk>*) override;
  grpc::Status GetTractionCurve(grpc::ServerContext*, const v1::GetTractionCurveRequest*,
                                v1::TractionCurve*) override;
  grpc::Status SubmitCurve(grpc::ServerContext*, const v1::GetTractionCurveRequest*,
                           v1::Job*) override;
  grpc::Status ListTractionCurves(grpc::ServerContext*, const v1::ListTractionCurvesRequest*,
                                  v1::ListTractionCurvesResponse*) override;
  grpc::Status RunScalability(grpc::ServerContext*, const v1::ScalabilityRequest*,
                              v1::ScalabilityReport*) override;
  grpc::Status ListTiers(grpc::ServerContext*, const v1::ListTiersRequest*,
                         v1::ListTiersResponse*) override;
  grpc::Status ListSoilModels(grpc::ServerContext*, const v1::ListSoilModelsRequest*,
                              v1::ListSoilModelsResponse*) override;
  grpc::Status ListSurrogateModels(grpc::ServerContext*, const v1::ListSurrogateModelsRequest*,
                                   v1::ListSurrogateModelsResponse*) override;
  grpc::Status TrainSurrogate(grpc::ServerContext*, const v1::TrainSurrogateRequest*,
                              v1::Job*) override;
  grpc::Status ListDatasets(grpc::ServerContext*, const v1::ListDatasetsRequest*,
                            v1::ListDatasetsResponse*) override;
  grpc::Status ExportDataset(grpc::ServerContext*, const v1::ExportDatasetRequest*,
                             grpc::ServerWriter<v1::ResultChunk>*) override;

 private:
  grpc::Status Authenticate(const grpc::ServerContext& context, Identity* caller) const {
    return authenticator_.Identify(context, caller);
  }
  // The job when `caller` may see it (its owner, or an admin). Another identity's job is NOT_FOUND,
  // worded as for an unknown id, so that ids leak nothing.
  grpc::Status VisibleJob(const std::string& job_id, const Identity& caller, v1::Job* job);

  JobManager& jobs_;
  const Authenticator& authenticator_;
  cache::Database& db_;
  cache::CurveStore curves_;
  const TierRegistry& tiers_;
  CurveResolver& resolver_;
  ServiceLimits limits_;
  StallWatch stall_watch_;
  std::string models_dir_;
  std::atomic<bool> draining_{false};
};

}  // namespace gonogo::server
