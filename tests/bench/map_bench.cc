// Map throughput and cache latency.
//
//   build/tests/bench/gonogo-bench-map [--size 1000] [--lookups 10000] [--tier empirical]
//                                      [--soil-classes N]
//
// Makes a SIZE x SIZE sample terrain, starts gonogo-server (embedded default) on a fresh data
// directory, and times the same map end to end (upload, plan, traction tasks, cell evaluation,
// products, download) twice: cold cache, then warm. Then times traction-curve lookups in the SQLite
// cache that the cold run filled. --soil-classes N replaces the sample's 3 soil classes by N
// vertical stripes, each mapped to a soil of the Bekker library (for --tier bekker).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include <gdal.h>
#include <ogr_srs_api.h>

#include "cache/curve_store.h"
#include "cache/database.h"
#include "server_process.h"
#include "solvers/common/cli_checks.h"

using namespace gonogo;
using namespace gonogo::testing;
using Clock = std::chrono::steady_clock;

namespace {

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

struct MapRun {
  double seconds;
  nlohmann::json summary;
};

// Library soils for --soil-classes (the Bekker library without its snows).
const char* kLibrarySoils[] = {
    "lll_dry_sand", "lll_sandy_loam_15pct", "lll_sandy_loam_22pct", "michigan_sandy_loam_11pct",
    "michigan_sandy_loam_23pct", "hanamoto_sandy_loam_26pct", "hanamoto_sandy_loam_32pct",
    "thailand_clayey_soil_38pct", "thailand_clayey_soil_55pct", "wes_heavy_clay_25pct",
    "wes_heavy_clay_40pct", "wes_lean_clay_22pct", "wes_lean_clay_32pct", "lete_sand",
    "upland_sandy_loam_51pct", "rubicon_sandy_loam_43pct", "north_gower_clayey_loam_46pct",
    "grenville_loam_24pct"};

// Rewrites soil_class.tif as `classes` vertical stripes on the cone-index grid; returns the table.
v1::SoilTable StripeSoils(const fs::path& terrain, int classes) {
  GDALAllRegister();
  GDALDatasetH ci = GDALOpen((terrain / "cone_index.tif").c_str(), GA_ReadOnly);
  const int w = GDALGetRasterXSize(ci), h = GDALGetRasterYSize(ci);
  double gt[6];
  GDALGetGeoTransform(ci, gt);
  GDALDatasetH out = GDALCreate(GDALGetDriverByName("GTiff"), (terrain / "soil_class.tif").c_str(),
                                w, h, 1, GDT_Byte, nullptr);
  GDALSetGeoTransform(out, gt);
  GDALSetSpatialRef(out, GDALGetSpatialRef(ci));
  std::vector<uint8_t> codes(static_cast<size_t>(w) * h);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) codes[static_cast<size_t>(r) * w + c] = 1 + c * classes / w;
  }
  CPLErr err = GDALRasterIO(GDALGetRasterBand(out, 1), GF_Write, 0, 0, w, h, codes.data(), w, h,
                            GDT_Byte, 0, 0);
  (void)err;
  GDALClose(out);
  GDALClose(ci);
  v1::SoilTable table;
  const int library = sizeof kLibrarySoils / sizeof kLibrarySoils[0];
  for (int k = 0; k < classes; ++k) {
    v1::SoilClass* c = table.add_classes();
    c->set_code(k + 1);
    c->set_name("class " + std::to_string(k + 1));
    c->set_bekker_soil(kLibrarySoils[k % library]);
  }
  return table;
}

MapRun RunMap(const ServerProcess& server, const fs::path& terrain, const std::string& tier,
              const v1::SoilTable& soils) {
  auto stub = server.Stub();
  v1::MapRequest request;
  request.set_name("bench");
  request.set_tier(tier);
  *request.mutable_vehicle() = FedAlpha();
  *request.mutable_soil_table() = soils;
  const auto start = Clock::now();
  const std::vector<std::pair<v1::RasterRole, std::string>> rasters = {
      {v1::RASTER_ROLE_CONE_INDEX, ReadFile(terrain / "cone_index.tif")},
      {v1::RASTER_ROLE_ELEVATION, ReadFile(terrain / "elevation.tif")},
      {v1::RASTER_ROLE_SOIL_CLASS, ReadFile(terrain / "soil_class.tif")}};
  v1::Job job;
  const grpc::Status s = Submit(*stub, request, rasters, &job);
  if (!s.ok()) {
    std::fprintf(stderr, "submit failed: %s\n", s.error_message().c_str());
    std::exit(1);
  }
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  if (end.state() != v1::JOB_STATE_DONE) {
    std::fprintf(stderr, "job ended %d: %s\n", end.state(), end.message().c_str());
    std::exit(1);
  }
  const auto products = DownloadAll(*stub, job.job_id());
  const double seconds = Seconds(start, Clock::now());
  return {seconds, nlohmann::json::parse(products.at("summary.json"))};
}

}  // namespace

