// The MobilityService end to end against a real gonogo-server on a loopback port: health and
// reflection, a sample map through every RPC, the cache on a second run, bad input of every kind,
// cancellation, traction-curve queries and the SIGTERM drain.
#include <gdal.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include <ogr_srs_api.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "raster_fixtures.h"
#include "server_process.h"

namespace gonogo::testing {
namespace {

using nlohmann::json;

class ServiceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("service");
    ASSERT_TRUE(MakeSampleTerrain(scratch_->path() / "terrain", 48));
    server_ = new ServerProcess(scratch_->path() / "data");
  }
  static void TearDownTestSuite() {
    delete server_;
    delete scratch_;
  }

  static std::string Terrain(const std::string& name) {
    return ReadFile(scratch_->path() / "terrain" / name);
  }

  static v1::MapRequest SampleRequest() { return SampleMapRequest(scratch_->path() / "terrain"); }

  static std::vector<std::pair<v1::RasterRole, std::string>> SampleRasters() {
    return SampleMapRasters(scratch_->path() / "terrain");
  }

  // Runs the sample map to the end and returns its summary.
  static json RunSample(std::string* job_id = nullptr) {
    auto stub = server_->Stub();
    v1::Job job;
    const grpc::Status s = Submit(*stub, SampleRequest(), SampleRasters(), &job);
    EXPECT_TRUE(s.ok()) << s.error_message();
    const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
    EXPECT_EQ(end.state(), v1::JOB_STATE_DONE) << end.message();
    if (job_id) *job_id = job.job_id();
    grpc::ClientContext ctx;
    v1::GetJobRequest req;
    req.set_job_id(job.job_id());
    v1::Job done;
    stub->GetJob(&ctx, req, &done);
    return json::parse(done.summary_json());
  }

  static int64_t CurveCount() {
    auto stub = server_->Stub();
    int64_t n = 0;
    std::string token;
    do {
      grpc::ClientContext ctx;
      v1::ListTractionCurvesRequest req;
      req.set_page_size(1000);
      req.set_page_token(token);
      v1::ListTractionCurvesResponse resp;
      EXPECT_TRUE(stub->ListTractionCurves(&ctx, req, &resp).ok());
      n += resp.curves_size();
      token = resp.next_page_token();
    } while (!token.empty());
    return n;
  }

  static ScratchDir* scratch_;
  static ServerProcess* server_;
};

ScratchDir* ServiceTest::scratch_ = nullptr;
ServerProcess* ServiceTest::server_ = nullptr;

TEST_F(ServiceTest, HealthIsServingAndReflectionListsTheService) {
  auto health = grpc::health::v1::Health::NewStub(server_->Channel());
  for (const std::string name : {"", "gonogo.v1.MobilityService"}) {
    grpc::ClientContext ctx;
    grpc::health::v1::HealthCheckRequest req;
    req.set_service(name);
    grpc::health::v1::HealthCheckResponse resp;
    ASSERT_TRUE(health->Check(&ctx, req, &resp).ok());
    EXPECT_EQ(resp.status(), grpc::health::v1::HealthCheckResponse::SERVING) << name;
  }
  auto reflection = grpc::reflection::v1alpha::ServerReflection::NewStub(server_->Channel());
  grpc::ClientContext ctx;
  auto stream = reflection->ServerReflectionInfo(&ctx);
  grpc::reflection::v1alpha::ServerReflectionRequest req;
  req.set_list_services("*");
  ASSERT_TRUE(stream->Write(req));
  stream->WritesDone();
  grpc::reflection::v1alpha::ServerReflectionResponse resp;
  ASSERT_TRUE(stream->Read(&resp));
  std::vector<std::string> names;
  for (const auto& s : resp.list_services_response().service()) names.push_back(s.name());
  EXPECT_NE(std::find(names.begin(), names.end(), "gonogo.v1.MobilityService"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "grpc.health.v1.Health"), names.end());
}

