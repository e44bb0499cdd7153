// Test fixture pieces: a real gonogo-server process on a loopback port, a scratch directory, the
// sample terrain, and small helpers around the generated stubs.
#pragma once

#include <grpcpp/grpcpp.h>
#include <sys/types.h>

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "gonogo/v1/mobility.grpc.pb.h"

namespace gonogo::testing {

namespace fs = std::filesystem;

std::string SourceDir();
std::string BinaryDir();
std::string ReadFile(const fs::path& path);

// A fresh directory under /tmp, removed by the destructor.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Runs the bundled sample-terrain script into `out` (size x size cells); returns false on failure.
bool MakeSampleTerrain(const fs::path& out, int size);
// Beside a sample terrain in `terrain_dir`: de_soils.json, a soil table mapping every class to the
// DE soil seed000_sand_rve100, and small_wheels.json, a one-axle pair of 0.5 x 0.2 m wheels each
// carrying 1,000 N (the fe-de and fe-ann tests' rig wheel), for maps on those tiers.
void WriteDeSoilTableAndRigWheels(const fs::path& terrain_dir);

// Bearer tokens of a token file (WriteTokenFile): alice and bob, and the admin ops.
inline constexpr char kAliceToken[] = "alice-0123456789abcdef";
inline constexpr char kBobToken[] = "bob-0123456789abcdefgh";
inline constexpr char kOpsToken[] = "ops-0123456789abcdefgh";
// `dir`/tokens for alice, bob and ops (admin), mode 0600, for gonogo-server --token-file.
fs::path WriteTokenFile(const fs::path& dir);

// gonogo-server (optionally under mpirun) listening on 127.0.0.1:0.
class ServerProcess {
 public:
  // `mpi_ranks` 0 starts the plain binary; N > 0 starts it under `mpirun -np N`.
  ServerProcess(const fs::path& data_dir, std::vector<std::string> extra_args = {},
                int mpi_ranks = 0);
  ~ServerProcess();

  const std::string& endpoint() const { return endpoint_; }
  const std::string& banner() const { return banner_; }
  // The serving process (rank 0 under mpirun).
  pid_t server_pid() const { return server_pid_; }
  // Plaintext; with a `token`, every call carries it as "authorization: Bearer TOKEN".
  std::unique_ptr<v1::MobilityService::Stub> Stub(const std::string& token = "") const;
  std::shared_ptr<grpc::Channel> Channel(const std::string& token = "") const;
  // SIGTERM to the serving process (rank 0 under mpirun) and wait; returns the exit status of the
  // started process (mpirun's under MPI).
  int Terminate();
  // SIGKILL: the crash case.
  void Kill();
  bool Running();

 private:
  pid_t pid_ = -1;
  pid_t server_pid_ = -1;  // the serving process: pid_ itself, or rank 0 under mpirun
  std::string endpoint_;
  std::string banner_;
};

// cache_key -> computed_unix_ms of every curve stored in the database of `data_dir`, read straight
// from the SQLite file.
std::map<std::string, int64_t> StoredCurves(const fs::path& data_dir);
// PRAGMA integrity_check of the database of `data_dir`: "ok" when intact.
std::string IntegrityCheck(const fs::path& data_dir);
// The traction curves `stub`'s identity is shown by ListTractionCurves (one page of 1,000).
int CurveCount(v1::MobilityService::Stub& stub);

// The `gonogo` command line against `endpoint`, stdout and stderr together, and its exit code.
struct CliRun {
  int exit_code;
  std::string out;
};
CliRun Gonogo(const std::string& endpoint, const std::string& args);
// A shell command's stdout and stderr together, and its exit code.
CliRun RunShell(const std::string& command);

// The small fe-ann recipe the service tests train (seed000_sand_rve100, 20-step paths, 4 walks,
// 60 epochs), as gonogo-ann and gonogo train options.
inline constexpr char kSmallSurrogateRecipe[] =
    "--soil seed000_sand_rve100 --steps 20 --walks 4 --epochs 60";
// gonogo-ann on that recipe at the tiny preset, a 16x16 MLP, registering into `data_dir`, with
// `more_options` (" --walk-share 0.6"): its output and exit code.
CliRun RegisterWithGonogoAnn(const fs::path& data_dir, const std::string& more_options = "");

struct MapFiles {
  std::string cone_index, slope, elevation, soil_class, soil_table;
};

v1::Vehicle FedAlpha();
// The soil table written by the sample-terrain script into `terrain_dir`.
v1::SoilTable SampleSoilTable(const fs::path& terrain_dir);
// The sample map of a sample terrain in `terrain_dir`: "sample", empirical tier, FED Alpha, the
// terrain's soil table; and its rasters (cone index, elevation, soil class) for Submit.
v1::MapRequest SampleMapRequest(const fs::path& terrain_dir);
std::vector<std::pair<v1::RasterRole, std::string>> SampleMapRasters(const fs::path& terrain_dir);
// Sends a SubmitMap stream with these rasters (role -> bytes); returns the status.
grpc::Status Submit(v1::MobilityService::Stub& stub, const v1::MapRequest& request,
                    const std::vector<std::pair<v1::RasterRole, std::string>>& rasters,
                    v1::Job* job);
// Follows WatchJob to the end; returns the last status seen.
v1::JobStatus WaitForEnd(v1::MobilityService::Stub& stub, const std::string& job_id);
// Downloads every product into `dir`; returns name -> bytes.
std::map<std::string, std::string> DownloadAll(v1::MobilityService::Stub& stub,
                                               const std::string& job_id);
// The names of a map job's products, as DownloadAll returns them.
std::set<std::string> MapProductNames();
// The names of DownloadAll's answer.
std::set<std::string> NamesOf(const std::map<std::string, std::string>& products);

}  // namespace gonogo::testing
