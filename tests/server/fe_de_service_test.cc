// The fe-de tier through the whole service: `mpirun -np 3 gonogo-server --fe-de-preset ci
// --ranks-per-task 2` (rank 0 serving, ranks 1 and 2 one rank group), driven by the `gonogo`
// command line. A curve job runs on the group and reports progress; the same request again comes
// from the cache; a cancelled job stops the whole group within seconds and frees its ranks for
// the next task.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <regex>
#include <sstream>
#include <thread>

#include "server_process.h"

namespace gonogo::testing {
namespace {

int CsvRows(const std::string& out) {
  int rows = 0;
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && (line[0] == '0' || line[0] == '1') && line.find(',') != std::string::npos) {
      ++rows;
    }
  }
  return rows;
}

// The CSV of the first test's uninterrupted curve, for the resume test.
std::string* uninterrupted_csv = nullptr;

std::string CsvPart(const std::string& out) {
  const std::size_t header = out.find("slip,drawbar_pull_n");
  return header == std::string::npos ? std::string() : out.substr(header);
}

const char kWheel[] =
    "curve --tier fe-de --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2 "
    "--section-height 0.1 --wheel-load 1000 --slip-step 0.25";

TEST(FeDeService, CurveJobOnARankGroupThenFromTheCacheAndCancelFreesTheGroup) {
  ScratchDir dir("fe-de-service");
  ServerProcess server(dir.path(), {"--fe-de-preset", "ci", "--ranks-per-task", "2"}, 3);

  const CliRun tiers = Gonogo(server.endpoint(), "tiers");
  ASSERT_EQ(tiers.exit_code, 0) << tiers.out;
  EXPECT_NE(tiers.out.find("fe-de (fe-de-1-ci)"), std::string::npos) << tiers.out;

  const auto start = std::chrono::steady_clock::now();
  const CliRun first = Gonogo(server.endpoint(), std::string(kWheel) + " --csv");
  const double first_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(first.exit_code, 0) << first.out;
  EXPECT_NE(first.out.find("curve job job-"), std::string::npos) << first.out;
  EXPECT_EQ(CsvRows(first.out), 5) << first.out;
  uninterrupted_csv = new std::string(CsvPart(first.out));
  std::printf("  fe-de ci curve through the service: %.1f s\n", first_s);

  const CliRun again = Gonogo(server.endpoint(), kWheel);
  ASSERT_EQ(again.exit_code, 0) << again.out;
  EXPECT_NE(again.out.find("from the cache"), std::string::npos) << again.out;

  // A map on fe-de: every soil class on the DE soil, a one-axle vehicle whose wheels carry the
  // curve's 1000 N on the same tyre, so the map's one fe-de curve is the one just computed.
  ASSERT_TRUE(MakeSampleTerrain(dir.path() / "terrain", 8));
  const fs::path terrain = dir.path() / "terrain";
  WriteDeSoilTableAndRigWheels(terrain);
  const std::string out = (dir.path() / "map").string();
  const CliRun map = Gonogo(
      server.endpoint(),
      "map --cone-index " + (terrain / "cone_index.tif").string() + " --elevation " +
          (terrain / "elevation.tif").string() + " --soil-class " +
          (terrain / "soil_class.tif").string() + " --soil-table " +
          (terrain / "de_soils.json").string() + " --vehicle " +
          (terrain / "small_wheels.json").string() +
          " --tier fe-de --slip-step 0.25 --out " + out);
  ASSERT_EQ(map.exit_code, 0) << map.out;
  for (const char* product : {"gonogo.tif", "speed.tif", "summary.json"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / product)) << product;
  }
  const std::string summary = ReadFile(fs::path(out) / "summary.json");
  EXPECT_NE(summary.find("fe-de"), std::string::npos) << summary;
  EXPECT_NE(map.out.find("tasks 1/1  cache hits 1"), std::string::npos)
      << "one distinct soil and wheel: the curve above, from the cache: " << map.out;

  // Another wheel load: a new curve. Cancel it once it is under way.
  const std::string heavier =
      "curve --tier fe-de --soil seed000_sand_rve100 --wheel-diameter 0.5 --wheel-width 0.2 "
      "--section-height 0.1 --wheel-load 1500 --slip-step 0.25 --no-wait";
  const CliRun submitted = Gonogo(server.endpoint(), heavier);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out;
  std::smatch match;
  const std::regex job_id("job-[0-9a-f-]+");
  ASSERT_TRUE(std::regex_search(submitted.out, match, job_id)) << submitted.out;
  const std::string id = match.str();
  std::this_thread::sleep_for(std::chrono::seconds(15));  // the group is stepping the FE by now
  const auto cancel_start = std::chrono::steady_clock::now();
  const CliRun cancel = Gonogo(server.endpoint(), "cancel " + id);
  ASSERT_EQ(cancel.exit_code, 0) << cancel.out;
  const CliRun watched = Gonogo(server.endpoint(), "watch " + id);
  const double cancel_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - cancel_start).count();
  EXPECT_NE(watched.out.find("CANCELLED"), std::string::npos) << watched.out;
  EXPECT_LT(cancel_s, 30) << "the group stops at its next collective cancellation check";
  std::printf("  cancelled in %.1f s\n", cancel_s);

  // The group's ranks are free again: a one-rank curve is answered.
  const CliRun after = Gonogo(server.endpoint(),
                              "curve --tier bekker --soil lll_dry_sand --wheel-diameter 0.5 "
                              "--wheel-width 0.2 --section-height 0.1 --wheel-load 1000");
  EXPECT_EQ(after.exit_code, 0) << after.out;
  EXPECT_EQ(server.Terminate(), 0);
}

