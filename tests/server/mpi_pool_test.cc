// The MPI worker pool for real: `mpirun -np 3 gonogo-server` (rank 0 serving, ranks 1 and 2
// computing), a map job whose summary shows both worker ranks at work, a curve query answered by a
// worker rank, bad input refused while the pool keeps serving, and a clean SIGTERM shutdown.
#include <gtest/gtest.h>

#include <dirent.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "server_process.h"

namespace gonogo::testing {
namespace {

// CPU time (user + system, seconds) of every process whose command line names gonogo-server and
// whose data directory is `data_dir`: the ranks of this test's MPI job.
std::map<int, double> RankCpuSeconds(const fs::path& data_dir) {
  std::map<int, double> out;
  DIR* proc = opendir("/proc");
  while (dirent* e = readdir(proc)) {
    const int pid = std::atoi(e->d_name);
    if (pid <= 0) continue;
    std::string cmdline = ReadFile(fs::path("/proc") / e->d_name / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.rfind("mpirun", 0) == 0) continue;
    if (cmdline.find("gonogo-server") == std::string::npos ||
        cmdline.find(data_dir.string()) == std::string::npos) {
      continue;
    }
    // /proc/PID/stat: fields 14 and 15 are utime and stime in clock ticks.
    std::string stat = ReadFile(fs::path("/proc") / e->d_name / "stat");
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    std::string f;
    double ticks = 0;
    for (int i = 3; i <= 15 && fields >> f; ++i) {
      if (i >= 14) ticks += std::stod(f);
    }
    out[pid] = ticks / sysconf(_SC_CLK_TCK);
  }
  closedir(proc);
  return out;
}

TEST(MpiPool, TwoWorkerRanksComputeAMapAndShutDownCleanly) {
  ScratchDir dir("mpi");
  ASSERT_TRUE(MakeSampleTerrain(dir.path() / "terrain", 48));
  ServerProcess server(dir.path() / "data", {"--task-delay-ms", "2"}, 3);
  EXPECT_NE(server.banner().find("MPI pool of 2 worker ranks"), std::string::npos)
      << server.banner();
  auto stub = server.Stub();

  v1::MapRequest request;
  request.set_tier("empirical");
  *request.mutable_vehicle() = FedAlpha();
  *request.mutable_soil_table() = SampleSoilTable(dir.path() / "terrain");
  v1::Job job;
  ASSERT_TRUE(Submit(*stub, request,
                     {{v1::RASTER_ROLE_CONE_INDEX, ReadFile(dir.path() / "terrain/cone_index.tif")},
                      {v1::RASTER_ROLE_ELEVATION, ReadFile(dir.path() / "terrain/elevation.tif")},
                      {v1::RASTER_ROLE_SOIL_CLASS,
                       ReadFile(dir.path() / "terrain/soil_class.tif")}},
                     &job)
                  .ok());
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  ASSERT_EQ(end.state(), v1::JOB_STATE_DONE) << end.message();

  grpc::ClientContext ctx;
  v1::GetJobRequest req;
  req.set_job_id(job.job_id());
  v1::Job done;
  ASSERT_TRUE(stub->GetJob(&ctx, req, &done).ok());
  const auto summary = nlohmann::json::parse(done.summary_json());
  const auto& by = summary["tasks"]["computed_by"];
  EXPECT_TRUE(by.contains("rank 1")) << by.dump();
  EXPECT_TRUE(by.contains("rank 2")) << by.dump();
  EXPECT_FALSE(by.contains("rank 0")) << "rank 0 serves and schedules only";
  EXPECT_EQ(by.value("rank 1", 0) + by.value("rank 2", 0), summary["tasks"]["computed"].get<int>());

  // A curve query goes to a worker rank; bad input comes back as an error, the worker survives.
  v1::GetTractionCurveRequest curve_req;
  curve_req.set_tier("empirical");
  *curve_req.mutable_tyre() = FedAlpha().axles(0).tyre();
  curve_req.set_wheel_load_n(9000);
  curve_req.mutable_soil()->set_cone_index_pa(1.5e6);
  v1::TractionCurve curve;
  {
    grpc::ClientContext c;
    ASSERT_TRUE(stub->GetTractionCurve(&c, curve_req, &curve).ok());
  }
  EXPECT_EQ(curve.provenance().computed_by().rfind("rank ", 0), 0u)
      << curve.provenance().computed_by();
  {
    grpc::ClientContext c;
    curve_req.set_wheel_load_n(-1);
    EXPECT_EQ(stub->GetTractionCurve(&c, curve_req, &curve).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  {
    grpc::ClientContext c;
    curve_req.set_wheel_load_n(9100);
    EXPECT_TRUE(stub->GetTractionCurve(&c, curve_req, &curve).ok()) << "workers still serve";
  }

  // Idle ranks sleep between polls instead of spinning in a blocking receive.
  const auto before = RankCpuSeconds(dir.path() / "data");
  EXPECT_EQ(before.size(), 3u) << "rank 0 and two workers";
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const auto after = RankCpuSeconds(dir.path() / "data");
  for (const auto& [pid, cpu] : after) {
    EXPECT_LT(cpu - before.at(pid), 0.2) << "rank process " << pid << " used CPU while idle";
  }
  EXPECT_EQ(server.Terminate(), 0);
}

// Issue "open seams", pool: a task that needs 2 ranks runs collectively on a sub-communicator of
// two workers while one-rank tasks complete on the third; errors reach the client typed.
TEST(MpiPool, ARankGroupRunsOnItsSubCommunicatorWhileOneRankTasksFlow) {
  ScratchDir dir("mpi-group");
  ServerProcess server(dir.path() / "data", {"--diagnostic-tiers"}, 4);
  ASSERT_NE(server.banner().find("MPI pool of 3 worker ranks"), std::string::npos)
      << server.banner();
  auto stub = server.Stub();
  auto curve_request = [](const std::string& tier, double load_n) {
    v1::GetTractionCurveRequest r;
    r.set_tier(tier);
    *r.mutable_tyre() = FedAlpha().axles(0).tyre();
    r.set_wheel_load_n(load_n);
    r.mutable_soil()->set_cone_index_pa(1.5e6);
    r.set_disable_similarity(true);  // every query is computed
    return r;
  };

  grpc::Status group_status;
  v1::TractionCurve group_curve;
  std::atomic<bool> group_done{false};
  std::thread group([&] {
    grpc::ClientContext c;
    group_status = stub->GetTractionCurve(&c, curve_request("diagnostic-rank-group", 9000),
                                          &group_curve);
    group_done = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(400));  // the group is at work
  for (int i = 0; i < 4; ++i) {
    grpc::ClientContext c;
    v1::TractionCurve curve;
    const grpc::Status s = stub->GetTractionCurve(&c, curve_request("empirical", 9500 + 500 * i), &curve);
    ASSERT_TRUE(s.ok()) << s.error_message();
    EXPECT_EQ(curve.provenance().computed_by(), "rank 3") << "ranks 1 and 2 hold the group";
    EXPECT_FALSE(curve.provenance().cache_hit());
  }
  EXPECT_FALSE(group_done) << "the one-rank tasks did not wait behind the group";
  group.join();
  ASSERT_TRUE(group_status.ok()) << group_status.error_message();
  EXPECT_EQ(group_curve.provenance().computed_by(), "ranks 1,2");
  EXPECT_EQ(group_curve.provenance().tier(), "diagnostic-rank-group");
  ASSERT_EQ(group_curve.points_size(), 21);
  EXPECT_GT(group_curve.points(10).drawbar_pull_n(), 0);

  // A numerical failure is not the client's fault: FAILED_PRECONDITION with the solver's reason.
  {
    grpc::ClientContext c;
    v1::TractionCurve curve;
    const grpc::Status s =
        stub->GetTractionCurve(&c, curve_request("diagnostic-numerical-failure", 9000), &curve);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << s.error_message();
    EXPECT_NE(s.error_message().find("did not converge"), std::string::npos) << s.error_message();
  }
  // Bad input stays INVALID_ARGUMENT, and the pool keeps serving after both.
  {
    grpc::ClientContext c;
    v1::TractionCurve curve;
    EXPECT_EQ(stub->GetTractionCurve(&c, curve_request("empirical", -1), &curve).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  {
    grpc::ClientContext c;
    v1::TractionCurve curve;
    EXPECT_TRUE(stub->GetTractionCurve(&c, curve_request("diagnostic-rank-group", 9300), &curve)
                    .ok());
    EXPECT_EQ(curve.provenance().computed_by(), "ranks 1,2");
  }
  EXPECT_EQ(server.Terminate(), 0);
}

}  // namespace
}  // namespace gonogo::testing
