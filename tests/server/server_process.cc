#include "server_process.h"

#include <google/protobuf/util/json_util.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "clients/bearer_token.h"

namespace gonogo::testing {

// The environment (set by CTest) wins; benchmarks run by hand fall back to the configured tree.
std::string SourceDir() {
  const char* env = std::getenv("GONOGO_SOURCE_DIR");
  return env ? env : GONOGO_DEFAULT_SOURCE_DIR;
}
std::string BinaryDir() {
  const char* env = std::getenv("GONOGO_BINARY_DIR");
  return env ? env : GONOGO_DEFAULT_BINARY_DIR;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

ScratchDir::ScratchDir(const std::string& tag) {
  path_ = fs::temp_directory_path() / ("gonogo-test-" + tag + "-" + std::to_string(getpid()));
  fs::remove_all(path_);
  fs::create_directories(path_);
}
ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

CliRun RunShell(const std::string& command) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

fs::path WriteTokenFile(const fs::path& dir) {
  const fs::path path = dir / "tokens";
  std::ofstream(path) << "# token identity [admin]\n"
                      << kAliceToken << " alice\n"
                      << kBobToken << " bob\n"
                      << kOpsToken << " ops admin\n";
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
  return path;
}

std::map<std::string, int64_t> StoredCurves(const fs::path& data_dir) {
  sqlite3* db = nullptr;
  std::map<std::string, int64_t> out;
  if (sqlite3_open_v2((data_dir / "gonogo.sqlite").c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db, "SELECT cache_key, computed_unix_ms FROM curves", -1, &s, nullptr);
    while (sqlite3_step(s) == SQLITE_ROW) {
      out[reinterpret_cast<const char*>(sqlite3_column_text(s, 0))] = sqlite3_column_int64(s, 1);
    }
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return out;
}

std::string IntegrityCheck(const fs::path& data_dir) {
  sqlite3* db = nullptr;
  std::string answer = "cannot open";
  if (sqlite3_open_v2((data_dir / "gonogo.sqlite").c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &s, nullptr);
    answer.clear();
    while (sqlite3_step(s) == SQLITE_ROW) answer += reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return answer;
}

int CurveCount(v1::MobilityService::Stub& stub) {
  grpc::ClientContext context;
  v1::ListTractionCurvesRequest request;
  request.set_page_size(1000);
  v1::ListTractionCurvesResponse response;
  if (!stub.ListTractionCurves(&context, request, &response).ok()) return -1;
  return response.curves_size();
}

CliRun Gonogo(const std::string& endpoint, const std::string& args) {
  return RunShell(BinaryDir() + "/clients/gonogo --server " + endpoint + " " + args);
}

CliRun RegisterWithGonogoAnn(const fs::path& data_dir, const std::string& more_options) {
  return RunShell("OMP_WAIT_POLICY=passive " + BinaryDir() + "/solvers/ann/gonogo-ann " +
                  kSmallSurrogateRecipe +
                  " --preset tiny --architecture 16x16 --threads 2 --register " +
                  data_dir.string() + more_options);
}

bool MakeSampleTerrain(const fs::path& out, int size) {
  const std::string cmd = "/usr/bin/python3 " + SourceDir() +
                          "/clients/sample-data/make_sample_terrain.py --out " + out.string() +
                          " --size " + std::to_string(size) + " > /dev/null";
  return std::system(cmd.c_str()) == 0;
}

void WriteDeSoilTableAndRigWheels(const fs::path& terrain_dir) {
  std::ofstream(terrain_dir / "de_soils.json") << R"({"classes": [
    {"code": 1, "name": "sand", "remolding_index": 0.9, "bekker_soil": "seed000_sand_rve100"},
    {"code": 2, "name": "silt loam", "remolding_index": 0.75, "bekker_soil": "seed000_sand_rve100"},
    {"code": 3, "name": "clay", "remolding_index": 0.55, "bekker_soil": "seed000_sand_rve100"}]})";
  std::ofstream(terrain_dir / "small_wheels.json") << R"({"name": "rig wheel pair",
    "mass_kg": 203.9432, "axles": [{"load_fraction": 1.0, "wheels": 2, "driven": true,
      "tyre": {"diameter_m": 0.5, "width_m": 0.2, "section_height_m": 0.1}}],
    "drive_power_w": 5000, "max_speed_kmh": 20, "driveline_efficiency": 0.85,
    "ground_clearance_m": 0.2})";
}

