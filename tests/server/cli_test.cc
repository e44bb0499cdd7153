// The `gonogo` command line against a real server: a map with progress and products, the job list,
// a traction curve as CSV, and clear errors for bad vehicle files and options.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "server_process.h"

namespace gonogo::testing {
namespace {

struct CliRun {
  int exit_code;
  std::string out;  // stdout and stderr together
};

CliRun Gonogo(const std::string& endpoint, const std::string& args) {
  const std::string cmd =
      BinaryDir() + "/clients/gonogo --server " + endpoint + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class CliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("cli");
    ASSERT_TRUE(MakeSampleTerrain(scratch_->path() / "terrain", 40));
    server_ = new ServerProcess(scratch_->path() / "data");
  }
  static void TearDownTestSuite() {
    delete server_;
    delete scratch_;
  }
  static std::string T(const std::string& f) { return (scratch_->path() / "terrain" / f).string(); }
  static std::string Vehicle() { return SourceDir() + "/clients/vehicles/fed_alpha.json"; }

  static ScratchDir* scratch_;
  static ServerProcess* server_;
};
ScratchDir* CliTest::scratch_ = nullptr;
ServerProcess* CliTest::server_ = nullptr;

TEST_F(CliTest, MapWritesEveryProductAndShowsProgress) {
  const std::string out = (scratch_->path() / "out").string();
  const CliRun r = Gonogo(server_->endpoint(),
                       "map --cone-index " + T("cone_index.tif") + " --elevation " +
                           T("elevation.tif") + " --soil-class " + T("soil_class.tif") +
                           " --soil-table " + T("soil_table.json") + " --vehicle " + Vehicle() +
                           " --tier empirical --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("100%"), std::string::npos) << "progress reaches 100 %: " << r.out;
  EXPECT_NE(r.out.find("tasks "), std::string::npos) << r.out;
  for (const char* f : {"gonogo.tif", "speed.tif", "quicklook.png", "summary.json"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
    EXPECT_GT(fs::file_size(fs::path(out) / f), 0u) << f;
  }
  const CliRun jobs = Gonogo(server_->endpoint(), "jobs");
  EXPECT_EQ(jobs.exit_code, 0);
  EXPECT_NE(jobs.out.find("DONE"), std::string::npos) << jobs.out;
}

TEST_F(CliTest, CurveCsvHasTheDocumentedColumns) {
  const CliRun r = Gonogo(server_->endpoint(),
                       "curve --tier empirical --vehicle " + Vehicle() +
                           " --cone-index 300 --slip-step 0.1 --csv");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::istringstream lines(r.out);
  std::string header;
  std::getline(lines, header);
  EXPECT_EQ(header.rfind("slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency", 0), 0u)
      << header;
  int rows = 0;
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0]))) ++rows;
  }
  EXPECT_EQ(rows, 11) << r.out;

  const CliRun wheel = Gonogo(server_->endpoint(),
                           "curve --tier empirical --wheel-diameter 1.011 --wheel-width 0.335 "
                           "--section-height 0.2178 --deflection 0.0327 --wheel-load 13438 "
                           "--cone-index 500 --csv");
  EXPECT_EQ(wheel.exit_code, 0) << wheel.out;
}

TEST_F(CliTest, ScalabilityWritesThePlotAndTables) {
  const fs::path out = scratch_->path() / "scalability";
  const CliRun r = Gonogo(server_->endpoint(), "scalability --tier empirical --vehicle " + Vehicle() +
                                                   " --cone-index 800 --scales 1,0.7,0.5 --out " +
                                                   out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("2NS 0.7: 100  97.1  100"), std::string::npos) << r.out;
  for (const char* f : {"scalability.png", "scalability_curves.csv", "scalability_summary.csv"}) {
    EXPECT_GT(fs::file_size(out / f), 0u) << f;
  }
  const std::string summary = ReadFile(out / "scalability_summary.csv");
  EXPECT_EQ(std::count(summary.begin(), summary.end(), '\n'), 4) << summary;
}

TEST_F(CliTest, TiersListsEveryTierWithWhatItReadsAndCosts) {
  const CliRun r = Gonogo(server_->endpoint(), "tiers");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* tier : {"empirical (empirical-1)", "bekker (bekker-1)", "fe-classic (fe-classic-2)"}) {
    EXPECT_NE(r.out.find(tier), std::string::npos) << tier << "\n" << r.out;
  }
  EXPECT_NE(r.out.find("reads:  cone index"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cost:   minutes on one core"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("diagnostic"), std::string::npos) << "only with --diagnostic-tiers";
}

TEST_F(CliTest, BadVehicleFileAndOptionsAreExplained) {
  const fs::path bad = scratch_->path() / "bad_vehicle.json";
  std::ofstream(bad) << R"({"name": "x", "mass_kg": 1000, "wingspan_m": 3})";
  CliRun r = Gonogo(server_->endpoint(), "curve --tier empirical --vehicle " + bad.string() +
                                          " --cone-index 300");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("wingspan_m"), std::string::npos) << r.out;

  r = Gonogo(server_->endpoint(), "curve --tier nonsense --vehicle " + Vehicle() +
                                      " --cone-index 300");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("INVALID_ARGUMENT: tier:"), std::string::npos) << r.out;

  r = Gonogo(server_->endpoint(), "curve --tier empirical --vehicle " + Vehicle() +
                                      " --cone-index soft");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--cone-index needs a number"), std::string::npos) << r.out;

  r = Gonogo(server_->endpoint(), "cancel job-doesnotexist");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("NOT_FOUND"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace gonogo::testing