TEST_F(ServiceTest, SampleMapProducesGeoreferencedProductsAndASecondRunComputesNothing) {
  std::string first_id;
  const json first = RunSample(&first_id);
  const int64_t total = first["tasks"]["total"];
  EXPECT_GT(total, 0);
  EXPECT_EQ(first["tasks"]["computed"].get<int64_t>() + first["tasks"]["cache_hits"].get<int64_t>() +
                first["tasks"]["similarity_hits"].get<int64_t>(),
            total);
  EXPECT_EQ(first["provenance"]["tier"], "empirical");
  EXPECT_EQ(first["provenance"]["vehicle_name"], "FED Alpha");
  EXPECT_TRUE(first["tasks"]["computed_by"].contains("thread") ||
              first["tasks"]["computed"].get<int64_t>() == 0);
  double percent = 0;
  for (const char* k : {"GO", "SLOW-GO", "NO-GO"}) percent += first["classes"][k]["percent_of_valid"].get<double>();
  EXPECT_NEAR(percent, 100.0, 0.05);
  EXPECT_GT(first["classes"]["GO"]["cells"].get<int64_t>(), 0) << "firm flat ground is GO";
  EXPECT_GT(first["classes"]["NO-GO"]["cells"].get<int64_t>(), 0) << "soft ground is NO-GO";

  // Products: CRS and geotransform of the cone-index input, palette, nodata, legend.
  auto stub = server_->Stub();
  auto files = DownloadAll(*stub, first_id);
  for (const char* name : {"gonogo.tif", "gonogo.tif.aux.xml", "gonogo.qml", "speed.tif",
                           "speed.qml", "gonogo.kmz", "quicklook.png", "summary.json", "item.json"}) {
    EXPECT_GT(files[name].size(), 0u) << name;
  }
  GDALAllRegister();
  VSILFILE* f = VSIFileFromMemBuffer("/vsimem/out_gonogo.tif",
                                     reinterpret_cast<GByte*>(files["gonogo.tif"].data()),
                                     files["gonogo.tif"].size(), FALSE);
  VSIFCloseL(f);
  const std::string ci_bytes = Terrain("cone_index.tif");
  std::string ci_copy = ci_bytes;
  VSIFCloseL(VSIFileFromMemBuffer("/vsimem/in_ci.tif", reinterpret_cast<GByte*>(ci_copy.data()),
                                  ci_copy.size(), FALSE));
  GDALDatasetH out = GDALOpen("/vsimem/out_gonogo.tif", GA_ReadOnly);
  GDALDatasetH in = GDALOpen("/vsimem/in_ci.tif", GA_ReadOnly);
  ASSERT_NE(out, nullptr);
  ASSERT_NE(in, nullptr);
  double gt_out[6], gt_in[6];
  GDALGetGeoTransform(out, gt_out);
  GDALGetGeoTransform(in, gt_in);
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(gt_out[i], gt_in[i]);
  EXPECT_TRUE(OSRIsSame(GDALGetSpatialRef(out), GDALGetSpatialRef(in)));
  GDALRasterBandH band = GDALGetRasterBand(out, 1);
  EXPECT_EQ(GDALGetRasterDataType(band), GDT_Byte);
  int has_nodata = 0;
  EXPECT_EQ(GDALGetRasterNoDataValue(band, &has_nodata), 255);
  EXPECT_TRUE(has_nodata);
  ASSERT_NE(GDALGetRasterColorTable(band), nullptr);
  const GDALColorEntry* no_go = GDALGetColorEntry(GDALGetRasterColorTable(band), 0);
  EXPECT_GT(no_go->c1, 200);  // red
  EXPECT_LT(no_go->c2, 100);
  std::string legend;
  for (char** md = GDALGetMetadata(out, nullptr); md && *md; ++md) {
    if (std::string(*md).find("NO-GO") != std::string::npos) legend = *md;
  }
  EXPECT_FALSE(legend.empty()) << "legend in the dataset metadata";
  std::vector<uint8_t> classes(GDALGetRasterXSize(out) * GDALGetRasterYSize(out));
  ASSERT_EQ(GDALRasterIO(band, GF_Read, 0, 0, GDALGetRasterXSize(out), GDALGetRasterYSize(out),
                         classes.data(), GDALGetRasterXSize(out), GDALGetRasterYSize(out), GDT_Byte,
                         0, 0),
            CE_None);
  for (uint8_t c : classes) ASSERT_TRUE(c <= 2 || c == 255) << int(c);
  GDALClose(out);
  GDALClose(in);
  VSIUnlink("/vsimem/out_gonogo.tif");
  VSIUnlink("/vsimem/in_ci.tif");

  // The same job again: every curve from the cache, identical classes.
  std::string second_id;
  const json second = RunSample(&second_id);
  EXPECT_EQ(second["tasks"]["total"], total);
  EXPECT_EQ(second["tasks"]["computed"], 0);
  EXPECT_EQ(second["tasks"]["cache_hits"], total);
  EXPECT_EQ(second["classes"], first["classes"]);
  EXPECT_EQ(DownloadAll(*stub, second_id)["gonogo.tif"].size(), files["gonogo.tif"].size());
}

