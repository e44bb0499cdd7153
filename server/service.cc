#include "server/service.h"

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>

#include "cache/curve_key.h"
#include "cache/dataset_store.h"
#include "server/convert.h"
#include "server/curve_lookup.h"
#include "server/curve_resolver.h"
#include "server/status.h"
#include "server/scalability.h"
#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"
#include "solvers/tiers/soil_catalogue.h"
#include "solvers/tiers/surrogate_registry.h"

namespace gonogo::server {

namespace fs = std::filesystem;

namespace {

constexpr size_t kChunkBytes = 1 << 20;

const char* RoleFileName(v1::RasterRole role) {
  switch (role) {
    case v1::RASTER_ROLE_CONE_INDEX: return "cone_index.tif";
    case v1::RASTER_ROLE_SLOPE: return "slope.tif";
    case v1::RASTER_ROLE_ELEVATION: return "elevation.tif";
    case v1::RASTER_ROLE_SOIL_CLASS: return "soil_class.tif";
    default: return nullptr;
  }
}

// A CSV field: quoted, with its quotes doubled, when it holds a comma, a quote or a line break.
std::string CsvQuoted(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

fs::path ExportsDir(const std::string& data_dir) { return fs::path(data_dir) / "exports"; }

// A write to the server's own disk failed: the server's failure (RESOURCE_EXHAUSTED when the disk
// is full, INTERNAL otherwise), never reported as the user's bad input.
[[noreturn]] void ThrowStorageFailure(const fs::path& path, int error_number) {
  if (error_number == ENOSPC || error_number == EDQUOT) {
    throw LimitError("server", "the server's disk is full: it could not store " +
                                   path.filename().string() + "; nothing was kept, try again later");
  }
  throw std::runtime_error("the server could not write " + path.filename().string() + ": " +
                           std::strerror(error_number));
}

// Streams the files `names` of `dir`, one after another, in chunks of at most kChunkBytes.
// A client that stops reading is cancelled by `stall_watch`.
grpc::Status StreamFiles(grpc::ServerContext* context, grpc::ServerWriter<v1::ResultChunk>* writer,
                         const fs::path& dir, const std::vector<std::string>& names,
                         StallWatch& stall_watch) {
  StallWatch::Guard guard(stall_watch, context);
  std::string buffer(kChunkBytes, '\0');
  for (const std::string& name : names) {
    const fs::path path = dir / name;
    std::ifstream in(path, std::ios::binary);
    if (!in) return {grpc::StatusCode::INTERNAL, "file " + name + " is missing on the server"};
    const uint64_t total = fs::file_size(path);
    uint64_t offset = 0;
    do {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const auto n = static_cast<size_t>(in.gcount());
      v1::ResultChunk chunk;
      chunk.set_product(name);
      chunk.set_offset(offset);
      chunk.set_total_bytes(total);
      chunk.set_data(buffer.data(), n);
      if (context->IsCancelled() || !writer->Write(chunk)) return grpc::Status::CANCELLED;
      guard.Touch();
      offset += n;
    } while (offset < total);
  }
  return grpc::Status::OK;
}

}  // namespace

MobilityServiceImpl::MobilityServiceImpl(JobManager& jobs, cache::Database& db,
                                         const TierRegistry& tiers, CurveResolver& resolver,
                                         const Authenticator& authenticator, ServiceLimits limits,
                                         std::string models_dir)
    : jobs_(jobs),
      authenticator_(authenticator),
      db_(db),
      curves_(db),
      tiers_(tiers),
      resolver_(resolver),
      limits_(limits),
      stall_watch_(std::chrono::milliseconds(limits.stream_stall_ms)),
      models_dir_(std::move(models_dir)) {
  // Dataset exports are staged here while they stream; what a crash left is of no use.
  std::error_code ignored;
  fs::remove_all(ExportsDir(jobs_.data_dir()), ignored);
}

grpc::Status MobilityServiceImpl::VisibleJob(const std::string& job_id, const Identity& caller,
                                             v1::Job* job) {
  if (job_id.size() > kMaxIdBytes) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            "job_id: is " + std::to_string(job_id.size()) + " bytes long; the limit is " +
                std::to_string(kMaxIdBytes)};
  }
  auto found = jobs_.GetJob(job_id);
  if (!found || (!caller.admin && found->owner() != caller.name)) {
    return {grpc::StatusCode::NOT_FOUND, "job_id: no job '" + job_id + "'"};
  }
  *job = std::move(*found);
  return grpc::Status::OK;
}