// kill -9 of the whole MPI job mid-curve; the restarted server resumes the curve job from the last
// checkpoint (FE state and every RVE) and ends with the uninterrupted curve.
TEST(FeDeService, AKilledServerResumesTheCurveFromItsCheckpointToTheSameCurve) {
  ScratchDir dir("fe-de-resume");
  const std::vector<std::string> flags = {"--fe-de-preset", "ci", "--ranks-per-task", "2",
                                          "--fe-de-checkpoint-s", "5"};
  std::string id;
  double fraction_at_kill = 0;
  {
    ServerProcess server(dir.path(), flags, 3);
    const CliRun submitted = Gonogo(server.endpoint(), std::string(kWheel) + " --no-wait");
    ASSERT_EQ(submitted.exit_code, 0) << submitted.out;
    std::smatch match;
    ASSERT_TRUE(std::regex_search(submitted.out, match, std::regex("job-[0-9a-f-]+")))
        << submitted.out;
    id = match.str();
    auto stub = server.Stub();
    for (int i = 0; i < 1200 && fraction_at_kill < 0.5; ++i) {
      grpc::ClientContext ctx;
      v1::GetJobRequest req;
      req.set_job_id(id);
      v1::Job now;
      stub->GetJob(&ctx, req, &now);
      fraction_at_kill = now.status().fraction_done();
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    ASSERT_GE(fraction_at_kill, 0.5) << "the curve should be half done within 5 minutes";
    ASSERT_LT(fraction_at_kill, 1.0) << "progress streams from the group leader while it runs";
    ASSERT_TRUE(fs::exists(dir.path() / "checkpoints")) << "a checkpoint every 5 s";
    server.Kill();
  }
  ServerProcess again(dir.path(), flags, 3);
  EXPECT_NE(again.banner().find("1 jobs resumed"), std::string::npos) << again.banner();
  const auto resumed_start = std::chrono::steady_clock::now();
  const CliRun watched = Gonogo(again.endpoint(), "watch " + id);
  const double resumed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - resumed_start).count();
  EXPECT_NE(watched.out.find("DONE"), std::string::npos) << watched.out;
  std::printf("  killed at %.0f %%, resumed to the end in %.1f s\n", 100 * fraction_at_kill,
              resumed_s);
  const CliRun curve = Gonogo(again.endpoint(), std::string(kWheel) + " --csv");
  ASSERT_EQ(curve.exit_code, 0) << curve.out;
  if (uninterrupted_csv != nullptr) {
    EXPECT_EQ(CsvPart(curve.out), *uninterrupted_csv) << "the resumed curve is the same";
  }
  const fs::path restart_files = dir.path() / "checkpoints";
  EXPECT_TRUE(!fs::exists(restart_files) || fs::is_empty(restart_files))
      << "restart files are removed once the curve is stored";
  EXPECT_EQ(again.Terminate(), 0);
}

}  // namespace
}  // namespace gonogo::testing
