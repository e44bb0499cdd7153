// gonogo-server: the map service.
//
//   gonogo-server --data-dir DIR --listen HOST:PORT            one process, in-process worker threads
//   mpirun -np N gonogo-server --data-dir DIR --listen ...     rank 0 serves, ranks 1..N-1 compute
//   gonogo-server --help                                        every option, with its default
//
// Port 0 picks a free port; the chosen endpoint is printed ("listening on HOST:PORT") and, with
// --endpoint-file, written to that file (mode 0600) for clients on a cluster, with the generated
// token on its second line under --generate-token.
//
// Transport and identity (server/identity.h): plaintext is for loopback addresses; a network
// address needs tokens, and TLS (--tls-cert, --tls-key) unless --allow-plaintext-network says
// otherwise. Everything the server writes is private to its user (umask 077, data directory 0700).
#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <mpi.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "cache/database.h"
#include "server/fallback_paths.h"
#include "server/identity.h"
#include "server/job_manager.h"
#include "server/mpi_pool.h"
#include "server/service.h"
#include "server/thread_pool.h"
#include "solvers/tiers/builtin_tiers.h"
#include "solvers/tiers/diagnostic_tiers.h"
#include "solvers/tiers/surrogate_registry.h"

namespace {

constexpr char kServiceName[] = "gonogo.v1.MobilityService";

struct Options {
  std::string data_dir = "gonogo-data";
  std::string listen = "127.0.0.1:50051";
  std::string endpoint_file;
  int threads = 0;  // 0: one per core
  uint32_t task_delay_ms = 0;
  int64_t max_cells = 25'000'000;
  int max_jobs = 2;
  int64_t max_upload_mib = 512;
  int64_t max_upload_chunks = 8192;
  double curve_timeout_s = 1800;
  double stream_stall_s = 60;
  bool private_curves = false;
  double keep_jobs_days = 30;
  double keep_jobs_gib = 50;
  int64_t max_tasks_per_job = 50'000;
  int max_queued_jobs = 1'000;
  int max_queued_per_identity = 100;
  int max_rpc_threads = 64;
  bool diagnostic_tiers = false;
  std::string log_level = "info";
  std::string token_file;
  bool generate_token = false;
  std::string tls_cert, tls_key, tls_client_ca;
  bool allow_plaintext_network = false;
  gonogo::BuiltinTierOptions tier_options;
};

// Parses the command line with CLI11: an unknown or mistyped option, a missing value or one out of
// range is an error (exit 2) that names it.
Options Parse(int argc, char** argv) {
  Options o;
  CLI::App app{
      "gonogo-server: the off-road mobility map service.\n"
      "Under mpirun or srun, rank 0 serves and ranks 1..N-1 compute traction tasks; without a\n"
      "launcher the tasks run on threads of this process.",
      "gonogo-server"};
  app.option_defaults()->always_capture_default();
  app.add_option("--data-dir", o.data_dir, "SQLite database and job files");
  app.add_option("--listen", o.listen, "gRPC address HOST:PORT; port 0 picks a free port");
  app.add_option("--endpoint-file", o.endpoint_file, "write the bound HOST:PORT to this file (mode 0600)");
  app.add_option("--threads", o.threads, "in-process worker threads when not under MPI (0: one per core)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-cells", o.max_cells, "largest raster, input or output, in cells")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-jobs", o.max_jobs, "map and curve jobs that run at once")
      ->check(CLI::Range(1, 64));
  app.add_option("--max-upload-mib", o.max_upload_mib, "largest upload of one map job, all rasters together, MiB")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 20));
  app.add_option("--max-upload-chunks", o.max_upload_chunks,
                 "most messages in one upload, empty ones included")
      ->check(CLI::Range(int64_t{16}, int64_t{1} << 30));
  app.add_option("--max-tasks-per-job", o.max_tasks_per_job,
                 "most traction curves one map may need (terrain units x axles)")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 40));
  app.add_option("--max-queued-jobs", o.max_queued_jobs, "most QUEUED jobs, all identities together")
      ->check(CLI::Range(1, 1 << 30));
  app.add_option("--max-queued-per-identity", o.max_queued_per_identity, "most QUEUED jobs of one identity")
      ->check(CLI::Range(1, 1 << 30));
  app.add_option("--max-rpc-threads", o.max_rpc_threads,
                 "most calls served at once (open streams included); beyond it a call gets "
                 "RESOURCE_EXHAUSTED")
      ->check(CLI::Range(4, 1 << 16));
  app.add_flag("--private-curves", o.private_curves,
               "keep each identity's traction curves to itself (by default curves are physics, "
               "shared by every identity through the cache)");
  app.add_option("--keep-jobs-days", o.keep_jobs_days,
                 "ended jobs older than this are deleted (their curves stay cached); 0: kept")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--keep-jobs-gib", o.keep_jobs_gib,
                 "beyond this much job files (inputs, products), ended jobs are deleted oldest first; 0: no limit")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--stream-stall-s", o.stream_stall_s,
                 "an upload or download that moves nothing for this long is cancelled, s")
      ->check(CLI::Range(0.1, 86400.0));
  app.add_option("--curve-timeout-s", o.curve_timeout_s,
                 "longest a GetTractionCurve or RunScalability call waits for the pool, s")
      ->check(CLI::Range(1.0, 86400.0));
  app.add_option("--task-delay-ms", o.task_delay_ms,
                 "delay every traction task by this many ms (fault-injection tests and demos)");
  app.add_option("--fe-de-preset", o.tier_options.fe_de_preset,
                 "fe-de configuration: default (seed 001 procedure, R/4 mesh; hours), ci (coarse "
                 "and short; minutes) or tiny (ci cut to 0.45 s; under a minute)")
      ->check(CLI::IsMember({"default", "ci", "tiny"}));
  app.add_option("--ranks-per-task", o.tier_options.fe_de_ranks,
                 "MPI ranks of one fe-de task (the FE rank and RVE servers; capped at the workers)")
      ->check(CLI::Range(1, 4096));
  app.add_option("--fe-de-threads", o.tier_options.fe_de_threads,
                 "OpenMP threads per rank of an fe-de task")
      ->check(CLI::Range(1, 1024));
  app.add_option("--fe-de-checkpoint-s", o.tier_options.fe_de_checkpoint_every_s,
                 "wall seconds between checkpoints of a running fe-de curve (FE state and every "
                 "RVE, under DATA_DIR/checkpoints; a restarted server resumes from them)")
      ->check(CLI::Range(0.0, 86400.0));
  app.add_option("--fe-ann-distance-threshold", o.tier_options.fe_ann_distance_threshold,
                 "fe-ann: Mahalanobis distance from a model's training inputs beyond which a point "
                 "is flagged (and falls back to its RVE); 0: each model's own (gonogo models)")
      ->check(CLI::Range(0.0, 1e12));
  app.add_option("--fe-ann-spread-threshold", o.tier_options.fe_ann_spread_threshold,
                 "fe-ann: relative spread of a model's members beyond which a point is flagged; "
                 "0: each model's own")
      ->check(CLI::Range(0.0, 1e12));
  app.add_option(
         "--fe-ann-pressure-floor-kpa",
         [&o](const CLI::results_t& values) {
           o.tier_options.fe_ann_pressure_floor_pa = 1e3 * std::stod(values.front());
           return true;
         },
         "fe-ann: mean compression below which a point is flagged (the network not trusted "
         "there), kPa; 0: no floor")
      ->type_name("KPA")
      ->check(CLI::Range(0.0, 1e9));
  auto* fe_ann_return = app.add_option("--fe-ann-return-after-steps", o.tier_options.fe_ann_return_after_steps,
                 "fe-ann: a fallen-back point returns to the network after this many FE steps in "
                 "a row that would not have been flagged; 0: it stays on its RVE")
      ->check(CLI::Range(0, 1000000));
  app.add_flag("--fe-ann-no-fallback{false}", o.tier_options.fe_ann_fallback,
               "fe-ann: a flagged point stays on the network (counted in the run's provenance) "
               "instead of falling back to its RVE")
      ->excludes(fe_ann_return);
  app.add_flag("--diagnostic-tiers", o.diagnostic_tiers,
               "also serve the diagnostic tiers (rank-group, failure and slow-curve probes)");
  app.add_option("--token-file", o.token_file,
                 "bearer tokens, one 'TOKEN IDENTITY [admin]' per line; the file must be private "
                 "(mode 0600)")
      ->check(CLI::ExistingFile);
  auto* generate = app.add_flag(
      "--generate-token", o.generate_token,
      "generate a token for the user running the server (an admin identity) and write it to the "
      "endpoint file's second line");
  auto* endpoint_file = app.get_option("--endpoint-file");
  generate->needs(endpoint_file);
  auto* cert = app.add_option("--tls-cert", o.tls_cert, "serve TLS with this PEM certificate (chain)")
                   ->check(CLI::ExistingFile);
  auto* key = app.add_option("--tls-key", o.tls_key, "the PEM private key of --tls-cert")
                  ->check(CLI::ExistingFile);
  cert->needs(key);
  key->needs(cert);
  app.add_option("--tls-client-ca", o.tls_client_ca,
                 "require client certificates signed by this PEM CA (with --tls-cert)")
      ->check(CLI::ExistingFile)
      ->needs(cert);
  app.add_flag("--allow-plaintext-network", o.allow_plaintext_network,
               "allow plaintext on a non-loopback --listen address (tokens then cross the network "
               "unencrypted)");
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error or off (logs go to stderr)")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e) == 0 ? 0 : 2);  // --help: 0; any usage error: 2, as the other programs
  }
  // The fe-ann tier's models live in the data directory, which every rank reads (as checkpoints).
  o.tier_options.models_dir = (std::filesystem::path(o.data_dir) / "models").string();
  return o;
}

