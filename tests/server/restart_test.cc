// A crash during a job: the server is killed (SIGKILL) part-way, started again on the same data
// directory, resumes the job to DONE, and recomputes none of the curves finished before the crash.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "server_process.h"

namespace gonogo::testing {
namespace {


TEST(Restart, KilledJobResumesAndRecomputesNoFinishedCurve) {
  ScratchDir dir("restart");
  ASSERT_TRUE(MakeSampleTerrain(dir.path() / "terrain", 48));
  const fs::path data = dir.path() / "data";
  v1::MapRequest request;
  request.set_name("crash");
  request.set_tier("empirical");
  *request.mutable_vehicle() = FedAlpha();
  *request.mutable_soil_table() = SampleSoilTable(dir.path() / "terrain");
  const std::vector<std::pair<v1::RasterRole, std::string>> rasters = {
      {v1::RASTER_ROLE_CONE_INDEX, ReadFile(dir.path() / "terrain/cone_index.tif")},
      {v1::RASTER_ROLE_SLOPE, ReadFile(dir.path() / "terrain/slope.tif")},
      {v1::RASTER_ROLE_SOIL_CLASS, ReadFile(dir.path() / "terrain/soil_class.tif")}};

  std::string job_id;
  uint32_t total = 0;
  {
    ServerProcess slow(data, {"--task-delay-ms", "40", "--threads", "1"});
    auto stub = slow.Stub();
    v1::Job job;
    ASSERT_TRUE(Submit(*stub, request, rasters, &job).ok());
    job_id = job.job_id();
    // Kill once a good share of the curves, but not all, are done.
    for (int i = 0; i < 600; ++i) {
      grpc::ClientContext ctx;
      v1::GetJobRequest req;
      req.set_job_id(job_id);
      v1::Job now;
      stub->GetJob(&ctx, req, &now);
      total = now.status().tasks_total();
      if (total > 0 && now.status().tasks_done() >= std::min<uint32_t>(20, total / 3)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    slow.Kill();
  }
  ASSERT_GT(total, 20u) << "the sample needs enough tasks for a mid-job kill";
  const auto before = StoredCurves(data);
  ASSERT_GE(before.size(), 20u);
  ASSERT_LT(before.size(), total) << "the kill must land mid-job";

  ServerProcess again(data);
  EXPECT_NE(again.banner().find("1 jobs resumed"), std::string::npos) << again.banner();
  auto stub = again.Stub();
  const v1::JobStatus end = WaitForEnd(*stub, job_id);
  ASSERT_EQ(end.state(), v1::JOB_STATE_DONE) << end.message();
  EXPECT_EQ(end.tasks_total(), total);
  EXPECT_EQ(end.cache_hits(), before.size());

  grpc::ClientContext ctx;
  v1::GetJobRequest req;
  req.set_job_id(job_id);
  v1::Job done;
  ASSERT_TRUE(stub->GetJob(&ctx, req, &done).ok());
  const auto summary = nlohmann::json::parse(done.summary_json());
  EXPECT_EQ(summary["tasks"]["computed"].get<size_t>(), total - before.size());
  EXPECT_EQ(summary["tasks"]["cache_hits"].get<size_t>(), before.size());

  // Every curve committed before the crash is still the same row.
  const auto after = StoredCurves(data);
  EXPECT_EQ(after.size(), total);
  for (const auto& [key, computed_ms] : before) {
    ASSERT_TRUE(after.count(key));
    EXPECT_EQ(after.at(key), computed_ms) << key;
  }
  EXPECT_EQ(NamesOf(DownloadAll(*stub, job_id)), MapProductNames());
  EXPECT_EQ(again.Terminate(), 0);
  EXPECT_EQ(IntegrityCheck(data), "ok");
}

}  // namespace
}  // namespace gonogo::testing