TEST_F(ServiceTest, BadInputIsRejectedWithTheFieldAndHarmsNothing) {
  std::string good_id;
  RunSample(&good_id);
  const int64_t curves_before = CurveCount();
  auto stub = server_->Stub();
  auto job_count = [&] {
    grpc::ClientContext ctx;
    v1::ListJobsRequest req;
    req.set_limit(1000);
    v1::ListJobsResponse resp;
    stub->ListJobs(&ctx, req, &resp);
    return resp.jobs_size();
  };
  auto job_dirs = [&] {
    int n = 0;
    for (const auto& e : fs::directory_iterator(scratch_->path() / "data" / "jobs")) n += e.is_directory();
    return n;
  };
  const int jobs_before = job_count();
  const int dirs_before = job_dirs();

  TiffSpec spec;
  std::vector<float> firm(64, 800.0f);
  std::vector<float> flat(64, 2.0f);
  const std::string slope = MakeTiff(spec, flat);
  struct Case {
    std::string what;
    v1::MapRequest request;
    std::vector<std::pair<v1::RasterRole, std::string>> rasters;
    std::string field;
  };
  auto base = [&] {
    v1::MapRequest r;
    r.set_tier("empirical");
    *r.mutable_vehicle() = FedAlpha();
    return r;
  };
  std::vector<Case> cases;
  cases.push_back({"not a raster", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, "this is not a GeoTIFF"},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "cone_index"});
  cases.push_back({"empty raster", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, ""}, {v1::RASTER_ROLE_SLOPE, slope}},
                   "cone_index"});
  cases.push_back({"all nodata", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, std::vector<float>(64, -9999))},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "cone_index"});
  TiffSpec no_crs = spec;
  no_crs.epsg = 0;
  cases.push_back({"no CRS", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(no_crs, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "cone_index"});
  std::vector<float> negative = firm;
  negative[10] = -5;
  cases.push_back({"negative cone index", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, negative)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "cone_index"});
  TiffSpec far = spec;
  far.origin_x += 100000;
  cases.push_back({"no overlap", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, MakeTiff(far, flat)}},
                   "slope"});
  v1::MapRequest no_mass = base();
  no_mass.mutable_vehicle()->set_mass_kg(0);
  cases.push_back({"vehicle mass missing", no_mass,
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "vehicle.mass_kg"});
  v1::MapRequest no_vehicle = base();
  no_vehicle.clear_vehicle();
  cases.push_back({"vehicle missing", no_vehicle,
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "vehicle"});
  v1::MapRequest bad_tyre = base();
  bad_tyre.mutable_vehicle()->mutable_axles(1)->mutable_tyre()->set_width_m(-0.3);
  cases.push_back({"negative tyre width", bad_tyre,
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "vehicle.axles[1].tyre.width_m"});
  v1::MapRequest bad_tier = base();
  bad_tier.set_tier("fe-magic");
  cases.push_back({"unknown tier", bad_tier,
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope}},
                   "tier"});
  cases.push_back({"slope and elevation both missing", base(),
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)}}, "slope"});
  v1::MapRequest with_table = base();
  *with_table.mutable_soil_table() = SampleSoilTable(scratch_->path() / "terrain");
  cases.push_back({"soil class not in the table", with_table,
                   {{v1::RASTER_ROLE_CONE_INDEX, MakeTiff(spec, firm)},
                    {v1::RASTER_ROLE_SLOPE, slope},
                    {v1::RASTER_ROLE_SOIL_CLASS, MakeTiff(spec, std::vector<float>(64, 77))}},
                   "soil_class"});

  for (const Case& c : cases) {
    v1::Job job;
    const grpc::Status s = Submit(*stub, c.request, c.rasters, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.what << ": " << s.error_message();
    EXPECT_EQ(s.error_message().rfind(c.field + ":", 0), 0u)
        << c.what << ": message should start with the field: " << s.error_message();
  }

  // The service still serves, the earlier job is intact and no cached curve was touched.
  grpc::ClientContext ctx;
  v1::GetJobRequest req;
  req.set_job_id(good_id);
  v1::Job job;
  ASSERT_TRUE(stub->GetJob(&ctx, req, &job).ok());
  EXPECT_EQ(job.status().state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(CurveCount(), curves_before);
  EXPECT_EQ(job_count(), jobs_before) << "a rejected request leaves no job";
  EXPECT_EQ(job_dirs(), dirs_before) << "a rejected request leaves no files";
  EXPECT_EQ(NamesOf(DownloadAll(*stub, good_id)), MapProductNames());
}

TEST_F(ServiceTest, SizeLimitGivesResourceExhausted) {
  ScratchDir dir("limits");
  ServerProcess small(dir.path(), {"--max-cells", "1000"});
  auto stub = small.Stub();
  v1::Job job;
  const grpc::Status s = Submit(*stub, SampleRequest(), SampleRasters(), &job);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
  EXPECT_NE(s.error_message().find("cone_index"), std::string::npos) << s.error_message();
}

TEST_F(ServiceTest, CancelStopsARunningJob) {
  ScratchDir dir("cancel");
  ServerProcess slow(dir.path(), {"--task-delay-ms", "300", "--threads", "1"});
  auto stub = slow.Stub();
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
  // Wait until it is running, then cancel.
  for (int i = 0; i < 100; ++i) {
    grpc::ClientContext ctx;
    v1::GetJobRequest req;
    req.set_job_id(job.job_id());
    v1::Job now;
    stub->GetJob(&ctx, req, &now);
    if (now.status().state() == v1::JOB_STATE_RUNNING && now.status().tasks_total() > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  grpc::ClientContext ctx;
  v1::CancelJobRequest cancel;
  cancel.set_job_id(job.job_id());
  v1::Job after;
  ASSERT_TRUE(stub->CancelJob(&ctx, cancel, &after).ok());
  const auto start = std::chrono::steady_clock::now();
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  EXPECT_EQ(end.state(), v1::JOB_STATE_CANCELLED);
  EXPECT_LT(end.tasks_done(), end.tasks_total());
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5))
      << "cancellation reaches the running task instead of waiting for the queue";

  grpc::ClientContext again_ctx;
  v1::Job again;
  EXPECT_EQ(stub->CancelJob(&again_ctx, cancel, &again).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  grpc::ClientContext unknown_ctx;
  cancel.set_job_id("job-nope");
  EXPECT_EQ(stub->CancelJob(&unknown_ctx, cancel, &again).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(slow.Terminate(), 0) << "SIGTERM drains and exits cleanly";
}

// Two map jobs progress at once (--max-jobs 2, the default), sharing the pool.
TEST_F(ServiceTest, TwoMapJobsProgressAtOnce) {
  ScratchDir dir("two-jobs");
  ServerProcess slow(dir.path(), {"--task-delay-ms", "100", "--threads", "2"});
  auto stub = slow.Stub();
  v1::Job first, second;
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &first).ok());
  v1::MapRequest other = SampleRequest();
  other.mutable_criteria()->set_design_slip(0.25);  // same tasks; a separate job all the same
  other.set_disable_similarity(true);
  ASSERT_TRUE(Submit(*stub, other, SampleRasters(), &second).ok());
  bool both_progressed = false;
  for (int i = 0; i < 400 && !both_progressed; ++i) {
    int progressing = 0;
    for (const std::string& id : {first.job_id(), second.job_id()}) {
      grpc::ClientContext ctx;
      v1::GetJobRequest req;
      req.set_job_id(id);
      v1::Job now;
      ASSERT_TRUE(stub->GetJob(&ctx, req, &now).ok());
      if (now.status().state() == v1::JOB_STATE_RUNNING && now.status().tasks_done() > 0 &&
          now.status().tasks_done() < now.status().tasks_total()) {
        ++progressing;
      }
    }
    both_progressed = progressing == 2;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  EXPECT_TRUE(both_progressed) << "both jobs were part-way through at the same moment";
  EXPECT_EQ(WaitForEnd(*stub, first.job_id()).state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(WaitForEnd(*stub, second.job_id()).state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(slow.Terminate(), 0);
}

// A tier that takes minutes is never computed inside GetTractionCurve: the query becomes a job
// with the solver's progress, cancellation and the curve as its products.
TEST_F(ServiceTest, ALongCurveIsAJobWithProgressCancellationAndItsCurve) {
  ScratchDir dir("curve-job");
  ServerProcess server(dir.path(), {"--diagnostic-tiers"});
  auto stub = server.Stub();
  v1::GetTractionCurveRequest req;
  req.set_tier("diagnostic-slow-curve");
  *req.mutable_tyre() = FedAlpha().axles(0).tyre();
  req.set_wheel_load_n(13438);
  req.mutable_soil()->set_cone_index_pa(300e3);
  {
    grpc::ClientContext ctx;
    v1::TractionCurve curve;
    const grpc::Status s = stub->GetTractionCurve(&ctx, req, &curve);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(s.error_message().find("SubmitCurve"), std::string::npos) << s.error_message();
  }
  v1::Job job;
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->SubmitCurve(&ctx, req, &job).ok());
  }
  EXPECT_EQ(job.kind(), "curve");
  // Watch: the solver's progress shows part-way, then DONE.
  bool saw_progress = false;
  v1::JobStatus last;
  {
    grpc::ClientContext ctx;
    v1::WatchJobRequest watch;
    watch.set_job_id(job.job_id());
    auto reader = stub->WatchJob(&ctx, watch);
    while (reader->Read(&last)) {
      if (last.fraction_done() > 0.05 && last.fraction_done() < 0.95 &&
          last.message().rfind("computing the traction curve", 0) == 0) {
        saw_progress = true;
      }
    }
  }
  ASSERT_EQ(last.state(), v1::JOB_STATE_DONE) << last.message();
  EXPECT_TRUE(saw_progress) << "the solver's progress reached the watcher";
  v1::Job done;
  {
    grpc::ClientContext ctx;
    v1::GetJobRequest get;
    get.set_job_id(job.job_id());
    ASSERT_TRUE(stub->GetJob(&ctx, get, &done).ok());
  }
  const json curve = json::parse(done.summary_json());
  EXPECT_EQ(curve["points"].size(), 21u);
  EXPECT_EQ(curve["provenance"]["tier"], "diagnostic-slow-curve");
  const auto products = DownloadAll(*stub, job.job_id());
  ASSERT_EQ(products.count("curve.csv"), 1u);
  EXPECT_EQ(products.at("curve.csv").rfind("slip,drawbar_pull_n,torque_nm,", 0), 0u);
  EXPECT_EQ(std::count(products.at("curve.csv").begin(), products.at("curve.csv").end(), '\n'),
            22);

  // Now cached: the RPC answers it, and a second job is done from the cache.
  {
    grpc::ClientContext ctx;
    v1::TractionCurve cached;
    ASSERT_TRUE(stub->GetTractionCurve(&ctx, req, &cached).ok());
    EXPECT_TRUE(cached.provenance().cache_hit());
  }
  {
    grpc::ClientContext ctx;
    v1::Job again;
    ASSERT_TRUE(stub->SubmitCurve(&ctx, req, &again).ok());
    const v1::JobStatus end = WaitForEnd(*stub, again.job_id());
    EXPECT_EQ(end.state(), v1::JOB_STATE_DONE);
    EXPECT_EQ(end.cache_hits(), 1u);
  }

  // Cancelled while the solver runs.
  req.set_wheel_load_n(9000);
  req.set_disable_similarity(true);
  v1::Job slow;
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->SubmitCurve(&ctx, req, &slow).ok());
  }
  for (int i = 0; i < 100; ++i) {
    grpc::ClientContext ctx;
    v1::GetJobRequest get;
    get.set_job_id(slow.job_id());
    v1::Job now;
    stub->GetJob(&ctx, get, &now);
    if (now.status().fraction_done() > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  {
    grpc::ClientContext ctx;
    v1::CancelJobRequest cancel;
    cancel.set_job_id(slow.job_id());
    v1::Job after;
    ASSERT_TRUE(stub->CancelJob(&ctx, cancel, &after).ok());
  }
  EXPECT_EQ(WaitForEnd(*stub, slow.job_id()).state(), v1::JOB_STATE_CANCELLED);

  // Bad input is refused before a job exists.
  req.set_wheel_load_n(-1);
  {
    grpc::ClientContext ctx;
    v1::Job bad;
    const grpc::Status s = stub->SubmitCurve(&ctx, req, &bad);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(s.error_message().rfind("wheel_load_n:", 0), 0u) << s.error_message();
  }
  {
    grpc::ClientContext ctx;
    v1::ListJobsRequest list;
    v1::ListJobsResponse jobs;
    ASSERT_TRUE(stub->ListJobs(&ctx, list, &jobs).ok());
    EXPECT_EQ(jobs.jobs_size(), 3);
  }
  EXPECT_EQ(server.Terminate(), 0);
}

// The server's own options: a mistyped one is an error naming it, not silently ignored; the log
// level is honoured and logs go to stderr, never mixed into the banner on stdout.
TEST_F(ServiceTest, ServerOptionsAreCheckedAndLogsGoToStderr) {
  auto run = [](const std::string& args) {
    const std::string cmd = BinaryDir() + "/server/gonogo-server " + args + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
    const int status = pclose(p);
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, out);
  };
  const auto [typo_rc, typo] = run("--max-jobz 3");
  EXPECT_NE(typo_rc, 0);
  EXPECT_NE(typo.find("--max-jobz"), std::string::npos) << typo;
  const auto [range_rc, range] = run("--log-level loud");
  EXPECT_NE(range_rc, 0);
  EXPECT_NE(range.find("--log-level"), std::string::npos) << range;
  const auto [help_rc, help] = run("--help");
  EXPECT_EQ(help_rc, 0);
  EXPECT_NE(help.find("--diagnostic-tiers"), std::string::npos) << help;

  ScratchDir dir("log-level");
  ServerProcess debug(dir.path(), {"--log-level", "debug"});
  auto stub = debug.Stub();
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, SampleRequest(), SampleRasters(), &job).ok());
  EXPECT_EQ(WaitForEnd(*stub, job.job_id()).state(), v1::JOB_STATE_DONE);
  EXPECT_EQ(debug.Terminate(), 0);
  EXPECT_EQ(debug.banner().find("[info]"), std::string::npos) << "the banner line is clean";
}

