// A bounded loopback load test of the service.
//
//   build/tests/bench/gonogo-bench-load [--clients 8] [--seconds 30] [--rounds 3] [--size 48]
//
// Starts gonogo-server (embedded default, 2 worker threads, a token file with one identity per
// client) on a fresh data directory, then CLIENTS threads, each with its own identity, run a mix for
// SECONDS: cached traction-curve queries (timed), small empirical maps (upload, watch to DONE,
// download), maps cancelled part-way, and list calls. Prints the calls of each kind, every error (the
// target is none), the p50 and p99 latency of a cached curve query, and the server's resident memory
// before the load and after each identical round (growth that does not level off is a leak).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "server_process.h"

using namespace gonogo;
using namespace gonogo::testing;
using Clock = std::chrono::steady_clock;

namespace {

// VmRSS of `pid`, MiB.
double ResidentMiB(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      double kib = 0;
      status >> kib;
      return kib / 1024.0;
    }
  }
  return -1;
}

struct Tally {
  std::mutex mutex;
  std::vector<double> cached_curve_ms;
  int maps = 0, cancelled = 0, lists = 0, curves = 0;
  std::vector<std::string> errors;
  void Error(const std::string& what, const grpc::Status& s) {
    std::lock_guard<std::mutex> lock(mutex);
    errors.push_back(what + ": " + std::to_string(s.error_code()) + " " + s.error_message());
  }
};

v1::GetTractionCurveRequest Curve(int load_step) {
  v1::GetTractionCurveRequest request;
  request.set_tier("empirical");
  *request.mutable_tyre() = FedAlpha().axles(0).tyre();
  request.set_wheel_load_n(8000 + 100 * load_step);
  request.mutable_soil()->set_cone_index_pa(600e3);
  return request;
}

// One client's loop until `until`: mostly cached curves, a map every 20th call, a cancelled map
// every 50th, a list every 10th.
void Client(const ServerProcess& server, const std::string& token, const v1::MapRequest& map,
            const std::vector<std::pair<v1::RasterRole, std::string>>& rasters, Clock::time_point until,
            unsigned seed, Tally& tally) {
  auto stub = server.Stub(token);
  std::mt19937 random(seed);
  for (int call = 1; Clock::now() < until; ++call) {
    if (call % 20 == 0) {
      v1::Job job;
      grpc::Status s = Submit(*stub, map, rasters, &job);
      if (!s.ok()) { tally.Error("SubmitMap", s); continue; }
      const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
      if (end.state() != v1::JOB_STATE_DONE) {
        tally.Error("map " + job.job_id(), grpc::Status(grpc::StatusCode::UNKNOWN, end.message()));
        continue;
      }
      if (NamesOf(DownloadAll(*stub, job.job_id())) != MapProductNames()) {
        tally.Error("DownloadResult", grpc::Status(grpc::StatusCode::DATA_LOSS, "products missing"));
      }
      std::lock_guard<std::mutex> lock(tally.mutex);
      ++tally.maps;
    } else if (call % 50 == 1) {
      v1::MapRequest fresh = map;
      fresh.set_disable_similarity(true);
      fresh.mutable_criteria()->set_slip_step(0.001 + 0.001 * (random() % 20));  // new curves
      v1::Job job;
      grpc::Status s = Submit(*stub, fresh, rasters, &job);
      if (!s.ok()) { tally.Error("SubmitMap (to cancel)", s); continue; }
      grpc::ClientContext context;
      v1::CancelJobRequest cancel;
      cancel.set_job_id(job.job_id());
      v1::Job after;
      s = stub->CancelJob(&context, cancel, &after);
      // A job that ended before the cancel arrived is refused with FAILED_PRECONDITION: not an error.
      if (!s.ok() && s.error_code() != grpc::StatusCode::FAILED_PRECONDITION) tally.Error("CancelJob", s);
      WaitForEnd(*stub, job.job_id());
      std::lock_guard<std::mutex> lock(tally.mutex);
      ++tally.cancelled;
    } else if (call % 10 == 0) {
      grpc::ClientContext context;
      v1::ListJobsRequest request;
      v1::ListJobsResponse response;
      if (grpc::Status s = stub->ListJobs(&context, request, &response); !s.ok()) tally.Error("ListJobs", s);
      std::lock_guard<std::mutex> lock(tally.mutex);
      ++tally.lists;
    } else {
      grpc::ClientContext context;
      v1::TractionCurve curve;
      const Clock::time_point start = Clock::now();
      const grpc::Status s = stub->GetTractionCurve(&context, Curve(random() % 10), &curve);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      if (!s.ok()) { tally.Error("GetTractionCurve", s); continue; }
      std::lock_guard<std::mutex> lock(tally.mutex);
      ++tally.curves;
      if (curve.provenance().cache_hit()) tally.cached_curve_ms.push_back(ms);
    }
  }
}

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<size_t>(p * values.size()))];
}

}  // namespace

