// The `gonogo` command line against a real server: a map with progress and products, the job list,
// a traction curve as CSV, and clear errors (exit 2, naming the option) for bad vehicle files and
// mistyped, missing or conflicting options; --help of every command.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "server_process.h"

namespace gonogo::testing {
namespace {

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
  const CliRun r =
      Gonogo(server_->endpoint(), "map --cone-index " + T("cone_index.tif") + " --elevation " +
                                      T("elevation.tif") + " --soil-class " + T("soil_class.tif") +
                                      " --soil-table " + T("soil_table.json") + " --vehicle " +
                                      Vehicle() + " --tier empirical --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("100%"), std::string::npos) << "progress reaches 100 %: " << r.out;
  EXPECT_NE(r.out.find("tasks "), std::string::npos) << r.out;
  for (const char* f : {"gonogo.tif", "gonogo.tif.aux.xml", "gonogo.qml", "speed.tif", "speed.qml",
                        "gonogo.kmz", "quicklook.png", "summary.json", "item.json"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
    EXPECT_GT(fs::file_size(fs::path(out) / f), 0u) << f;
  }
  // The downloaded folder as a GIS user opens it: QGIS applies the styles and shows the labelled
  // classes and the km/h ramp, and the STAC item (with the job's provenance) validates.
  const std::string qgis_check =
      "/usr/bin/python3 " + SourceDir() + "/tests/server/geo/qgis_products_test.py --products " +
      out + " --out " + out + "/qgis --stac-schemas " + SourceDir() + "/tests/data/stac 2>&1";
  FILE* check = popen(qgis_check.c_str(), "r");
  ASSERT_NE(check, nullptr);
  std::string check_output;
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, check)) > 0;) {
    check_output.append(buffer, n);
  }
  const int check_status = pclose(check);
  EXPECT_TRUE(WIFEXITED(check_status) && WEXITSTATUS(check_status) == 0) << check_output;
  const std::string item = ReadFile(fs::path(out) / "item.json");
  EXPECT_NE(item.find("\"gonogo:provenance\""), std::string::npos) << item;
  EXPECT_NE(item.find("\"vehicle_hash\""), std::string::npos) << item;
  const CliRun jobs = Gonogo(server_->endpoint(), "jobs");
  EXPECT_EQ(jobs.exit_code, 0);
  EXPECT_NE(jobs.out.find("DONE"), std::string::npos) << jobs.out;
}