TEST_F(ServiceTest, TractionCurveIsComputedOnceThenServedFromTheCache) {
  auto stub = server_->Stub();
  v1::GetTractionCurveRequest req;
  req.set_tier("empirical");
  *req.mutable_tyre() = FedAlpha().axles(0).tyre();
  req.set_wheel_load_n(9876.5);  // no map in this suite uses this wheel load
  req.mutable_soil()->set_cone_index_pa(412345);
  v1::TractionCurve first, second;
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->GetTractionCurve(&ctx, req, &first).ok());
  }
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->GetTractionCurve(&ctx, req, &second).ok());
  }
  EXPECT_FALSE(first.provenance().cache_hit());
  EXPECT_TRUE(second.provenance().cache_hit());
  EXPECT_EQ(first.provenance().cache_key(), second.provenance().cache_key());
  ASSERT_EQ(first.points_size(), 21);
  EXPECT_DOUBLE_EQ(first.points(10).drawbar_pull_n(), second.points(10).drawbar_pull_n());
  EXPECT_NEAR(first.soil().cone_index_pa(), 412345, 0.005 * 412345) << "snapped to a 1 % bin";
  EXPECT_EQ(first.provenance().tier_version(), "empirical-1");

  req.mutable_soil()->set_cone_index_pa(NAN);
  grpc::ClientContext bad_ctx;
  v1::TractionCurve bad;
  const grpc::Status s = stub->GetTractionCurve(&bad_ctx, req, &bad);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message().rfind("soil.cone_index_pa:", 0), 0u) << s.error_message();

  // Paging walks every curve exactly once.
  std::set<std::string> keys;
  std::string token;
  int pages = 0;
  do {
    grpc::ClientContext ctx;
    v1::ListTractionCurvesRequest list;
    list.set_tier("empirical");
    list.set_page_size(7);
    list.set_page_token(token);
    v1::ListTractionCurvesResponse resp;
    ASSERT_TRUE(stub->ListTractionCurves(&ctx, list, &resp).ok());
    for (const auto& c : resp.curves()) EXPECT_TRUE(keys.insert(c.provenance().cache_key()).second);
    token = resp.next_page_token();
    ++pages;
  } while (!token.empty());
  EXPECT_EQ(static_cast<int64_t>(keys.size()), CurveCount());
  EXPECT_GE(pages, 1);
}