int main(int argc, char** argv) {
  int size = 1000, lookups = 10000, soil_classes = 0;
  std::string tier = "empirical";
  CLI::App app(
      "Map throughput and cache latency: makes a SIZE x SIZE sample terrain, starts gonogo-server "
      "(embedded default) on a fresh data directory, and times the same map end to end (upload, "
      "plan, traction tasks, cell evaluation, products, download) twice: cold cache, then warm. "
      "Then times traction-curve lookups in the SQLite cache that the cold run filled.",
      "gonogo-bench-map");
  const CLI::Validator at_least_one = gonogo::cli_checks::AtLeastOne();
  app.add_option("--size", size, "cells per side of the sample terrain")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--lookups", lookups, "cache lookups timed, hits and misses each")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--tier", tier, "traction tier of the map")->capture_default_str();
  app.add_option("--soil-classes", soil_classes,
                 "replace the sample's 3 soil classes by N vertical stripes, each mapped to a soil "
                 "of the Bekker library (for --tier bekker); 0: the sample's classes")
      ->check(CLI::Range(0, std::numeric_limits<int>::max()).description(">= 0"))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  ScratchDir dir("bench");
  const fs::path terrain = dir.path() / "terrain";
  if (!MakeSampleTerrain(terrain, size)) return 1;
  const v1::SoilTable soils =
      soil_classes > 0 ? StripeSoils(terrain, soil_classes) : SampleSoilTable(terrain);
  std::printf("map %d x %d cells, %s tier, %d soil classes, FED Alpha, embedded server\n", size,
              size, tier.c_str(), soils.classes_size());
  {
    ServerProcess server(dir.path() / "data");
    const MapRun cold = RunMap(server, terrain, tier, soils);
    const MapRun warm = RunMap(server, terrain, tier, soils);
    const double cells = double(size) * size;
    std::printf("terrain units %d\n", cold.summary["terrain_units"].get<int>());
    std::printf("%-6s %10s %12s %8s %10s %10s\n", "cache", "seconds", "cells/s", "tasks", "computed",
                "hits");
    for (const auto& [name, run] : {std::pair{"cold", cold}, std::pair{"warm", warm}}) {
      std::printf("%-6s %10.3f %12.0f %8d %10d %10d\n", name, run.seconds, cells / run.seconds,
                  run.summary["tasks"]["total"].get<int>(),
                  run.summary["tasks"]["computed"].get<int>(),
                  run.summary["tasks"]["cache_hits"].get<int>());
    }
    server.Terminate();
  }
  // Cache lookups: random existing keys, then missing keys.
  cache::Database db((dir.path() / "data" / "gonogo.sqlite").string());
  cache::CurveStore store(db);
  std::vector<std::string> keys;
  for (int64_t before = 0;;) {
    auto page = store.List({}, 1000, before);
    for (auto& c : page.curves) keys.push_back(c.cache_key);
    if (!page.next_after_id) break;
    before = page.next_after_id;
  }
  std::mt19937 rng(7);
  auto t0 = Clock::now();
  int found = 0;
  for (int i = 0; i < lookups; ++i) found += store.Find(keys[rng() % keys.size()]).has_value();
  auto t1 = Clock::now();
  for (int i = 0; i < lookups; ++i) found += store.Find("missing-" + std::to_string(i)).has_value();
  auto t2 = Clock::now();
  std::printf("cache: %zu curves; lookup hit %.1f us, miss %.1f us (%d lookups each, %d found)\n",
              keys.size(), 1e6 * Seconds(t0, t1) / lookups, 1e6 * Seconds(t1, t2) / lookups, lookups,
              found);
  return 0;
}
