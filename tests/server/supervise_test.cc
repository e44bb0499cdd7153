// Survival of a dead worker rank: gonogo-server under `mpirun -np 3`, kept up by
// deploy/gonogo-supervise. A worker rank is killed (SIGKILL, as the OOM killer does) in the middle
// of a map; Open MPI aborts the whole job, the supervisor starts it again, and the job finishes
// with every curve committed before the kill reused, not recomputed. The crash-loop limit and the
// signal handling of the supervisor are tested on plain commands.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "server_process.h"

namespace gonogo::testing {
namespace {

using Clock = std::chrono::steady_clock;



// The pid of the gonogo-server process of MPI rank `rank` serving `data` (its command line names
// the data directory; Open MPI puts the rank in its environment), or 0.
pid_t PidOfRank(const fs::path& data, int rank) {
  const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = ReadFile(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find("gonogo-server") == std::string::npos || cmdline.find(data.string()) == std::string::npos ||
        cmdline.find("mpirun") != std::string::npos) {
      continue;
    }
    std::string environment = ReadFile(entry.path() / "environ");
    std::replace(environment.begin(), environment.end(), '\0', '\n');
    if (("\n" + environment).find("\n" + wanted + "\n") != std::string::npos) return std::stoi(name);
  }
  return 0;
}

// The endpoint the file names once it exists (60 s at most), else "".
std::string WaitForEndpoint(const fs::path& file) {
  for (int i = 0; i < 600; ++i) {
    std::ifstream in(file);
    std::string endpoint;
    if (std::getline(in, endpoint) && !endpoint.empty()) return endpoint;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return "";
}

// Starts `command` (through sh) in its own process group with stdout and stderr into `log`.
pid_t Start(const std::string& command, const fs::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    const std::string line = "exec " + command + " > " + log.string() + " 2>&1";
    execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits at most `limit` for `pid` to end; its exit status, or -1 when it is still running.
int WaitExit(pid_t pid, std::chrono::seconds limit) {
  const Clock::time_point until = Clock::now() + limit;
  while (Clock::now() < until) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return -1;
}

std::string Supervisor() { return SourceDir() + "/deploy/gonogo-supervise"; }

v1::Job GetJob(v1::MobilityService::Stub& stub, const std::string& job_id) {
  grpc::ClientContext context;
  v1::GetJobRequest request;
  request.set_job_id(job_id);
  v1::Job job;
  stub.GetJob(&context, request, &job);
  return job;
}

TEST(Supervise, AKilledWorkerRankIsSurvivedAndTheJobResumesWithItsCurvesKept) {
  ScratchDir dir("supervise");
  ASSERT_TRUE(MakeSampleTerrain(dir.path() / "terrain", 48));
  const fs::path data = dir.path() / "data";
  const fs::path endpoint_file = dir.path() / "endpoint";
  const fs::path log = dir.path() / "supervise.log";
  const pid_t supervisor =
      Start(Supervisor() + " --backoff-s 2 -- mpirun --allow-run-as-root --oversubscribe -np 3 " + BinaryDir() +
                "/server/gonogo-server --data-dir " + data.string() +
                " --listen 127.0.0.1:0 --endpoint-file " + endpoint_file.string() + " --task-delay-ms 100",
            log);
  struct KillGroup {
    pid_t pid;
    ~KillGroup() { kill(-pid, SIGKILL); waitpid(pid, nullptr, WNOHANG); }
  } kill_group{supervisor};
  const std::string first_endpoint = WaitForEndpoint(endpoint_file);
  ASSERT_NE(first_endpoint, "") << ReadFile(log);

  v1::MapRequest request;
  request.set_name("dead rank");
  request.set_tier("empirical");
  *request.mutable_vehicle() = FedAlpha();
  *request.mutable_soil_table() = SampleSoilTable(dir.path() / "terrain");
  const fs::path terrain = dir.path() / "terrain";
  v1::Job job;
  {
    auto stub = v1::MobilityService::NewStub(grpc::CreateChannel(first_endpoint, grpc::InsecureChannelCredentials()));
    ASSERT_TRUE(Submit(*stub, request,
                       {{v1::RASTER_ROLE_CONE_INDEX, ReadFile(terrain / "cone_index.tif")},
                        {v1::RASTER_ROLE_SLOPE, ReadFile(terrain / "slope.tif")},
                        {v1::RASTER_ROLE_SOIL_CLASS, ReadFile(terrain / "soil_class.tif")}},
                       &job)
                    .ok());
    for (int i = 0; i < 600; ++i) {
      const v1::JobStatus s = GetJob(*stub, job.job_id()).status();
      if (s.tasks_total() > 0 && s.tasks_done() >= std::min<uint32_t>(10, s.tasks_total() / 3)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  const pid_t rank0 = PidOfRank(data, 0);
  const pid_t rank1 = PidOfRank(data, 1);
  ASSERT_GT(rank0, 0);
  ASSERT_GT(rank1, 0);
  fs::remove(endpoint_file);  // the next start writes a new one
  ASSERT_EQ(kill(rank1, SIGKILL), 0);

  // Open MPI takes the whole job down; the supervisor waits 2 s before it starts it again, time to
  // read what the killed run committed.
  for (int i = 0; i < 200 && kill(rank0, 0) == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_NE(kill(rank0, 0), 0) << "rank 0 went down with the job";
  const auto before = StoredCurves(data);
  ASSERT_GE(before.size(), 5u);

  const std::string endpoint = WaitForEndpoint(endpoint_file);
  ASSERT_NE(endpoint, "") << ReadFile(log);
  auto stub = v1::MobilityService::NewStub(grpc::CreateChannel(endpoint, grpc::InsecureChannelCredentials()));
  const v1::JobStatus end = WaitForEnd(*stub, job.job_id());
  ASSERT_EQ(end.state(), v1::JOB_STATE_DONE) << end.message() << "\n" << ReadFile(log);
  ASSERT_LT(before.size(), end.tasks_total()) << "the kill landed mid-job";
  EXPECT_EQ(end.cache_hits(), before.size());
  const auto summary = nlohmann::json::parse(GetJob(*stub, job.job_id()).summary_json());
  EXPECT_EQ(summary["tasks"]["computed"].get<size_t>(), end.tasks_total() - before.size());
  const auto after = StoredCurves(data);
  for (const auto& [key, computed_ms] : before) {
    ASSERT_TRUE(after.count(key));
    EXPECT_EQ(after.at(key), computed_ms) << "curve " << key << " recomputed";
  }
  EXPECT_EQ(NamesOf(DownloadAll(*stub, job.job_id())), MapProductNames());

  // SIGTERM to the supervisor drains the service and ends supervision.
  ASSERT_EQ(kill(supervisor, SIGTERM), 0);
  const int status = WaitExit(supervisor, std::chrono::seconds(60));
  EXPECT_NE(status, -1) << "the supervisor ends on SIGTERM";
  const std::string text = ReadFile(log);
  EXPECT_NE(text.find("restart 1 of at most 5 within 600 s, in 2 s"), std::string::npos) << text;
  EXPECT_NE(text.find("stopped by SIGTERM"), std::string::npos) << text;
  EXPECT_EQ(text.find("restart 2 of"), std::string::npos) << text;
  EXPECT_EQ(IntegrityCheck(data), "ok");
}

TEST(Supervise, ACrashLoopEndsSupervisionAndACleanExitIsNotRestarted) {
  ScratchDir dir("supervise-loop");
  const fs::path log = dir.path() / "log";
  const fs::path count = dir.path() / "starts";
  // Fails at once, every time: three restarts within the window, then the supervisor gives up.
  pid_t pid = Start(Supervisor() + " --max-restarts 3 --window-s 60 --backoff-s 0.1 -- sh -c 'echo x >> " +
                        count.string() + "; exit 3'",
                    log);
  EXPECT_EQ(WaitExit(pid, std::chrono::seconds(30)), 1);
  EXPECT_EQ(ReadFile(count), "x\nx\nx\nx\n") << "the first start and three restarts";
  EXPECT_NE(ReadFile(log).find("3 restarts within 60 s is a crash loop: giving up"), std::string::npos)
      << ReadFile(log);

  // The waits between restarts double: 0.1, 0.2, 0.4 s.
  EXPECT_NE(ReadFile(log).find("in 0.4 s"), std::string::npos) << ReadFile(log);

  pid = Start(Supervisor() + " -- true", log);
  EXPECT_EQ(WaitExit(pid, std::chrono::seconds(30)), 0);
  EXPECT_NE(ReadFile(log).find("true ended cleanly"), std::string::npos) << ReadFile(log);

  pid = Start(Supervisor() + " --backoff-s x -- true", log);
  EXPECT_EQ(WaitExit(pid, std::chrono::seconds(30)), 2);
  EXPECT_NE(ReadFile(log).find("--backoff-s must be a non-negative number (got 'x')"), std::string::npos);
}

}  // namespace
}  // namespace gonogo::testing