TEST_F(ServiceTest, SimilarTyreIsAnsweredFromTheCacheUnlessDisabled) {
  auto stub = server_->Stub();
  // Seed 001 Tables 4 and 6: the FED Alpha tyre and its scale models, loads by equal W/(b d),
  // on a soil no other test here uses (cone index 149 kPa, the 2NS sand).
  auto request = [](double k, bool disable) {
    v1::GetTractionCurveRequest req;
    req.set_tier("empirical");
    v1::Tyre* t = req.mutable_tyre();
    t->set_diameter_m(1.011 * k);
    t->set_width_m(0.335 * k);
    t->set_section_height_m(0.2178 * k);
    t->set_deflection_m(0.0327 * k);
    req.set_wheel_load_n(13438 * k * k);
    req.mutable_soil()->set_cone_index_pa(149e3);
    req.set_disable_similarity(disable);
    return req;
  };
  auto get = [&](const v1::GetTractionCurveRequest& req) {
    grpc::ClientContext ctx;
    v1::TractionCurve c;
    const grpc::Status s = stub->GetTractionCurve(&ctx, req, &c);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return c;
  };
  const v1::TractionCurve full = get(request(1.0, false));
  EXPECT_FALSE(full.provenance().cache_hit());
  const v1::TractionCurve similar = get(request(0.7, false));
  EXPECT_TRUE(similar.provenance().cache_hit());
  EXPECT_TRUE(similar.provenance().similarity_hit());
  EXPECT_NEAR(similar.provenance().similarity_scale_ratio(), 0.7, 1e-3);
  EXPECT_EQ(similar.provenance().cache_key(), full.provenance().cache_key()) << "names the source";
  EXPECT_EQ(similar.provenance().reliability().reference_soil(), "2NS");
  EXPECT_DOUBLE_EQ(similar.provenance().reliability().gross_traction_pct(), 97.1);
  EXPECT_NEAR(similar.tyre().diameter_m(), 0.7077, 1e-4) << "answered for the requested tyre";
  // Both carry the dimensionless form; for similar tyres it is the same curve.
  ASSERT_EQ(similar.dimensionless_size(), full.dimensionless_size());
  for (int i = 0; i < full.dimensionless_size(); ++i) {
    EXPECT_NEAR(similar.dimensionless(i).drawbar_pull_coefficient(),
                full.dimensionless(i).drawbar_pull_coefficient(), 1e-12);
    EXPECT_NEAR(full.dimensionless(i).drawbar_pull_coefficient(),
                full.points(i).drawbar_pull_n() / full.wheel_load_n(), 1e-12);
  }
  EXPECT_NEAR(similar.pi_terms().load_over_bd_pa(), full.pi_terms().load_over_bd_pa(),
              0.01 * full.pi_terms().load_over_bd_pa());

  // The same tyre with similarity off is computed, and for this tier it must agree (the empirical
  // tier depends on the pi-terms only; the residue is the key's quantisation of lengths and load).
  const v1::TractionCurve direct = get(request(0.7, true));
  EXPECT_FALSE(direct.provenance().cache_hit());
  EXPECT_FALSE(direct.provenance().similarity_hit());
  ASSERT_EQ(direct.points_size(), similar.points_size());
  for (int i = 0; i < direct.points_size(); ++i) {
    EXPECT_NEAR(similar.points(i).drawbar_pull_n(), direct.points(i).drawbar_pull_n(),
                2e-3 * 13438 * 0.49)
        << "slip " << direct.points(i).slip();
    EXPECT_NEAR(similar.points(i).tractive_efficiency(), direct.points(i).tractive_efficiency(),
                2e-3);
  }
  // A quarter-scale tyre is below the smallest ratio served from similarity (0.5).
  EXPECT_FALSE(get(request(0.25, false)).provenance().similarity_hit());
}