ServerProcess::ServerProcess(const fs::path& data_dir, std::vector<std::string> extra,
                             int mpi_ranks) {
  std::vector<std::string> args;
  if (mpi_ranks > 0) {
    args = {"mpirun", "--allow-run-as-root", "--oversubscribe", "-np", std::to_string(mpi_ranks)};
  }
  args.push_back(BinaryDir() + "/server/gonogo-server");
  args.insert(args.end(), {"--data-dir", data_dir.string(), "--listen", "127.0.0.1:0"});
  args.insert(args.end(), extra.begin(), extra.end());

  int out[2];
  if (pipe(out) != 0) throw std::runtime_error("pipe failed");
  pid_ = fork();
  if (pid_ == 0) {
    setpgid(0, 0);  // own process group: Kill() reaches mpirun's children too
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  close(out[1]);
  // The banner line carries the bound port.
  FILE* stream = fdopen(out[0], "r");
  char line[4096];
  const std::regex re(R"(listening on (\S+) \(pid (\d+))");
  while (fgets(line, sizeof line, stream)) {
    std::cmatch m;
    if (std::regex_search(line, m, re)) {
      endpoint_ = m[1];
      server_pid_ = std::stoi(m[2]);
      banner_ = line;
      break;
    }
  }
  if (endpoint_.empty()) throw std::runtime_error("gonogo-server did not start");
  // Keep draining stdout in the background so the server never blocks on a full pipe.
  std::thread([stream] {
    char buf[4096];
    while (fgets(buf, sizeof buf, stream)) {
    }
    fclose(stream);
  }).detach();
}

ServerProcess::~ServerProcess() {
  if (Running()) Kill();
}

bool ServerProcess::Running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    pid_ = -1;
    return false;
  }
  return true;
}

int ServerProcess::Terminate() {
  if (pid_ <= 0) return -1;
  kill(server_pid_, SIGTERM);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

void ServerProcess::Kill() {
  if (pid_ <= 0) return;
  kill(-pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
}

std::shared_ptr<grpc::Channel> ServerProcess::Channel(const std::string& token) const {
  return clients::ChannelWithToken(endpoint_, grpc::InsecureChannelCredentials(), token);
}

std::unique_ptr<v1::MobilityService::Stub> ServerProcess::Stub(const std::string& token) const {
  return v1::MobilityService::NewStub(Channel(token));
}

v1::Vehicle FedAlpha() {
  v1::Vehicle v;
  const auto status = google::protobuf::util::JsonStringToMessage(
      ReadFile(SourceDir() + "/clients/vehicles/fed_alpha.json"), &v);
  if (!status.ok()) throw std::runtime_error("fed_alpha.json: " + std::string(status.message()));
  return v;
}

v1::SoilTable SampleSoilTable(const fs::path& terrain_dir) {
  v1::SoilTable t;
  const auto status =
      google::protobuf::util::JsonStringToMessage(ReadFile(terrain_dir / "soil_table.json"), &t);
  if (!status.ok()) throw std::runtime_error("soil_table.json: " + std::string(status.message()));
  return t;
}

v1::MapRequest SampleMapRequest(const fs::path& terrain_dir) {
  v1::MapRequest r;
  r.set_name("sample");
  r.set_tier("empirical");
  *r.mutable_vehicle() = FedAlpha();
  *r.mutable_soil_table() = SampleSoilTable(terrain_dir);
  return r;
}

std::vector<std::pair<v1::RasterRole, std::string>> SampleMapRasters(const fs::path& terrain_dir) {
  return {{v1::RASTER_ROLE_CONE_INDEX, ReadFile(terrain_dir / "cone_index.tif")},
          {v1::RASTER_ROLE_ELEVATION, ReadFile(terrain_dir / "elevation.tif")},
          {v1::RASTER_ROLE_SOIL_CLASS, ReadFile(terrain_dir / "soil_class.tif")}};
}

grpc::Status Submit(v1::MobilityService::Stub& stub, const v1::MapRequest& request,
                    const std::vector<std::pair<v1::RasterRole, std::string>>& rasters,
                    v1::Job* job) {
  grpc::ClientContext ctx;
  auto writer = stub.SubmitMap(&ctx, job);
  v1::SubmitMapRequest first;
  *first.mutable_request() = request;
  writer->Write(first);
  for (const auto& [role, bytes] : rasters) {
    for (size_t off = 0; off < bytes.size() || off == 0; off += 1 << 20) {
      v1::SubmitMapRequest m;
      m.mutable_chunk()->set_role(role);
      m.mutable_chunk()->set_data(bytes.substr(off, 1 << 20));
      if (!writer->Write(m)) break;
      if (bytes.empty()) break;
    }
  }
  writer->WritesDone();
  return writer->Finish();
}

v1::JobStatus WaitForEnd(v1::MobilityService::Stub& stub, const std::string& job_id) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::minutes(5));
  v1::WatchJobRequest req;
  req.set_job_id(job_id);
  auto reader = stub.WatchJob(&ctx, req);
  v1::JobStatus s, last;
  while (reader->Read(&s)) last = s;
  reader->Finish();
  return last;
}

std::map<std::string, std::string> DownloadAll(v1::MobilityService::Stub& stub,
                                               const std::string& job_id) {
  grpc::ClientContext ctx;
  v1::DownloadResultRequest req;
  req.set_job_id(job_id);
  auto reader = stub.DownloadResult(&ctx, req);
  std::map<std::string, std::string> files;
  v1::ResultChunk c;
  while (reader->Read(&c)) files[c.product()] += c.data();
  reader->Finish();
  return files;
}

std::set<std::string> MapProductNames() {
  return {"gonogo.tif", "gonogo.tif.aux.xml", "gonogo.qml", "speed.tif", "speed.qml",
          "gonogo.kmz", "quicklook.png", "summary.json", "item.json"};
}

std::set<std::string> NamesOf(const std::map<std::string, std::string>& products) {
  std::set<std::string> names;
  for (const auto& [name, bytes] : products) names.insert(name);
  return names;
}

}  // namespace gonogo::testing
