// The MPI worker pool for real: `mpirun -np 3 gonogo-server` (rank 0 serving, ranks 1 and 2
// computing), a map job whose summary shows both worker ranks at work, a curve query answered by a
// worker rank, bad input refused while the pool keeps serving, and a clean SIGTERM shutdown.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "server_process.h"

namespace gonogo::testing {
namespace {

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
  EXPECT_EQ(server.Terminate(), 0);
}

}  // namespace
}  // namespace gonogo::testing