TEST_F(ServiceTest, ScalabilityStudyOfTheEmpiricalTierIsExactlySimilar) {
  auto stub = server_->Stub();
  v1::ScalabilityRequest req;
  req.set_tier("empirical");
  *req.mutable_tyre() = FedAlpha().axles(0).tyre();
  req.set_wheel_load_n(13438);
  req.mutable_soil()->set_cone_index_pa(1e6);
  for (double k : {1.0, 0.7, 0.5, 0.25}) req.add_scales(k);
  v1::ScalabilityReport report;
  {
    grpc::ClientContext ctx;
    const grpc::Status s = stub->RunScalability(&ctx, req, &report);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }
  ASSERT_EQ(report.rows_size(), 4);
  EXPECT_GT(report.band_drawbar_pull(), 0);
  // Brixius depends on the pi-terms only: every scaled point lies on the full-scale curve.
  for (const auto& row : report.rows()) {
    EXPECT_DOUBLE_EQ(row.drawbar_pull_inside_pct(), 100) << row.scale();
    EXPECT_DOUBLE_EQ(row.efficiency_inside_pct(), 100) << row.scale();
    EXPECT_FALSE(row.provenance().similarity_hit()) << "every scale is computed";
  }
  EXPECT_NEAR(report.rows(2).wheel_load_n(), 13438 * 0.25, 1.0) << "equal W/(b d)";
  EXPECT_NEAR(report.rows(3).tyre().diameter_m(), 1.011 * 0.25, 1e-4);
  EXPECT_EQ(report.rows(1).seed_measured().reference_soil(), "2NS");
  EXPECT_DOUBLE_EQ(report.rows(1).seed_measured().gross_traction_pct(), 97.1);
  EXPECT_DOUBLE_EQ(report.rows(3).seed_measured().drawbar_pull_pct(), 75.6);
  ASSERT_GT(report.plot_png().size(), 8u);
  EXPECT_EQ(report.plot_png().substr(1, 3), "PNG");

  req.set_scales(0, 0.9);
  grpc::ClientContext bad_ctx;
  const grpc::Status bad = stub->RunScalability(&bad_ctx, req, &report);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad.error_message().rfind("scales:", 0), 0u) << bad.error_message();
}