std::string ReadWholeFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(what + " " + path + ": cannot be read");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// How the server is reached and who may call: the credentials to listen with, and the words the
// banner says it in. Throws std::runtime_error naming the option when the combination would expose
// the service: a network address with no tokens, or in plaintext without --allow-plaintext-network.
struct Transport {
  std::shared_ptr<grpc::ServerCredentials> credentials;
  std::string description;
};

Transport ChooseTransport(const Options& o, const gonogo::server::Authenticator& auth) {
  using gonogo::server::IsLoopbackHost;
  const std::string host = o.listen.substr(0, o.listen.rfind(':'));
  const bool loopback = IsLoopbackHost(host);
  const bool tls = !o.tls_cert.empty();
  if (!loopback && !auth.required()) {
    throw std::runtime_error("--listen " + o.listen +
                             " is not a loopback address: a server other hosts can reach needs "
                             "--token-file or --generate-token");
  }
  if (!loopback && !tls && !o.allow_plaintext_network) {
    throw std::runtime_error("--listen " + o.listen +
                             " is not a loopback address: serve TLS (--tls-cert, --tls-key) or "
                             "accept plaintext with --allow-plaintext-network");
  }
  Transport t;
  if (tls) {
    grpc::SslServerCredentialsOptions ssl(
        o.tls_client_ca.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
    if (!o.tls_client_ca.empty()) ssl.pem_root_certs = ReadWholeFile(o.tls_client_ca, "--tls-client-ca");
    ssl.pem_key_cert_pairs.push_back(
        {ReadWholeFile(o.tls_key, "--tls-key"), ReadWholeFile(o.tls_cert, "--tls-cert")});
    t.credentials = grpc::SslServerCredentials(ssl);
    t.description = o.tls_client_ca.empty() ? "TLS" : "TLS with client certificates";
  } else {
    t.credentials = grpc::InsecureServerCredentials();
    t.description = loopback ? "plaintext on loopback"
                             : "PLAINTEXT on a network address: tokens cross the network unencrypted";
  }
  t.description += auth.required()
                       ? ", bearer tokens for " + std::to_string(auth.identity_count()) + " identities"
                       : ", no tokens: every user of this host can connect";
  return t;
}

// Writes "HOST:PORT\n" and, when there is one, "TOKEN\n" to `path`, created with mode 0600 (never
// readable by anyone else, not even between creation and a chmod) and renamed into place whole.
void WriteEndpointFile(const std::string& path, const std::string& endpoint, const std::string& token) {
  const std::string tmp = path + ".tmp";
  unlink(tmp.c_str());
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error("--endpoint-file " + path + ": cannot be created");
  const std::string text = endpoint + "\n" + (token.empty() ? "" : token + "\n");
  const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  close(fd);
  if (!written) throw std::runtime_error("--endpoint-file " + path + ": cannot be written");
  std::filesystem::rename(tmp, path);
}

// The data directory and the database: private to the service's user whatever they were created
// with (files made later are private through the umask set in main()).
void MakePrivate(const std::filesystem::path& data_dir) {
  std::filesystem::create_directories(data_dir);
  if (chmod(data_dir.c_str(), 0700) != 0) {
    throw std::runtime_error("--data-dir " + data_dir.string() + ": cannot be made private (chmod 0700)");
  }
  for (const char* name : {"gonogo.sqlite", "gonogo.sqlite-wal", "gonogo.sqlite-shm"}) {
    const auto path = data_dir / name;
    if (std::filesystem::exists(path)) chmod(path.c_str(), 0600);
  }
}

// One server per data directory: two would resume the same jobs and write the same products. An
// exclusive flock on DATA_DIR/gonogo.lock, held for the process's life (the kernel drops it when
// the process ends, however it ends); the file names the holder for the error a second server
// gives. Linux NFS clients implement flock with NFS locks, so this also holds across the nodes of a
// cluster; on a file system without locks (Lustre mounted without -o flock) it warns and goes on.
class DataDirLock {
 public:
  explicit DataDirLock(const std::string& data_dir) {
    const std::string path = (std::filesystem::path(data_dir) / "gonogo.lock").string();
    fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (fd_ < 0) throw std::runtime_error("--data-dir " + data_dir + ": cannot create " + path);
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      if (errno == EWOULDBLOCK) {
        char holder[256] = {0};
        const ssize_t n = pread(fd_, holder, sizeof holder - 1, 0);
        std::string who(holder, n > 0 ? static_cast<size_t>(n) : 0);
        while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
        close(fd_);
        throw std::runtime_error("--data-dir " + data_dir + " is in use by another gonogo-server (" +
                                 (who.empty() ? "unknown" : who) +
                                 "): one server per data directory; stop it or choose another directory");
      }
      spdlog::warn("--data-dir {}: the file system does not lock files ({}); make sure no other "
                   "gonogo-server uses this directory", data_dir, std::strerror(errno));
      return;
    }
    char host[256] = {0};
    gethostname(host, sizeof host - 1);
    const std::string who = "pid " + std::to_string(getpid()) + " on " + host + "\n";
    if (ftruncate(fd_, 0) != 0 || pwrite(fd_, who.data(), who.size(), 0) < 0) {
      spdlog::warn("--data-dir {}: cannot write the lock file's holder", data_dir);
    }
  }
  ~DataDirLock() {
    if (fd_ >= 0) close(fd_);  // releases the lock
  }
  DataDirLock(const DataDirLock&) = delete;
  DataDirLock& operator=(const DataDirLock&) = delete;

 private:
  int fd_ = -1;
};

