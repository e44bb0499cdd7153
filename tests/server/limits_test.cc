// Resource bounds against a real gonogo-server: every request that sizes work is bounded before
// anything is stored (slip sweep, traction tasks of a map, names, upload chunks), vehicles and tyres
// outside their plausible ranges are refused at submission, the queue is bounded per identity and
// in total, a job cancelled while queued leaves no files, a stalled upload is timed out, a full
// disk is the server's failure, files of uploads that never became a job are collected at start,
// and a drain ends every watcher promptly with its job QUEUED for the next start.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <set>
#include <future>
#include <sstream>
#include <thread>

#include "server_process.h"

namespace gonogo::testing {
namespace {

using Clock = std::chrono::steady_clock;

class LimitsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("limits");
    ASSERT_TRUE(MakeSampleTerrain(scratch_->path() / "terrain", 24));
  }
  static void TearDownTestSuite() { delete scratch_; }

  static v1::MapRequest SampleRequest() { return SampleMapRequest(scratch_->path() / "terrain"); }
  static std::vector<std::pair<v1::RasterRole, std::string>> SampleRasters() {
    return SampleMapRasters(scratch_->path() / "terrain");
  }
  // Entries under the data directory's jobs/ (inputs and products of every job).
  static int JobDirs(const fs::path& data) {
    if (!fs::exists(data / "jobs")) return 0;
    return static_cast<int>(std::distance(fs::directory_iterator(data / "jobs"), fs::directory_iterator()));
  }
  static int ListedJobs(v1::MobilityService::Stub& stub) {
    grpc::ClientContext context;
    v1::ListJobsRequest request;
    request.set_limit(1000);
    v1::ListJobsResponse response;
    EXPECT_TRUE(stub.ListJobs(&context, request, &response).ok());
    return response.jobs_size();
  }
  static v1::JobStatus StatusOf(v1::MobilityService::Stub& stub, const std::string& job_id) {
    grpc::ClientContext context;
    v1::GetJobRequest request;
    request.set_job_id(job_id);
    v1::Job job;
    EXPECT_TRUE(stub.GetJob(&context, request, &job).ok());
    return job.status();
  }
  // Polls until the job runs with its tasks planned (10 s at most).
  static bool WaitRunning(v1::MobilityService::Stub& stub, const std::string& job_id) {
    for (int i = 0; i < 200; ++i) {
      const v1::JobStatus s = StatusOf(stub, job_id);
      if (s.state() == v1::JOB_STATE_RUNNING && s.tasks_total() > 0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  static inline ScratchDir* scratch_ = nullptr;
};

v1::GetTractionCurveRequest EmpiricalCurve(double slip_step) {
  v1::GetTractionCurveRequest request;
  request.set_tier("empirical");
  *request.mutable_tyre() = FedAlpha().axles(0).tyre();
  request.set_wheel_load_n(9000);
  request.mutable_soil()->set_cone_index_pa(600e3);
  request.set_slip_step(slip_step);
  return request;
}


// The status's code and message, for EXPECT messages.
std::string Describe(const grpc::Status& s) {
  return std::to_string(s.error_code()) + " " + s.error_message();
}

TEST_F(LimitsTest, ASlipSweepFinerThanTheLimitIsRefusedBeforeAnyWork) {
  ScratchDir scratch("limits-slip");
  ServerProcess server(scratch.path() / "data");
  auto stub = server.Stub();
  for (const double step : {3e-7, 1e-9, 0.000999}) {
    grpc::ClientContext context;
    v1::TractionCurve curve;
    const grpc::Status s = stub->GetTractionCurve(&context, EmpiricalCurve(step), &curve);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_EQ(s.error_message().rfind("slip_step: ", 0), 0u) << s.error_message();
    EXPECT_NE(s.error_message().find("0.001"), std::string::npos) << s.error_message();

    grpc::ClientContext job_context;
    v1::Job job;
    EXPECT_EQ(stub->SubmitCurve(&job_context, EmpiricalCurve(step), &job).error_code(),
              grpc::StatusCode::RESOURCE_EXHAUSTED);

    grpc::ClientContext study_context;
    v1::ScalabilityRequest study;
    study.set_tier("empirical");
    *study.mutable_tyre() = FedAlpha().axles(0).tyre();
    study.set_wheel_load_n(9000);
    study.mutable_soil()->set_cone_index_pa(600e3);
    study.add_scales(1.0);
    study.add_scales(0.5);
    study.set_slip_step(step);
    v1::ScalabilityReport report;
    EXPECT_EQ(stub->RunScalability(&study_context, study, &report).error_code(),
              grpc::StatusCode::RESOURCE_EXHAUSTED);
  }
  EXPECT_EQ(ListedJobs(*stub), 0);
  {
    grpc::ClientContext context;
    v1::ListTractionCurvesRequest request;
    v1::ListTractionCurvesResponse response;
    ASSERT_TRUE(stub->ListTractionCurves(&context, request, &response).ok());
    EXPECT_EQ(response.curves_size(), 0) << "nothing computed, nothing cached";
  }
  // The finest sweep allowed is served.
  grpc::ClientContext context;
  v1::TractionCurve curve;
  const grpc::Status s = stub->GetTractionCurve(&context, EmpiricalCurve(0.001), &curve);
  ASSERT_TRUE(s.ok()) << Describe(s);
  EXPECT_EQ(curve.points_size(), 1001);
}

TEST_F(LimitsTest, ImplausibleVehiclesAndTyresAreRefusedAtSubmissionLeavingNothing) {
  ScratchDir scratch("limits-plausible");
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data);
  auto stub = server.Stub();
  struct Case {
    std::string field;
    std::function<void(v1::Vehicle&)> spoil;
  };
  const std::vector<Case> cases = {
      {"vehicle.mass_kg", [](v1::Vehicle& v) { v.set_mass_kg(1e-30); }},
      {"vehicle.mass_kg", [](v1::Vehicle& v) { v.set_mass_kg(5e7); }},
      {"vehicle.axles[0].tyre.diameter_m", [](v1::Vehicle& v) { v.mutable_axles(0)->mutable_tyre()->set_diameter_m(1e-9); }},
      {"vehicle.axles[0].tyre.width_m", [](v1::Vehicle& v) { v.mutable_axles(0)->mutable_tyre()->set_width_m(40); }},
      {"vehicle.drive_power_w", [](v1::Vehicle& v) { v.set_drive_power_w(1e12); }},
      {"vehicle.max_speed_kmh", [](v1::Vehicle& v) { v.set_max_speed_kmh(5000); }},
      {"vehicle.axles", [](v1::Vehicle& v) {
         const v1::Axle axle = v.axles(0);
         v.clear_axles();
         for (int i = 0; i < 21; ++i) {
           *v.add_axles() = axle;
           v.mutable_axles(i)->set_load_fraction(1.0 / 21);
         }
       }},
  };
  for (const Case& c : cases) {
    v1::MapRequest request = SampleRequest();
    c.spoil(*request.mutable_vehicle());
    v1::Job job;
    const grpc::Status s = Submit(*stub, request, SampleRasters(), &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.field << ": " << Describe(s);
    EXPECT_EQ(s.error_message().rfind(c.field + ": ", 0), 0u) << c.field << ": " << s.error_message();
  }
  // A curve query's wheel load and cone index are bounded the same way.
  v1::GetTractionCurveRequest curve = EmpiricalCurve(0.05);
  curve.set_wheel_load_n(1e-6);
  grpc::ClientContext context;
  v1::TractionCurve answer;
  const grpc::Status s = stub->GetTractionCurve(&context, curve, &answer);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(s);
  EXPECT_NE(s.error_message().find("wheel_load_n: 1e-06 N is outside the plausible range [10, 1.5e+06] N"),
            std::string::npos)
      << s.error_message();

  EXPECT_EQ(ListedJobs(*stub), 0);
  EXPECT_EQ(JobDirs(data), 0) << "a refused upload leaves no files";
}

TEST_F(LimitsTest, AMapNeedingMoreTractionCurvesThanTheLimitIsRefused) {
  ScratchDir scratch("limits-tasks");
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data, {"--max-tasks-per-job", "3"});
  auto stub = server.Stub();
  v1::Job job;
  const grpc::Status s = Submit(*stub, SampleRequest(), SampleRasters(), &job);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
  EXPECT_NE(s.error_message().find("above the server's limit of 3 (gonogo-server --max-tasks-per-job)"),
            std::string::npos)
      << s.error_message();
  EXPECT_EQ(ListedJobs(*stub), 0);
  EXPECT_EQ(JobDirs(data), 0);
}

TEST_F(LimitsTest, NamesIdsAndUploadChunksAreBounded) {
  ScratchDir scratch("limits-strings");
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data, {"--max-upload-chunks", "16"});
  auto stub = server.Stub();
  {
    v1::MapRequest request = SampleRequest();
    request.set_name(std::string(300, 'n'));
    v1::Job job;
    const grpc::Status s = Submit(*stub, request, SampleRasters(), &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_EQ(s.error_message(), "name: is 300 bytes long; the limit is 256");
  }
  {
    v1::MapRequest request = SampleRequest();
    request.mutable_soil_table()->mutable_classes(0)->set_name(std::string(100'000, 's'));
    v1::Job job;
    const grpc::Status s = Submit(*stub, request, SampleRasters(), &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_NE(s.error_message().find("].name: is 100000 bytes long"), std::string::npos) << s.error_message();
  }
  {
    grpc::ClientContext context;
    v1::GetJobRequest request;
    request.set_job_id(std::string(10'000, 'j'));
    v1::Job job;
    const grpc::Status s = stub->GetJob(&context, request, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_LT(s.error_message().size(), 200u) << "the id is not echoed back";
  }
  {
    // Empty chunks count: 17 messages of nothing are as many as the limit allows, and one more.
    std::vector<std::pair<v1::RasterRole, std::string>> rasters = SampleRasters();
    for (int i = 0; i < 17; ++i) rasters.emplace_back(v1::RASTER_ROLE_CONE_INDEX, "");
    v1::Job job;
    const grpc::Status s = Submit(*stub, SampleRequest(), rasters, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_NE(s.error_message().find("16 chunks, empty ones included (gonogo-server --max-upload-chunks)"),
              std::string::npos)
        << s.error_message();
  }
  EXPECT_EQ(ListedJobs(*stub), 0);
  EXPECT_EQ(JobDirs(data), 0);
  // Within the limits, the same server takes the map.
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
  EXPECT_EQ(WaitForEnd(*stub, job.job_id()).state(), v1::JOB_STATE_DONE);
}

TEST_F(LimitsTest, TheQueueIsBoundedPerIdentityAndACancelledQueuedJobLeavesNoFiles) {
  ScratchDir scratch("limits-queue");
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data, {"--token-file", WriteTokenFile(scratch.path()).string(), "--max-jobs", "1",
                              "--threads", "1", "--task-delay-ms", "200", "--max-queued-per-identity",
                              "1", "--max-queued-jobs", "2"});
  auto alice = server.Stub(kAliceToken);
  auto bob = server.Stub(kBobToken);
  auto ops = server.Stub(kOpsToken);
  v1::Job running, queued, bobs;
  ASSERT_TRUE(Submit(*alice, SampleRequest(), SampleRasters(), &running).ok());
  ASSERT_TRUE(WaitRunning(*alice, running.job_id()));
  ASSERT_TRUE(Submit(*alice, SampleRequest(), SampleRasters(), &queued).ok());
  EXPECT_EQ(StatusOf(*alice, queued.job_id()).state(), v1::JOB_STATE_QUEUED);

  v1::Job refused;
  grpc::Status s = Submit(*alice, SampleRequest(), SampleRasters(), &refused);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
  EXPECT_NE(s.error_message().find("gonogo-server --max-queued-per-identity"), std::string::npos)
      << s.error_message();
  // Another identity has its own share, up to the total.
  ASSERT_TRUE(Submit(*bob, SampleRequest(), SampleRasters(), &bobs).ok());
  s = Submit(*ops, SampleRequest(), SampleRasters(), &refused);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
  EXPECT_NE(s.error_message().find("gonogo-server --max-queued-jobs"), std::string::npos) << s.error_message();
  EXPECT_EQ(JobDirs(data), 3) << "refused submissions leave no files";

  // Cancelling a queued job frees what it held: its inputs are gone, its record says CANCELLED.
  ASSERT_TRUE(fs::exists(data / "jobs" / queued.job_id()));
  for (const auto& [stub, job] : {std::make_pair(alice.get(), queued), std::make_pair(bob.get(), bobs)}) {
    grpc::ClientContext context;
    v1::CancelJobRequest cancel;
    cancel.set_job_id(job.job_id());
    v1::Job after;
    ASSERT_TRUE(stub->CancelJob(&context, cancel, &after).ok());
    EXPECT_EQ(after.status().state(), v1::JOB_STATE_CANCELLED);
    EXPECT_FALSE(fs::exists(data / "jobs" / job.job_id()));
  }
  // Its place in the queue is free again.
  v1::Job next;
  ASSERT_TRUE(Submit(*alice, SampleRequest(), SampleRasters(), &next).ok());
  EXPECT_EQ(server.Terminate(), 0);
}

TEST_F(LimitsTest, HeldOpenStreamsCannotTakeMoreThanTheServersCallThreads) {
  ScratchDir scratch("limits-threads");
  ServerProcess server(scratch.path() / "data",
                       {"--max-rpc-threads", "4", "--task-delay-ms", "300", "--threads", "1"});
  auto stub = server.Stub();
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
  // Watchers that never end while the job runs, each holding a server thread.
  struct Watcher {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<v1::JobStatus>> reader;
  };
  std::vector<std::unique_ptr<Watcher>> held;
  int refused = 0;
  for (int i = 0; i < 6; ++i) {
    auto w = std::make_unique<Watcher>();
    v1::WatchJobRequest request;
    request.set_job_id(job.job_id());
    w->reader = stub->WatchJob(&w->context, request);
    v1::JobStatus first;
    if (w->reader->Read(&first)) {
      held.push_back(std::move(w));
    } else {
      const grpc::Status s = w->reader->Finish();
      EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
      ++refused;
    }
  }
  EXPECT_GE(held.size(), 1u);
  EXPECT_GE(refused, 1) << "6 streams on a server of 4 call threads";
  // The streams end (the clients go away): the threads serve calls again.
  for (auto& w : held) w->context.TryCancel();
  for (auto& w : held) w->reader->Finish();
  bool served = false;
  for (int i = 0; i < 40 && !served; ++i) {
    grpc::ClientContext context;
    v1::ListTiersResponse tiers;
    served = stub->ListTiers(&context, {}, &tiers).ok();
    if (!served) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(served);
}


TEST_F(LimitsTest, ACancelTakesEffectWithinASecondAndCommitsNoCurveAfterIt) {
  ScratchDir scratch("limits-cancel");
  // Every task takes 600 ms, so that two are in flight, part-way, when the cancel arrives.
  ServerProcess server(scratch.path() / "data", {"--task-delay-ms", "600", "--threads", "2"});
  auto stub = server.Stub();
  v1::MapRequest request = SampleRequest();
  request.set_disable_similarity(true);
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, request, SampleRasters(), &job).ok());
  ASSERT_TRUE(WaitRunning(*stub, job.job_id()));
  for (int i = 0; i < 100 && StatusOf(*stub, job.job_id()).tasks_done() < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the next two are part-way
  grpc::ClientContext context;
  v1::CancelJobRequest cancel;
  cancel.set_job_id(job.job_id());
  v1::Job after;
  const Clock::time_point cancelled = Clock::now();
  ASSERT_TRUE(stub->CancelJob(&context, cancel, &after).ok());
  const int curves_at_cancel = CurveCount(*stub);
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  EXPECT_EQ(end.state(), v1::JOB_STATE_CANCELLED);
  EXPECT_LT(Clock::now() - cancelled, std::chrono::milliseconds(1500)) << "the cancel takes effect within a second";
  EXPECT_LT(end.tasks_done(), end.tasks_total());
  // The tasks that were part-way would have finished by now: their curves are dropped.
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  EXPECT_EQ(CurveCount(*stub), curves_at_cancel) << "no curve committed after the cancel";
  EXPECT_GE(curves_at_cancel, 2) << "the curves finished before the cancel stay";
}

TEST_F(LimitsTest, AClientThatCancelsAfterItsLastChunkGetsNoJob) {
  ScratchDir scratch("limits-cancelled-upload");
  // A terrain large enough that validation (GDAL, warping, planning) takes far longer than the
  // cancel takes to arrive.
  const fs::path terrain = scratch.path() / "terrain";
  ASSERT_TRUE(MakeSampleTerrain(terrain, 600));
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data);
  auto stub = server.Stub();
  v1::MapRequest request = SampleRequest();
  *request.mutable_soil_table() = SampleSoilTable(terrain);
  grpc::ClientContext context;
  v1::Job job;
  auto writer = stub->SubmitMap(&context, &job);
  v1::SubmitMapRequest first;
  *first.mutable_request() = request;
  ASSERT_TRUE(writer->Write(first));
  for (const auto& [role, name] : {std::make_pair(v1::RASTER_ROLE_CONE_INDEX, "cone_index.tif"),
                                   std::make_pair(v1::RASTER_ROLE_ELEVATION, "elevation.tif"),
                                   std::make_pair(v1::RASTER_ROLE_SOIL_CLASS, "soil_class.tif")}) {
    v1::SubmitMapRequest chunk;
    chunk.mutable_chunk()->set_role(role);
    chunk.mutable_chunk()->set_data(ReadFile(terrain / name));
    ASSERT_TRUE(writer->Write(chunk));
  }
  ASSERT_TRUE(writer->WritesDone());
  context.TryCancel();  // the client gives up once everything is sent
  EXPECT_EQ(writer->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // The server finishes validating, sees the cancel, and keeps nothing.
  for (int i = 0; i < 100 && JobDirs(data) > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(JobDirs(data), 0);
  EXPECT_EQ(ListedJobs(*stub), 0);
}

TEST_F(LimitsTest, AListPageStopsShortOfTheMessageSizeAClientAccepts) {
  ScratchDir scratch("limits-page-bytes");
  ServerProcess server(scratch.path() / "data");
  auto stub = server.Stub();
  // 80 curves of 1,001 points each: several MiB in all, more than one answer may carry.
  constexpr int kCurves = 80;
  for (int i = 0; i < kCurves; ++i) {
    v1::GetTractionCurveRequest request = EmpiricalCurve(0.001);
    request.set_wheel_load_n(5000 + 50 * i);
    request.set_disable_similarity(true);
    grpc::ClientContext context;
    v1::TractionCurve curve;
    ASSERT_TRUE(stub->GetTractionCurve(&context, request, &curve).ok());
  }
  std::set<std::string> keys;
  int pages = 0;
  std::string token;
  do {
    grpc::ClientContext context;
    v1::ListTractionCurvesRequest request;
    request.set_page_size(1000);
    request.set_page_token(token);
    v1::ListTractionCurvesResponse response;
    const grpc::Status s = stub->ListTractionCurves(&context, request, &response);
    ASSERT_TRUE(s.ok()) << Describe(s);
    EXPECT_LE(response.ByteSizeLong(), 3u << 20);
    EXPECT_GT(response.curves_size(), 0);
    for (const auto& c : response.curves()) keys.insert(c.provenance().cache_key());
    token = response.next_page_token();
    ++pages;
  } while (!token.empty() && pages < 20);
  EXPECT_GE(pages, 2) << "the curves do not fit in one answer";
  EXPECT_EQ(keys.size(), static_cast<size_t>(kCurves)) << "every curve once, over the pages";
}

TEST_F(LimitsTest, AStalledUploadIsCancelledAndLeavesNothing) {
  ScratchDir scratch("limits-stall");
  const fs::path data = scratch.path() / "data";
  ServerProcess server(data, {"--stream-stall-s", "1"});
  auto stub = server.Stub();
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  v1::Job job;
  auto writer = stub->SubmitMap(&context, &job);
  v1::SubmitMapRequest first;
  *first.mutable_request() = SampleRequest();
  ASSERT_TRUE(writer->Write(first));
  v1::SubmitMapRequest chunk;
  chunk.mutable_chunk()->set_role(v1::RASTER_ROLE_CONE_INDEX);
  chunk.mutable_chunk()->set_data(SampleRasters()[0].second.substr(0, 1000));
  ASSERT_TRUE(writer->Write(chunk));
  // The client now sends nothing more and waits for the answer.
  const Clock::time_point stalled = Clock::now();
  const grpc::Status s = writer->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::CANCELLED) << Describe(s);
  EXPECT_GT(Clock::now() - stalled, std::chrono::milliseconds(900));
  EXPECT_LT(Clock::now() - stalled, std::chrono::seconds(5)) << "cancelled after --stream-stall-s";
  for (int i = 0; i < 100 && JobDirs(data) > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(JobDirs(data), 0);
  EXPECT_EQ(ListedJobs(*stub), 0);
  // A slow but moving upload is not a stalled one: the server is still whole.
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
  EXPECT_EQ(WaitForEnd(*stub, job.job_id()).state(), v1::JOB_STATE_DONE);
}

TEST_F(LimitsTest, AFullDiskIsTheServersFailureNotTheUsersRaster) {
  ScratchDir scratch("limits-disk");
  const fs::path data = scratch.path() / "data";
  fs::create_directories(data);
  // An 8 MiB file system for the data directory (mounting needs root, as CI and this test run).
  if (RunShell("mount -t tmpfs -o size=8m,mode=0700 gonogo-limits-test " + data.string()).exit_code != 0) {
    GTEST_SKIP() << "mounting a small tmpfs needs root";
  }
  struct Unmount {
    fs::path path;
    ~Unmount() { RunShell("umount " + path.string()); }
  } unmount{data};
  {
    ServerProcess server(data);
    auto stub = server.Stub();
    // A valid map whose cone-index upload is padded past the disk's free space: the raster is not
    // at fault, the server's disk is.
    std::vector<std::pair<v1::RasterRole, std::string>> rasters = SampleRasters();
    rasters.emplace_back(v1::RASTER_ROLE_SLOPE, std::string(12 << 20, 'x'));
    v1::Job job;
    const grpc::Status s = Submit(*stub, SampleRequest(), rasters, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    EXPECT_NE(s.error_message().find("the server's disk is full"), std::string::npos) << s.error_message();
    EXPECT_EQ(JobDirs(data), 0) << "what was written is removed again";
    // The space comes back with the refused upload's files: the next map runs.
    ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
    EXPECT_EQ(WaitForEnd(*stub, job.job_id()).state(), v1::JOB_STATE_DONE);
    EXPECT_EQ(server.Terminate(), 0);
  }
  EXPECT_EQ(IntegrityCheck(data), "ok");
}

// Bytes of the files under `dir`.
int64_t DirectoryBytes(const fs::path& dir) {
  int64_t bytes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) bytes += static_cast<int64_t>(entry.file_size());
  }
  return bytes;
}

// Polls (10 s at most) until `path` is gone.
bool WaitGone(const fs::path& path) {
  for (int i = 0; i < 200 && fs::exists(path); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return !fs::exists(path);
}

TEST_F(LimitsTest, EndedJobsAreDeletedOnRequestAndByTheRetentionLimits) {
  ScratchDir scratch("limits-retention");
  const fs::path data = scratch.path() / "data";
  const std::string tokens = WriteTokenFile(scratch.path()).string();
  std::vector<std::string> ids;
  int curves = 0;
  {
    ServerProcess server(data, {"--token-file", tokens, "--task-delay-ms", "20"});
    auto alice = server.Stub(kAliceToken);
    auto bob = server.Stub(kBobToken);
    for (int i = 0; i < 3; ++i) {
      v1::MapRequest request = SampleRequest();
      request.mutable_criteria()->set_design_slip(0.15 + 0.05 * i);  // three jobs, one set of curves
      v1::Job job;
      ASSERT_TRUE(Submit(*alice, request, SampleRasters(), &job).ok());
      ASSERT_EQ(WaitForEnd(*alice, job.job_id()).state(), v1::JOB_STATE_DONE);
      ids.push_back(job.job_id());
    }
    {
      grpc::ClientContext context;
      v1::ListTractionCurvesResponse response;
      ASSERT_TRUE(alice->ListTractionCurves(&context, {}, &response).ok());
      curves = response.curves_size();
      ASSERT_GT(curves, 0);
    }
    const auto delete_job = [](v1::MobilityService::Stub& stub, const std::string& id) {
      grpc::ClientContext context;
      v1::DeleteJobRequest request;
      request.set_job_id(id);
      v1::DeleteJobResponse response;
      return stub.DeleteJob(&context, request, &response);
    };
    // A job still at work is cancelled first.
    v1::MapRequest busy_request = SampleRequest();
    busy_request.set_disable_similarity(true);
    busy_request.mutable_criteria()->set_slip_step(0.01);  // new curves: 20 ms each
    v1::Job busy;
    ASSERT_TRUE(Submit(*alice, busy_request, SampleRasters(), &busy).ok());
    grpc::Status s = delete_job(*alice, busy.job_id());
    EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << Describe(s);
    EXPECT_NE(s.error_message().find("; cancel it first"), std::string::npos) << s.error_message();
    {
      grpc::ClientContext context;
      v1::CancelJobRequest cancel;
      cancel.set_job_id(busy.job_id());
      v1::Job after;
      ASSERT_TRUE(alice->CancelJob(&context, cancel, &after).ok());
      EXPECT_EQ(WaitForEnd(*alice, busy.job_id()).state(), v1::JOB_STATE_CANCELLED);
    }
    // Another identity's job is not there for bob.
    s = delete_job(*bob, ids[0]);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND) << Describe(s);
    EXPECT_TRUE(fs::exists(data / "jobs" / ids[0]));
    // Its owner deletes it with the CLI: record and files go, the curves stay.
    const CliRun deleted = Gonogo(server.endpoint(), std::string("--token ") + kAliceToken + " delete " + ids[0]);
    EXPECT_EQ(deleted.exit_code, 0) << deleted.out;
    EXPECT_NE(deleted.out.find(ids[0] + " deleted, "), std::string::npos) << deleted.out;
    EXPECT_NE(deleted.out.find(" MiB freed"), std::string::npos) << deleted.out;
    EXPECT_FALSE(fs::exists(data / "jobs" / ids[0]));
    {
      grpc::ClientContext context;
      v1::GetJobRequest request;
      request.set_job_id(ids[0]);
      v1::Job gone;
      EXPECT_EQ(alice->GetJob(&context, request, &gone).error_code(), grpc::StatusCode::NOT_FOUND);
    }
    {
      grpc::ClientContext context;
      v1::ListTractionCurvesRequest request;
      request.set_page_size(1000);
      v1::ListTractionCurvesResponse response;
      ASSERT_TRUE(alice->ListTractionCurves(&context, request, &response).ok());
      EXPECT_GE(response.curves_size(), curves) << "curves are the shared cache's, not the job's";
    }
    EXPECT_EQ(server.Terminate(), 0);
  }
  // Retention by size: a limit just below what the ended jobs hold deletes the longest ended one.
  const int64_t total = DirectoryBytes(data / "jobs");
  std::ostringstream gib;
  gib.precision(17);
  gib << static_cast<double>(total - DirectoryBytes(data / "jobs" / ids[1]) + 1) / (1LL << 30);
  {
    ServerProcess server(data, {"--keep-jobs-gib", gib.str()});
    EXPECT_TRUE(WaitGone(data / "jobs" / ids[1]));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    EXPECT_TRUE(fs::exists(data / "jobs" / ids[2])) << "the newer jobs fit in the limit";
    EXPECT_EQ(server.Terminate(), 0);
  }
  // Retention by age: everything ended before now goes.
  {
    ServerProcess server(data, {"--keep-jobs-days", "1e-9", "--token-file", tokens});
    EXPECT_TRUE(WaitGone(data / "jobs" / ids[2]));
    for (int i = 0; i < 100 && ListedJobs(*server.Stub(kOpsToken)) > 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(ListedJobs(*server.Stub(kOpsToken)), 0);
    EXPECT_EQ(JobDirs(data), 0);
    EXPECT_EQ(server.Terminate(), 0);
  }
  EXPECT_EQ(IntegrityCheck(data), "ok");
}

TEST_F(LimitsTest, ADrainEndsEveryWatcherPromptlyWithItsJobQueuedAgain) {
  ScratchDir scratch("limits-drain");
  const fs::path data = scratch.path() / "data";
  std::string running_id, queued_id;
  {
    ServerProcess server(data, {"--max-jobs", "1", "--threads", "1", "--task-delay-ms", "300"});
    auto stub = server.Stub();
    v1::Job running, queued;
    ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &running).ok());
    ASSERT_TRUE(WaitRunning(*stub, running.job_id()));
    ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &queued).ok());
    running_id = running.job_id();
    queued_id = queued.job_id();

    // One watcher per job, each recording the states it saw and how its stream ended.
    struct Watched {
      std::vector<v1::JobState> states;
      grpc::Status end;
      Clock::time_point ended;
    };
    const auto watch = [&](const std::string& id) {
      return std::async(std::launch::async, [&server, id] {
        auto watcher = server.Stub();
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::minutes(2));
        v1::WatchJobRequest request;
        request.set_job_id(id);
        auto reader = watcher->WatchJob(&context, request);
        Watched w;
        v1::JobStatus status;
        while (reader->Read(&status)) w.states.push_back(status.state());
        w.end = reader->Finish();
        w.ended = Clock::now();
        return w;
      });
    };
    auto running_watch = watch(running_id);
    auto queued_watch = watch(queued_id);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // both streams open

    const Clock::time_point term = Clock::now();
    EXPECT_EQ(server.Terminate(), 0);
    EXPECT_LT(Clock::now() - term, std::chrono::seconds(3)) << "the server is gone within about a second";
    for (auto* future : {&running_watch, &queued_watch}) {
      const Watched w = future->get();
      EXPECT_EQ(w.end.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(w.end);
      EXPECT_NE(w.end.error_message().find("is QUEUED and resumes when the server starts again"),
                std::string::npos)
          << w.end.error_message();
      ASSERT_FALSE(w.states.empty());
      EXPECT_EQ(w.states.back(), v1::JOB_STATE_QUEUED);
      EXPECT_LT(w.ended - term, std::chrono::seconds(3)) << "the stream ends with the drain";
    }
  }
  EXPECT_EQ(IntegrityCheck(data), "ok");
  // An upload a crash cut short: a directory under jobs/ that no job owns. The next start removes
  // it and resumes both jobs.
  fs::create_directories(data / "jobs" / "j-cut-short" / "inputs");
  std::ofstream(data / "jobs" / "j-cut-short" / "inputs" / "cone_index.tif") << "partial";
  ServerProcess again(data);
  EXPECT_FALSE(fs::exists(data / "jobs" / "j-cut-short"));
  EXPECT_TRUE(fs::exists(data / "jobs" / running_id));
  EXPECT_NE(again.banner().find("2 jobs resumed"), std::string::npos) << again.banner();
  auto stub = again.Stub();
  EXPECT_EQ(WaitForEnd(*stub, running_id).state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(WaitForEnd(*stub, queued_id).state(), v1::JOB_STATE_DONE);
}

}  // namespace
}  // namespace gonogo::testing