TEST_F(ServiceTest, BekkerTierMapsSoilClassesAndExplainsWhatItCannotDo) {
  auto stub = server_->Stub();
  v1::MapRequest request = SampleRequest();
  request.set_tier("bekker");
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, request, SampleRasters(), &job).ok());
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  ASSERT_EQ(end.state(), v1::JOB_STATE_DONE) << end.message();
  // The bekker tier reads the soil, not the cone index: one curve per soil class and axle.
  EXPECT_EQ(end.tasks_total(), 3u * 2u);

  // Cone-index-only terrain stays on the empirical tier.
  v1::Job rejected;
  grpc::Status s = Submit(*stub, request,
                          {{v1::RASTER_ROLE_CONE_INDEX, Terrain("cone_index.tif")},
                           {v1::RASTER_ROLE_SLOPE, Terrain("slope.tif")}},
                          &rejected);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message().rfind("soil_class:", 0), 0u) << s.error_message();
  // A class naming no library soil.
  v1::MapRequest unknown = request;
  unknown.mutable_soil_table()->mutable_classes(1)->set_bekker_soil("moon dust");
  s = Submit(*stub, unknown, SampleRasters(), &rejected);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("soil_table.classes[code 2]"), std::string::npos)
      << s.error_message();
  // Non-physical explicit parameters.
  v1::MapRequest bad = request;
  v1::BekkerParameters* p = bad.mutable_soil_table()->mutable_classes(0)->mutable_bekker();
  p->set_n(0.7);
  p->set_kc(5270);
  p->set_kphi(1515040);
  p->set_cohesion_pa(1720);
  p->set_friction_angle_deg(95);
  p->set_shear_deformation_m(0.025);
  s = Submit(*stub, bad, SampleRasters(), &rejected);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("friction_angle_deg"), std::string::npos) << s.error_message();

  // A soil that cannot carry the wheel: its cells are NO-GO with the reason, never NaN.
  v1::MapRequest snow = request;
  for (auto& c : *snow.mutable_soil_table()->mutable_classes()) c.set_bekker_soil("snow_us");
  ASSERT_TRUE(Submit(*stub, snow, SampleRasters(), &job).ok());
  ASSERT_EQ(WaitForEnd(*stub, job.job_id()).state(), v1::JOB_STATE_DONE);
  grpc::ClientContext ctx;
  v1::GetJobRequest get;
  get.set_job_id(job.job_id());
  v1::Job done;
  ASSERT_TRUE(stub->GetJob(&ctx, get, &done).ok());
  const json summary = json::parse(done.summary_json());
  EXPECT_EQ(summary["classes"]["NO-GO"]["cells"], summary["cells"]["valid"]);
  EXPECT_EQ(summary["no_go_cells_by_reason"]["soil_cannot_carry_the_wheel"],
            summary["cells"]["valid"]);
  EXPECT_NE(summary["no_go_cells_by_reason"]["soil_cannot_carry_example"].get<std::string>().find(
                "sink past its axle"),
            std::string::npos);

  // A single wheel the soil cannot carry: a clear error, not a curve.
  v1::GetTractionCurveRequest curve_req;
  curve_req.set_tier("bekker");
  *curve_req.mutable_tyre() = FedAlpha().axles(0).tyre();
  curve_req.mutable_tyre()->set_inflation_pressure_pa(0);  // rigid
  curve_req.set_wheel_load_n(14513);
  curve_req.mutable_soil()->set_soil_name("snow_us");
  v1::TractionCurve curve;
  grpc::ClientContext c1;
  s = stub->GetTractionCurve(&c1, curve_req, &curve);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(s.error_message().rfind("wheel_load_n: the soil cannot carry", 0), 0u)
      << s.error_message();
  // Explicit parameters (LETE sand, Wong's Table 2.3) work without a library name.
  curve_req.mutable_soil()->clear_soil_name();
  v1::BekkerParameters* lete = curve_req.mutable_soil()->mutable_bekker();
  lete->set_n(0.79);
  lete->set_kc(102000);
  lete->set_kphi(5301000);
  lete->set_cohesion_pa(1300);
  lete->set_friction_angle_deg(31.1);
  lete->set_shear_deformation_m(0.0115);
  grpc::ClientContext c2;
  s = stub->GetTractionCurve(&c2, curve_req, &curve);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_GT(curve.points(8).drawbar_pull_n(), 0) << "LETE sand pulls at 40 % slip";
  for (const auto& pt : curve.points()) EXPECT_TRUE(std::isfinite(pt.drawbar_pull_n()));

  // The scaled-tyre study on loose dry sand: the quarter-scale wheel sinks past its axle and is
  // reported as such; the others are compared.
  v1::ScalabilityRequest study;
  study.set_tier("bekker");
  study.mutable_soil()->set_soil_name("lll_dry_sand");
  *study.mutable_tyre() = FedAlpha().axles(0).tyre();
  study.set_wheel_load_n(14513);
  for (double k : {1.0, 0.5, 0.25}) study.add_scales(k);
  v1::ScalabilityReport report;
  grpc::ClientContext c3;
  s = stub->RunScalability(&c3, study, &report);
  ASSERT_TRUE(s.ok()) << s.error_message();
  ASSERT_EQ(report.rows_size(), 3);
  EXPECT_TRUE(report.rows(1).immobile_reason().empty());
  EXPECT_LT(report.rows(1).drawbar_pull_inside_pct(), 100) << "Bekker is not scale-free";
  EXPECT_NE(report.rows(2).immobile_reason().find("sink past its axle"), std::string::npos);
  EXPECT_EQ(report.rows(2).points_size(), 0);
}

}  // namespace
}  // namespace gonogo::testing