int main(int argc, char** argv) {
  int clients = 8, seconds = 30, rounds = 3, size = 48;
  CLI::App app("A bounded loopback load test: several clients, mixed maps, cached curves, cancels and "
               "lists for a fixed time; prints errors, cached-curve latency and server memory.",
               "gonogo-bench-load");
  app.add_option("--clients", clients, "client threads, one identity each")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--seconds", seconds, "length of each round, s")->check(CLI::Range(1, 3600))->capture_default_str();
  app.add_option("--rounds", rounds, "identical rounds, memory printed after each")->check(CLI::Range(1, 100))->capture_default_str();
  app.add_option("--size", size, "cells per side of the sample terrain the maps use")->check(CLI::Range(8, 2000))->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  ScratchDir dir("bench-load");
  const fs::path terrain = dir.path() / "terrain";
  if (!MakeSampleTerrain(terrain, size)) return 1;
  std::vector<std::string> tokens;
  {
    std::ofstream file(dir.path() / "tokens");
    for (int i = 0; i < clients; ++i) {
      tokens.push_back("load-client-token-" + std::to_string(1000000 + i));
      file << tokens.back() << " client" << i << "\n";
    }
  }
  fs::permissions(dir.path() / "tokens", fs::perms::owner_read | fs::perms::owner_write);
  ServerProcess server(dir.path() / "data",
                       {"--token-file", (dir.path() / "tokens").string(), "--threads", "2"});
  v1::MapRequest map;
  map.set_name("load");
  map.set_tier("empirical");
  *map.mutable_vehicle() = FedAlpha();
  *map.mutable_soil_table() = SampleSoilTable(terrain);
  const std::vector<std::pair<v1::RasterRole, std::string>> rasters = {
      {v1::RASTER_ROLE_CONE_INDEX, ReadFile(terrain / "cone_index.tif")},
      {v1::RASTER_ROLE_ELEVATION, ReadFile(terrain / "elevation.tif")},
      {v1::RASTER_ROLE_SOIL_CLASS, ReadFile(terrain / "soil_class.tif")}};
  // The curves the clients query, computed once so that every later query is a cache hit.
  {
    auto stub = server.Stub(tokens[0]);
    for (int i = 0; i < 10; ++i) {
      grpc::ClientContext context;
      v1::TractionCurve curve;
      if (!stub->GetTractionCurve(&context, Curve(i), &curve).ok()) return 1;
    }
  }
  const double rss_start = ResidentMiB(server.server_pid());
  std::printf("gonogo-bench-load: %d clients, %d rounds of %d s, %d x %d terrain; server RSS at start %.1f MiB\n",
              clients, rounds, seconds, size, size, rss_start);
  int total_errors = 0;
  for (int round = 1; round <= rounds; ++round) {
    Tally tally;
    const Clock::time_point until = Clock::now() + std::chrono::seconds(seconds);
    std::vector<std::thread> threads;
    for (int i = 0; i < clients; ++i) {
      threads.emplace_back(Client, std::cref(server), tokens[i], std::cref(map), std::cref(rasters), until,
                           1234u + 97u * i + 7u * round, std::ref(tally));
    }
    for (auto& t : threads) t.join();
    total_errors += static_cast<int>(tally.errors.size());
    std::printf("round %d: %d curve queries (%zu cached: p50 %.2f ms, p99 %.2f ms), %d maps, %d cancelled maps, "
                "%d lists; errors %zu; server RSS %.1f MiB\n",
                round, tally.curves, tally.cached_curve_ms.size(), Percentile(tally.cached_curve_ms, 0.5),
                Percentile(tally.cached_curve_ms, 0.99), tally.maps, tally.cancelled, tally.lists,
                tally.errors.size(), ResidentMiB(server.server_pid()));
    for (size_t i = 0; i < std::min<size_t>(tally.errors.size(), 10); ++i) {
      std::printf("  error: %s\n", tally.errors[i].c_str());
    }
  }
  std::printf("%s\n", server.Terminate() == 0 ? "server drained and exited cleanly" : "server exit FAILED");
  return total_errors == 0 ? 0 : 1;
}