int Serve(const Options& o, const gonogo::TierRegistry& tiers, gonogo::server::WorkerPool& pool,
          const sigset_t& signals) {
  using namespace gonogo;
  server::Authenticator authenticator;
  if (!o.token_file.empty()) authenticator.LoadTokenFile(o.token_file);
  std::string generated_token;
  if (o.generate_token) {
    generated_token = server::GenerateToken();
    authenticator.AddToken(generated_token, {server::ProcessUserName(), true});
  }
  const Transport transport = ChooseTransport(o, authenticator);
  MakePrivate(o.data_dir);
  const DataDirLock data_dir_lock(o.data_dir);
  cache::Database db((std::filesystem::path(o.data_dir) / "gonogo.sqlite").string());

  server::JobManagerConfig config;
  config.data_dir = o.data_dir;
  config.task_delay_ms = o.task_delay_ms;
  config.limits.max_input_cells = o.max_cells;
  config.limits.max_output_cells = o.max_cells;
  config.max_concurrent_jobs = o.max_jobs;
  config.max_tasks_per_job = o.max_tasks_per_job;
  config.keep_jobs_days = o.keep_jobs_days;
  config.share_curves = !o.private_curves;
  config.keep_jobs_bytes = static_cast<int64_t>(o.keep_jobs_gib * (1LL << 30));
  config.max_queued_jobs = o.max_queued_jobs;
  config.max_queued_jobs_per_identity = o.max_queued_per_identity;
  config.fe_de_preset = o.tier_options.fe_de_preset;
  config.models_dir = o.tier_options.models_dir;
  cache::CurveStore curves(db);
  server::CurveResolver resolver(curves, pool);
  // Restart files of long curves (fe-de); the worker ranks read them too, so under MPI the data
  // directory must be on a file system they share.
  resolver.set_checkpoint_root((std::filesystem::path(o.data_dir) / "checkpoints").string());
  // An fe-ann curve's fallback paths join its soil's dataset (gonogo train --fallback-paths-share).
  resolver.set_training_history_keeper(
      [&db, preset = o.tier_options.fe_de_preset,
       rve_version = tiers.Find("fe-de") ? tiers.Find("fe-de")->Version() : std::string()](
          const gonogo::TractionTier&, const gonogo::server::CurveTask& task,
          const gonogo::server::TaskResult& result) {
        const int kept = server::KeepFallbackPaths(db, preset, rve_version, task, result);
        if (kept > 0) {
          spdlog::info("kept {} fallback paths of curve {} for training", kept, task.key);
        }
      });
  server::JobManager jobs(config, db, tiers, resolver);
  const int orphans = jobs.CollectOrphanUploads();
  if (orphans > 0) spdlog::info("removed the files of {} uploads that never became a job", orphans);
  const int resumed = jobs.ResumeUnfinished();
  server::ServiceLimits limits;
  limits.max_upload_bytes = o.max_upload_mib << 20;
  limits.curve_timeout_ms = static_cast<int>(o.curve_timeout_s * 1000);
  limits.max_upload_chunks = o.max_upload_chunks;
  limits.stream_stall_ms = static_cast<int>(o.stream_stall_s * 1000);
  server::MobilityServiceImpl service(jobs, db, tiers, resolver, authenticator, limits,
                                     o.tier_options.models_dir);
  const int abandoned = tiers::SurrogateRegistry(o.tier_options.models_dir).CollectAbandoned();
  if (abandoned > 0) spdlog::warn("removed {} unfinished model registrations", abandoned);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(o.listen, transport.credentials, &port);
  builder.RegisterService(&service);
  builder.SetMaxReceiveMessageSize(8 << 20);
  // Every call the synchronous server serves holds a thread, an open stream too: bounded, so that
  // held-open streams cannot take the process's threads without end.
  grpc::ResourceQuota quota("gonogo-server");
  quota.SetMaxThreads(o.max_rpc_threads);
  builder.SetResourceQuota(quota);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    spdlog::error("cannot listen on {}", o.listen);
    return 1;
  }
  // Health stays NOT_SERVING until every worker rank has checked in (below); jobs queue meanwhile.
  server->GetHealthCheckService()->SetServingStatus(kServiceName, false);
  server->GetHealthCheckService()->SetServingStatus("", false);
  jobs.Start();

  const std::string host = o.listen.substr(0, o.listen.rfind(':'));
  const std::string endpoint = host + ":" + std::to_string(port);
  if (!o.endpoint_file.empty()) WriteEndpointFile(o.endpoint_file, endpoint, generated_token);
  std::cout << "gonogo-server listening on " << endpoint << " (pid " << getpid() << ", " << pool.Describe()
            << ", tiers:";
  for (const auto& n : tiers.Names()) std::cout << " " << n;
  std::cout << ", data " << o.data_dir << ", " << resumed << " jobs resumed; " << transport.description
            << ")" << std::endl;

  // SERVING once every worker is ready (at once for threads; under MPI when each rank has checked
  // in), unless a signal comes first.
  int sig = 0;
  if (pool.ReadyWorkers() < pool.Workers()) {
    spdlog::info("waiting for {} worker ranks to check in", pool.Workers() - pool.ReadyWorkers());
  }
  const timespec tick{0, 100'000'000};
  while (sig <= 0 && pool.ReadyWorkers() < pool.Workers()) sig = sigtimedwait(&signals, nullptr, &tick);
  if (sig <= 0) {
    server->GetHealthCheckService()->SetServingStatus(kServiceName, true);
    server->GetHealthCheckService()->SetServingStatus("", true);
    spdlog::info("SERVING: {} of {} workers ready", pool.ReadyWorkers(), pool.Workers());
    sigwait(&signals, &sig);
  }
  // SIGTERM / SIGINT drain: refuse new work, report NOT_SERVING, stop the scheduler (the running
  // job returns to QUEUED), then stop gRPC and the pool.
  spdlog::info("signal {}: draining", sig);
  service.SetDraining();
  server->GetHealthCheckService()->SetServingStatus(kServiceName, false);
  server->GetHealthCheckService()->SetServingStatus("", false);
  const auto drain_start = std::chrono::steady_clock::now();
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  jobs.Drain();
  const double drain_s = seconds_since(drain_start);
  // Calls still in flight (a download, a watcher) get a second, then are cancelled: a drain is
  // over within about a second whatever the jobs.
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
  const double calls_s = seconds_since(drain_start);
  pool.Shutdown();
  spdlog::info("stopped: jobs drained in {:.2f} s, calls ended in {:.2f} s, pool stopped in {:.2f} s",
               drain_s, calls_s, seconds_since(drain_start));
  return 0;
}

}  // namespace