TEST_F(CliTest, CurveCsvHasTheDocumentedColumns) {
  const CliRun r = Gonogo(server_->endpoint(), "curve --tier empirical --vehicle " + Vehicle() +
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
  const CliRun r =
      Gonogo(server_->endpoint(), "scalability --tier empirical --vehicle " + Vehicle() +
                                      " --cone-index 800 --scales 1,0.7,0.5 --out " + out.string());
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
  for (const char* tier :
       {"empirical (empirical-1)", "bekker (bekker-1)", "fe-classic (fe-classic-3)"}) {
    EXPECT_NE(r.out.find(tier), std::string::npos) << tier << "\n" << r.out;
  }
  EXPECT_NE(r.out.find("reads:  cone index"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cost:   minutes on one core"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("diagnostic"), std::string::npos) << "only with --diagnostic-tiers";
}

TEST_F(CliTest, SoilsListsModelsWithUnitsAndTheCatalogueWithItsTiers) {
  const CliRun r = Gonogo(server_->endpoint(), "soils");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("model bekker:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("friction_angle_deg"), std::string::npos);
  EXPECT_NE(r.out.find("(0, 90)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("model dem-hertz-mindlin:"), std::string::npos);
  EXPECT_NE(r.out.find("default 0.452"), std::string::npos) << "seed 000's friction";
  // lete_sand: calibrated for bekker and drucker-prager, read by both tiers.
  const size_t lete = r.out.find("\n  lete_sand ");
  ASSERT_NE(lete, std::string::npos) << r.out;
  const std::string line = r.out.substr(lete + 1, r.out.find('\n', lete + 1) - lete - 1);
  EXPECT_NE(line.find("bekker,drucker-prager"), std::string::npos) << line;
  EXPECT_NE(line.find("bekker,fe-classic"), std::string::npos) << line;

  const CliRun one = Gonogo(server_->endpoint(), "soils dem-eepa");
  EXPECT_EQ(one.exit_code, 0);
  EXPECT_NE(one.out.find("surface_energy_j_m2"), std::string::npos);
  EXPECT_EQ(one.out.find("catalogue"), std::string::npos);
  EXPECT_EQ(Gonogo(server_->endpoint(), "soils moon-dust").exit_code, 2);
}

TEST_F(CliTest, SoilParamsReachTheTierAndBadOnesNameTheParameter) {
  // The same soil as --bekker, through the generic form: the same cache key.
  const std::string wheel =
      "curve --tier bekker --wheel-diameter 1.011 --wheel-width 0.335 "
      "--wheel-load 14513 ";
  const CliRun short_names =
      Gonogo(server_->endpoint(), wheel +
                                      "--bekker n=0.79,kc=102000,kphi=5301000,c=1300,"
                                      "phi_deg=31.1,K=0.0115 --csv");
  ASSERT_EQ(short_names.exit_code, 0) << short_names.out;
  const CliRun generic =
      Gonogo(server_->endpoint(),
             wheel +
                 "--soil-params bekker:n=0.79,kc=102000,kphi=5301000,cohesion_pa=1300,"
                 "friction_angle_deg=31.1,shear_deformation_m=0.0115 --csv");
  ASSERT_EQ(generic.exit_code, 0) << generic.out;
  EXPECT_EQ(short_names.out.substr(0, short_names.out.find("cache key")),
            generic.out.substr(0, generic.out.find("cache key")));
  EXPECT_NE(generic.out.find("params=bekker{cohesion_pa=1300,"), std::string::npos) << generic.out;

  const CliRun bad =
      Gonogo(server_->endpoint(), wheel +
                                      "--soil-params bekker:n=0.79,kc=102000,kphi=5301000,"
                                      "cohesion_pa=1300,friction_angle_deg=95,"
                                      "shear_deformation_m=0.0115");
  EXPECT_EQ(bad.exit_code, 3) << bad.out;
  EXPECT_NE(
      bad.out.find("INVALID_ARGUMENT: soil.parameters.friction_angle_deg: must lie in (0, 90) deg"),
      std::string::npos)
      << bad.out;
  EXPECT_EQ(Gonogo(server_->endpoint(), wheel + "--soil-params n=1").exit_code, 2);
}

TEST_F(CliTest, ACurveThatTakesMinutesRunsAsAJobWithProgress) {
  ScratchDir dir("cli-curve-job");
  ServerProcess server(dir.path(), {"--diagnostic-tiers"});
  const std::string wheel =
      "curve --tier diagnostic-slow-curve --wheel-diameter 1.011 "
      "--wheel-width 0.335 --section-height 0.2178 --deflection 0.0327 "
      "--wheel-load 13438 --cone-index 300 --csv";
  const CliRun r = Gonogo(server.endpoint(), wheel);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("curve job job-"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("slip,drawbar_pull_n,torque_nm"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n1,"), std::string::npos) << "the sweep reaches slip 1: " << r.out;
  const CliRun no_wait = Gonogo(server.endpoint(), wheel + " --no-wait");
  ASSERT_EQ(no_wait.exit_code, 0) << no_wait.out;
  EXPECT_EQ(no_wait.out.find("slip,"), std::string::npos) << "returns with the job id only";
}

TEST_F(CliTest, BadVehicleFileAndOptionsAreExplained) {
  const fs::path bad = scratch_->path() / "bad_vehicle.json";
  std::ofstream(bad) << R"({"name": "x", "mass_kg": 1000, "wingspan_m": 3})";
  CliRun r = Gonogo(server_->endpoint(),
                    "curve --tier empirical --vehicle " + bad.string() + " --cone-index 300");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("wingspan_m"), std::string::npos) << r.out;

  r = Gonogo(server_->endpoint(),
             "curve --tier nonsense --vehicle " + Vehicle() + " --cone-index 300");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("INVALID_ARGUMENT: tier:"), std::string::npos) << r.out;

  r = Gonogo(server_->endpoint(),
             "curve --tier empirical --vehicle " + Vehicle() + " --cone-index soft");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--cone-index"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("soft"), std::string::npos) << "names the value: " << r.out;

  r = Gonogo(server_->endpoint(), "cancel job-doesnotexist");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.out.find("NOT_FOUND"), std::string::npos) << r.out;
}

TEST_F(CliTest, MistypedMissingAndConflictingOptionsAreUsageErrorsNamingTheOption) {
  const std::string wheel = "curve --tier empirical --wheel-diameter 1.011 --wheel-width 0.335 ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {wheel + "--wheel-lod 9000 --cone-index 300", "--wheel-lod"},
      {"jobs --limt 3", "--limt"},
      {"jobs --limit many", "--limit"},
      {wheel + "--cone-index 300", "--wheel-load"},  // required without --vehicle
      {"curve --vehicle " + Vehicle() + " --cone-index 300", "--tier"},
      {"curve --tier empirical --vehicle " + Vehicle() + " --wheel-width 0.3 --cone-index 300",
       "--wheel-width"},  // the wheel's own dimensions exclude a vehicle
      {"curve --tier empirical --vehicle " + Vehicle(), "--cone-index"},  // no soil
      {"download job-1", "--out"},
      {"map --cone-index " + T("cone_index.tif") + " --slope " + T("elevation.tif") +
           " --elevation " + T("elevation.tif") + " --vehicle " + Vehicle() +
           " --tier empirical --out /tmp",
       "--elevation"},
      {"frobnicate", "frobnicate"}};
  for (const auto& [args, option] : cases) {
    const CliRun r = Gonogo(server_->endpoint(), args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(option), std::string::npos) << args << " names " << option << ":\n"
                                                     << r.out;
  }
}

TEST_F(CliTest, HelpListsEachCommandsOptionsWithUnits) {
  const CliRun top = Gonogo(server_->endpoint(), "--help");
  ASSERT_EQ(top.exit_code, 0) << top.out;
  for (const char* command : {"map", "jobs", "watch", "cancel", "download", "curve", "scalability",
                              "tiers", "soils", "--server"}) {
    EXPECT_NE(top.out.find(command), std::string::npos) << command << "\n" << top.out;
  }
  const CliRun curve = Gonogo(server_->endpoint(), "curve --help");
  ASSERT_EQ(curve.exit_code, 0) << curve.out;
  for (const char* text : {"--tier", "--vehicle", "--axle", "--wheel-diameter", "--wheel-load",
                           "--section-height", "--inflation-pressure-kpa", "--cone-index", "kPa",
                           "--soil", "--bekker", "--soil-params", "--slip-step", "--csv", "--job",
                           "--no-wait", "--no-similarity", "vertical load on the wheel, N"}) {
    EXPECT_NE(curve.out.find(text), std::string::npos) << text << "\n" << curve.out;
  }
  const CliRun jobs = Gonogo(server_->endpoint(), "jobs --help");
  EXPECT_EQ(jobs.exit_code, 0) << jobs.out;
  EXPECT_NE(jobs.out.find("--limit"), std::string::npos) << jobs.out;
  const CliRun map = Gonogo(server_->endpoint(), "map --help");
  EXPECT_EQ(map.exit_code, 0) << map.out;
  for (const char* text : {"--cone-index", "--slope", "--elevation", "--soil-class", "--passes",
                           "--design-slip", "--out", "percent"}) {
    EXPECT_NE(map.out.find(text), std::string::npos) << text << "\n" << map.out;
  }
}

}  // namespace
}  // namespace gonogo::testing