grpc::Status MobilityServiceImpl::SubmitMap(grpc::ServerContext* context,
                                            grpc::ServerReader<v1::SubmitMapRequest>* reader,
                                            v1::Job* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  if (draining_) return {grpc::StatusCode::UNAVAILABLE, "server is shutting down"};
  const std::string id = jobs_.NewJobId();
  const fs::path inputs_dir = fs::path(jobs_.JobDir(id)) / "inputs";
  // Whatever happens before the job is persisted, its directory is removed again.
  struct Cleanup {
    fs::path dir;
    bool keep = false;
    ~Cleanup() {
      std::error_code ec;
      if (!keep) fs::remove_all(dir, ec);
    }
  } cleanup{fs::path(jobs_.JobDir(id))};
  try {
    v1::SubmitMapRequest message;
    Require(reader->Read(&message) && message.has_request(), "request",
            "the first message must carry the MapRequest");
    const v1::MapRequest request = message.request();
    RequireShortNames(request);
    fs::create_directories(inputs_dir);
    std::map<v1::RasterRole, std::ofstream> files;
    JobInputs inputs;
    int64_t received = 0;
    int64_t chunks = 0;
    StallWatch::Guard stall_guard(stall_watch_, context);
    while (reader->Read(&message)) {
      stall_guard.Touch();
      if (++chunks > limits_.max_upload_chunks) {
        throw LimitError("chunk", "the upload exceeds the server's limit of " +
                                      std::to_string(limits_.max_upload_chunks) +
                                      " chunks, empty ones included (gonogo-server --max-upload-chunks)");
      }
      Require(message.has_chunk(), "request", "only the first message may carry the MapRequest");
      const char* name = RoleFileName(message.chunk().role());
      Require(name != nullptr, "chunk.role", "unknown raster role");
      received += static_cast<int64_t>(message.chunk().data().size());
      if (received > limits_.max_upload_bytes) {
        throw LimitError("rasters", "the upload exceeds the server's limit of " +
                                        std::to_string(limits_.max_upload_bytes >> 20) +
                                        " MiB (gonogo-server --max-upload-mib)");
      }
      auto& out = files[message.chunk().role()];
      if (!out.is_open()) out.open(inputs_dir / name, std::ios::binary);
      out.write(message.chunk().data().data(),
                static_cast<std::streamsize>(message.chunk().data().size()));
      if (!out) ThrowStorageFailure(inputs_dir / name, errno);
    }
    if (stall_guard.stalled()) {
      throw LimitError("chunk", "no message for " +
                                    std::to_string(limits_.stream_stall_ms / 1000) +
                                    " s: the upload timed out (gonogo-server --stream-stall-s)");
    }
    for (auto& [role, stream] : files) {
      stream.close();
      if (!stream) ThrowStorageFailure(inputs_dir / RoleFileName(role), errno);
      const std::string path = (inputs_dir / RoleFileName(role)).string();
      switch (role) {
        case v1::RASTER_ROLE_CONE_INDEX: inputs.cone_index = path; break;
        case v1::RASTER_ROLE_SLOPE: inputs.slope = path; break;
        case v1::RASTER_ROLE_ELEVATION: inputs.elevation = path; break;
        case v1::RASTER_ROLE_SOIL_CLASS: inputs.soil_class = path; break;
        default: break;
      }
    }
    jobs_.Validate(request, inputs);
    // A client that gave up after its last chunk gets no job created behind its back.
    if (context->IsCancelled()) return grpc::Status::CANCELLED;
    *response = jobs_.Submit(id, caller.name, request);
    cleanup.keep = true;
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::WatchJob(grpc::ServerContext* context,
                                           const v1::WatchJobRequest* request,
                                           grpc::ServerWriter<v1::JobStatus>* writer) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  v1::Job job;
  if (grpc::Status hidden = VisibleJob(request->job_id(), caller, &job); !hidden.ok()) return hidden;
  uint64_t seen = 0;
  while (!context->IsCancelled()) {
    auto status = jobs_.WaitStatus(request->job_id(), seen, 500);
    if (!status) return {grpc::StatusCode::NOT_FOUND, "job_id: no job '" + request->job_id() + "'"};
    if (status->second != seen) {
      seen = status->second;
      if (!writer->Write(status->first)) return grpc::Status::OK;
    }
    const auto state = status->first.state();
    if (state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
        state == v1::JOB_STATE_CANCELLED) {
      return grpc::Status::OK;
    }
    if (state == v1::JOB_STATE_QUEUED && jobs_.stopping()) {
      return {grpc::StatusCode::UNAVAILABLE,
              "server is shutting down: job '" + request->job_id() +
                  "' is QUEUED and resumes when the server starts again"};
    }
  }
  return grpc::Status::CANCELLED;
}

grpc::Status MobilityServiceImpl::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                         v1::Job* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    return VisibleJob(request->job_id(), caller, response);
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                                           v1::ListJobsResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    const int limit = request->limit() == 0 ? 50 : static_cast<int>(std::min(request->limit(), 1000u));
    for (auto& job : jobs_.ListJobs(limit, caller.admin ? "" : caller.name)) {
      // The newest that fit in one answer a client accepts.
      if (response->ByteSizeLong() + job.ByteSizeLong() > limits_.max_page_bytes) break;
      *response->add_jobs() = std::move(job);
    }
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::CancelJob(grpc::ServerContext* context,
                                            const v1::CancelJobRequest* request,
                                            v1::Job* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    v1::Job before;
    if (grpc::Status hidden = VisibleJob(request->job_id(), caller, &before); !hidden.ok()) {
      return hidden;
    }
    const auto state = before.status().state();
    if (state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
        state == v1::JOB_STATE_CANCELLED) {
      return {grpc::StatusCode::FAILED_PRECONDITION,
              "job_id: job '" + request->job_id() + "' has already ended"};
    }
    *response = jobs_.Cancel(request->job_id());
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::DeleteJob(grpc::ServerContext* context,
                                            const v1::DeleteJobRequest* request,
                                            v1::DeleteJobResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    v1::Job job;
    if (grpc::Status hidden = VisibleJob(request->job_id(), caller, &job); !hidden.ok()) return hidden;
    response->set_bytes_freed(static_cast<uint64_t>(jobs_.Delete(request->job_id())));
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::DownloadResult(grpc::ServerContext* context,
                                                 const v1::DownloadResultRequest* request,
                                                 grpc::ServerWriter<v1::ResultChunk>* writer) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  v1::Job job;
  if (grpc::Status hidden = VisibleJob(request->job_id(), caller, &job); !hidden.ok()) return hidden;
  if (job.status().state() != v1::JOB_STATE_DONE) {
    return {grpc::StatusCode::FAILED_PRECONDITION, "job_id: job has no products until it is DONE"};
  }
  std::vector<std::string> wanted;
  for (const auto& p : job.products()) {
    if (request->product().empty() || request->product() == p) wanted.push_back(p);
  }
  if (wanted.empty()) {
    if (request->product().size() > kMaxIdBytes) {
      return {grpc::StatusCode::NOT_FOUND, "product: job has no product of that name"};
    }
    return {grpc::StatusCode::NOT_FOUND, "product: job has no product '" + request->product() + "'"};
  }
  return StreamFiles(context, writer, fs::path(jobs_.JobDir(request->job_id())) / "out", wanted, stall_watch_);
}

grpc::Status MobilityServiceImpl::GetTractionCurve(grpc::ServerContext* context,
                                                   const v1::GetTractionCurveRequest* request,
                                                   v1::TractionCurve* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    if (draining_) return {grpc::StatusCode::UNAVAILABLE, "server is shutting down"};
    Require(!request->tier().empty(), "tier", "is missing");
    const TractionTier& tier = tiers_.Get(request->tier());
    Require(request->has_tyre(), "tyre", "is missing");
    const CurveTask task = CurveResolver::Prepare(tier, FromProto(*request));
    // The pool computes a miss; this handler waits on the answer, not on the solver. A tier that
    // takes minutes is answered here only from the cache.
    ResolveOptions options;
    options.allow_similarity = !request->disable_similarity();
    const double expected_s = tier.Needs(task.request).expected_seconds;
    options.lookup_only = expected_s >= kLongQuerySeconds;
    options.deadline = std::chrono::steady_clock::now() +
                       std::chrono::milliseconds(limits_.curve_timeout_ms);
    options.stop = [context] { return context->IsCancelled(); };
    options.scope = jobs_.CurveScope(caller.name);
    const Resolution answer = resolver_.Resolve(tier, {task}, options).front();
    if (answer.source == CurveSource::kCancelled) {
      return {grpc::StatusCode::DEADLINE_EXCEEDED, "the traction curve was not ready in time"};
    }
    if (answer.source == CurveSource::kUnresolved) {
      return {grpc::StatusCode::FAILED_PRECONDITION,
              "tier: the " + tier.Name() + " tier takes about " +
                  std::to_string(static_cast<int>(expected_s)) +
                  " s a curve and this one is not cached: submit it as a job (SubmitCurve; "
                  "`gonogo curve` does so by itself)"};
    }
    if (!answer.ok()) return StatusFor(answer.error_kind, answer.error);
    if (!answer.curve.immobile_reason.empty()) {
      return StatusFor(ErrorKind::kCannotCarry, answer.curve.immobile_reason);
    }
    FillResolved(task.request, answer, response);
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::SubmitCurve(grpc::ServerContext* context,
                                              const v1::GetTractionCurveRequest* request,
                                              v1::Job* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    if (draining_) return {grpc::StatusCode::UNAVAILABLE, "server is shutting down"};
    *response = jobs_.SubmitCurve(jobs_.NewJobId(), caller.name, *request);
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::ListTractionCurves(grpc::ServerContext* context,
                                                     const v1::ListTractionCurvesRequest* request,
                                                     v1::ListTractionCurvesResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    int64_t before = 0;
    if (!request->page_token().empty()) {
      RequireShort(request->page_token(), kMaxIdBytes, "page_token");
      try {
        before = std::stoll(request->page_token());
      } catch (...) {
        throw InputError("page_token", "is not a token returned by this service");
      }
    }
    const int page_size =
        request->page_size() == 0 ? 50 : static_cast<int>(std::min(request->page_size(), 1000u));
    cache::CurveFilter filter{request->tier(), request->soil_name(), request->min_cone_index_pa(),
                              request->max_cone_index_pa(), /*key_prefix=*/""};
    // Curves kept private (--private-curves) are listed to their identity alone, and to an admin.
    const std::string scope = jobs_.CurveScope(caller.name);
    if (!scope.empty() && !caller.admin) filter.key_prefix = cache::Scoped(scope, "");
    const cache::CurvePage page = curves_.List(filter, page_size, before);
    int64_t next_before = page.next_after_id;
    for (size_t i = 0; i < page.curves.size(); ++i) {
      v1::TractionCurve curve;
      FillCurve(page.curves[i], true, &curve);
      // A page stops short of the entries that would not fit in one answer a client accepts; the
      // next page starts with them.
      if (i > 0 && response->ByteSizeLong() + curve.ByteSizeLong() > limits_.max_page_bytes) {
        next_before = page.row_ids[i - 1];
        break;
      }
      *response->add_curves() = std::move(curve);
    }
    if (next_before) response->set_next_page_token(std::to_string(next_before));
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

}  // namespace gonogo::server

namespace gonogo::server {

grpc::Status MobilityServiceImpl::RunScalability(grpc::ServerContext* context,
                                                 const v1::ScalabilityRequest* request,
                                                 v1::ScalabilityReport* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    if (draining_) return {grpc::StatusCode::UNAVAILABLE, "server is shutting down"};
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::milliseconds(limits_.curve_timeout_ms);
    *response = RunScalabilityStudy(*request, tiers_, resolver_, deadline,
                                    [context] { return context->IsCancelled(); },
                                    jobs_.CurveScope(caller.name));
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::ListTiers(grpc::ServerContext* context, const v1::ListTiersRequest*,
                                            v1::ListTiersResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  for (const std::string& name : tiers_.Names()) {
    const TractionTier& tier = tiers_.Get(name);
    const TierDescription d = tier.Describe();
    const TierNeeds needs = tier.Needs(TractionRequest{});
    v1::TierInfo* info = response->add_tiers();
    info->set_name(name);
    info->set_version(tier.Version());
    info->set_summary(d.summary);
    info->set_reads(d.reads);
    info->set_typical_cost(d.typical_cost);
    info->set_ranks(static_cast<uint32_t>(needs.ranks));
    info->set_threads(static_cast<uint32_t>(needs.threads));
    info->set_expected_seconds(needs.expected_seconds);
    info->set_curves_are_jobs(needs.expected_seconds >= kLongQuerySeconds);
  }
  return grpc::Status::OK;
}

grpc::Status MobilityServiceImpl::ListSoilModels(grpc::ServerContext* context,
                                                 const v1::ListSoilModelsRequest*,
                                                 v1::ListSoilModelsResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  for (const std::string& name : SoilModels().Names()) {
    const SoilModelSpec& spec = *SoilModels().Find(name);
    v1::SoilModelInfo* model = response->add_models();
    model->set_name(spec.name);
    model->set_description(spec.description);
    model->set_source(spec.source);
    for (const SoilParameterSpec& p : spec.parameters) {
      v1::SoilParameterInfo* info = model->add_parameters();
      info->set_name(p.name);
      info->set_unit(p.unit);
      info->set_min(p.min);
      info->set_max(p.max);
      info->set_min_open(p.min_open);
      info->set_max_open(p.max_open);
      info->set_has_default(p.default_value.has_value());
      info->set_default_value(p.default_value.value_or(0));
      info->set_description(p.description);
    }
  }
  const tiers::SoilCatalogue& catalogue = tiers::BuiltinSoilCatalogue();
  for (const std::string& soil : catalogue.Names()) {
    v1::CatalogueSoil* entry = response->add_soils();
    entry->set_name(soil);
    const std::vector<std::string> models = catalogue.ModelsOf(soil);
    for (const std::string& m : models) {
      entry->add_models(m);
      if (entry->source().empty()) entry->set_source(catalogue.Find(soil, m)->source);
    }
    for (const std::string& tier_name : tiers_.Names()) {
      const std::vector<std::string> read = tiers_.Get(tier_name).Describe().soil_models;
      const bool resolves = std::any_of(models.begin(), models.end(), [&](const std::string& m) {
        return std::find(read.begin(), read.end(), m) != read.end();
      });
      if (resolves) entry->add_tiers(tier_name);
    }
  }
  return grpc::Status::OK;
}

grpc::Status MobilityServiceImpl::ListSurrogateModels(
    grpc::ServerContext* context, const v1::ListSurrogateModelsRequest* request,
    v1::ListSurrogateModelsResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    Require(request->soil_name().size() <= 256, "soil_name", "must be at most 256 characters");
    if (models_dir_.empty()) return grpc::Status::OK;
    for (const tiers::RegisteredSurrogate& m :
         tiers::SurrogateRegistry(models_dir_).List(request->soil_name())) {
      *response->add_models() = ToProto(m);
    }
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::TrainSurrogate(grpc::ServerContext* context,
                                                 const v1::TrainSurrogateRequest* request,
                                                 v1::Job* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    if (draining_) return {grpc::StatusCode::UNAVAILABLE, "server is shutting down"};
    RequireShort(request->soil_name(), kMaxNameBytes, "soil_name");
    RequireShort(request->from_model(), kMaxIdBytes, "from_model");
    RequireShort(request->name(), kMaxNameBytes, "name");
    *response = jobs_.SubmitTraining(jobs_.NewJobId(), caller.name, *request);
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::ListDatasets(grpc::ServerContext* context,
                                               const v1::ListDatasetsRequest* request,
                                               v1::ListDatasetsResponse* response) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  try {
    Require(request->soil_name().size() <= 256, "soil_name", "must be at most 256 characters");
    for (const cache::DatasetSummary& d : cache::DatasetStore(db_).List(request->soil_name())) {
      v1::Dataset* out = response->add_datasets();
      out->set_dataset_id(d.dataset);
      out->set_soil_name(d.soil_name);
      out->set_soil_parameters(d.soil_parameters);
      out->set_fe_de_preset(d.fe_de_preset);
      out->set_rve_version(d.rve_version);
      out->set_histories(static_cast<uint32_t>(d.histories));
      out->set_training_histories(static_cast<uint32_t>(d.training_histories));
      out->set_held_out_histories(static_cast<uint32_t>(d.held_out_histories));
      out->set_steps(static_cast<uint64_t>(d.steps));
      out->set_bytes(static_cast<uint64_t>(d.bytes));
      out->set_compute_seconds(d.compute_seconds);
      out->set_first_unix_ms(d.first_unix_ms);
      out->set_last_unix_ms(d.last_unix_ms);
    }
    return grpc::Status::OK;
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

grpc::Status MobilityServiceImpl::ExportDataset(grpc::ServerContext* context,
                                                const v1::ExportDatasetRequest* request,
                                                grpc::ServerWriter<v1::ResultChunk>* writer) {
  Identity caller;
  if (grpc::Status denied = Authenticate(*context, &caller); !denied.ok()) return denied;
  // Staged in a private directory under the data directory, removed whatever happens.
  struct Staging {
    fs::path dir;
    ~Staging() {
      std::error_code ignored;
      if (!dir.empty()) fs::remove_all(dir, ignored);
    }
  } staging;
  try {
    const std::string& id = request->dataset_id();
    Require(!id.empty(), "dataset_id", "is missing");
    Require(id.size() <= 320, "dataset_id", "must be at most 320 characters");
    const std::string format = request->format().empty() ? "csv" : request->format();
    Require(format == "csv" || format == "npy", "format", "must be csv or npy, not '" + format + "'");
    const std::string& role = request->role();
    Require(role.empty() || role == cache::kTrainingRole || role == cache::kHeldOutRole, "role",
            "must be training, held-out or empty (both), not '" + role + "'");
    const std::vector<cache::StoredHistory> rows = cache::DatasetStore(db_).Histories(id, role);
    if (rows.empty()) {
      return {grpc::StatusCode::NOT_FOUND,
              "dataset_id: no histories in dataset '" + id + "'" +
                  (role.empty() ? "" : " with role " + role) + " (`gonogo dataset` lists them)"};
    }
    std::vector<ann::StrainHistory> histories;
    for (const cache::StoredHistory& row : rows) histories.push_back(ann::ParseHistory(row.history));
    std::random_device random;
    staging.dir = ExportsDir(jobs_.data_dir()) /
                  (std::to_string(::getpid()) + "-" + std::to_string(random()));
    fs::create_directories(staging.dir);
    // Names are the dataset's id, which is made of catalogue names and hex: a safe file name.
    const std::string base = id + (role.empty() ? "" : "-" + role);
    std::vector<std::string> names;
    if (format == "csv") {
      names.push_back(base + ".csv");
      ann::WriteHistoriesCsv((staging.dir / names.back()).string(), histories);
    } else {
      names.push_back(base + ".npy");
      ann::WriteHistoriesNpy((staging.dir / names.back()).string(), histories);
      names.push_back(base + ".npy.columns.txt");  // WriteHistoriesNpy writes it beside
    }
    // The provenance of each history, by its number in the table's `history` column.
    names.push_back(base + ".paths.csv");
    std::ofstream index(staging.dir / names.back());
    index << "history,path_kind,path_name,role,seed,steps,fe_de_preset,rve_version,code_version,"
             "computed_by,compute_seconds,created_unix_ms,stopped_reason\n";
    for (size_t k = 0; k < rows.size(); ++k) {
      const cache::StoredHistory& r = rows[k];
      // Names are free text (a fallback path's names its model and wheel, commas included).
      index << k << "," << CsvQuoted(r.path_kind) << "," << CsvQuoted(r.path_name) << ","
            << CsvQuoted(r.role) << "," << r.seed << "," << r.steps << ","
            << CsvQuoted(r.fe_de_preset) << "," << CsvQuoted(r.rve_version) << ","
            << CsvQuoted(r.code_version) << "," << CsvQuoted(r.computed_by) << ","
            << r.compute_seconds << "," << r.created_unix_ms << ","
            << CsvQuoted(histories[k].stopped_reason) << "\n";
    }
    index.close();
    if (!index) return {grpc::StatusCode::INTERNAL, "cannot write the dataset's index"};
    return StreamFiles(context, writer, staging.dir, names, stall_watch_);
  } catch (...) {
    return ToStatus(std::current_exception());
  }
}

}  // namespace gonogo::server