// Logs go to stderr ("[time] [level] [rank N] message"); stdout carries only the banner line that
// scripts and tests read the endpoint from.
void SetUpLogging(const std::string& level, const std::string& who) {
  auto logger = spdlog::stderr_color_mt("gonogo-server");
  logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] [" + who + "] %v");
  logger->set_level(spdlog::level::from_str(level));
  spdlog::set_default_logger(logger);
}

int main(int argc, char** argv) {
  // Under an MPI launcher several ranks share the cores: OpenMP threads that spin while they wait
  // (libgomp's default) would take them from the other ranks. libgomp reads OMP_WAIT_POLICY when
  // it is loaded, before main, so the process starts itself again with the variable set.
  if (gonogo::server::LaunchedUnderMpi() && std::getenv("OMP_WAIT_POLICY") == nullptr) {
    setenv("OMP_WAIT_POLICY", "passive", 1);
    execv("/proc/self/exe", argv);  // returns only on failure: go on with the default policy
  }
  const Options options = Parse(argc, argv);
  // Whatever the caller's umask, what the server writes (database, inputs, products, checkpoints,
  // models, the endpoint file) is readable by the service's user only.
  umask(077);
  // Signals are taken by sigwait in Serve(); every thread created later inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  gonogo::TierRegistry tiers;
  gonogo::RegisterBuiltinTiers(tiers, options.tier_options);
  if (options.diagnostic_tiers) gonogo::RegisterDiagnosticTiers(tiers);

  if (!gonogo::server::LaunchedUnderMpi()) {
    SetUpLogging(options.log_level, "server");
    const int threads =
        options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
    gonogo::server::ThreadPool pool(tiers, threads);
    try {
      return Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      spdlog::critical("{}", e.what());
      return 1;
    }
  }

  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  SetUpLogging(options.log_level, "rank " + std::to_string(rank));
  int rc = 0;
  if (rank > 0) {
    gonogo::server::RunMpiWorker(tiers, rank);
  } else if (provided < MPI_THREAD_SERIALIZED) {
    spdlog::critical("MPI lacks MPI_THREAD_SERIALIZED");
    MPI_Abort(MPI_COMM_WORLD, 1);
  } else if (size == 1) {
    gonogo::server::ThreadPool pool(tiers, options.threads > 0 ? options.threads : 2);
    try {
      rc = Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      spdlog::critical("{}", e.what());
      rc = 1;
    }
  } else {
    gonogo::server::MpiPool pool(size);
    try {
      rc = Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      spdlog::critical("{}", e.what());
      pool.Shutdown();  // releases the worker ranks so that MPI_Finalize can complete
      rc = 1;
    }
  }
  MPI_Finalize();
  return rc;
}
