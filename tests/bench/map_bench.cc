// Map throughput and cache latency.
//
//   build/tests/bench/gonogo-bench-map [--size 1000] [--lookups 10000]
//
// Makes a SIZE x SIZE sample terrain, starts gonogo-server (embedded default) on a fresh data
// directory, and times the same empirical-tier map end to end (upload, plan, traction tasks, cell
// evaluation, products, download) twice: cold cache, then warm. Then times traction-curve lookups
// in the SQLite cache that the cold run filled.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "cache/curve_store.h"
#include "cache/database.h"
#include "server_process.h"

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

MapRun RunMap(const ServerProcess& server, const fs::path& terrain) {
  auto stub = server.Stub();
  v1::MapRequest request;
  request.set_name("bench");
  request.set_tier("empirical");
  *request.mutable_vehicle() = FedAlpha();
  *request.mutable_soil_table() = SampleSoilTable(terrain);
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
  int size = 1000, lookups = 10000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size")) size = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--lookups")) lookups = std::atoi(argv[i + 1]);
  }
  ScratchDir dir("bench");
  const fs::path terrain = dir.path() / "terrain";
  if (!MakeSampleTerrain(terrain, size)) return 1;
  std::printf("map %d x %d cells, empirical tier, FED Alpha, embedded server\n", size, size);
  {
    ServerProcess server(dir.path() / "data");
    const MapRun cold = RunMap(server, terrain);
    const MapRun warm = RunMap(server, terrain);
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
