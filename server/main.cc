// gonogo-server: the map service.
//
//   gonogo-server --data-dir DIR --listen HOST:PORT            one process, in-process worker threads
//   mpirun -np N gonogo-server --data-dir DIR --listen ...     rank 0 serves, ranks 1..N-1 compute
//
// Port 0 picks a free port; the chosen endpoint is printed ("listening on HOST:PORT") and, with
// --endpoint-file, written to that file (mode 0600) for clients on a cluster.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <mpi.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "cache/database.h"
#include "server/job_manager.h"
#include "server/mpi_pool.h"
#include "server/service.h"
#include "server/thread_pool.h"
#include "solvers/tiers/builtin_tiers.h"
#include "solvers/tiers/diagnostic_tiers.h"

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
  bool diagnostic_tiers = false;
};

void Usage(std::ostream& out) {
  out << "usage: gonogo-server [--data-dir DIR] [--listen HOST:PORT] [--endpoint-file PATH]\n"
         "                     [--threads N] [--max-cells N] [--max-jobs N] [--task-delay-ms MS]\n"
         "                     [--diagnostic-tiers]\n"
         "  --data-dir DIR       SQLite database and job files (default ./gonogo-data)\n"
         "  --listen HOST:PORT   gRPC address; port 0 picks a free port (default 127.0.0.1:50051)\n"
         "  --endpoint-file P    write the bound HOST:PORT to P (mode 0600)\n"
         "  --threads N          in-process worker threads when not under MPI (default: cores)\n"
         "  --max-cells N        largest raster, input or output, in cells (default 25000000)\n"
         "  --max-jobs N         map jobs that run at once (default 2)\n"
         "  --task-delay-ms MS   delay every traction task (fault-injection tests and demos)\n"
         "  --diagnostic-tiers   also serve the diagnostic tiers (rank-group and failure probes)\n"
         "Under mpirun or srun, rank 0 serves and ranks 1..N-1 compute traction tasks.\n";
}

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "gonogo-server: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--data-dir") o.data_dir = value();
      else if (a == "--listen") o.listen = value();
      else if (a == "--endpoint-file") o.endpoint_file = value();
      else if (a == "--threads") o.threads = std::stoi(value());
      else if (a == "--task-delay-ms") o.task_delay_ms = static_cast<uint32_t>(std::stoul(value()));
      else if (a == "--max-cells") o.max_cells = std::stoll(value());
      else if (a == "--max-jobs") o.max_jobs = std::stoi(value());
      else if (a == "--diagnostic-tiers") o.diagnostic_tiers = true;
      else if (a == "--help" || a == "-h") {
        Usage(std::cout);
        std::exit(0);
      } else {
        std::cerr << "gonogo-server: unknown option " << a << "\n";
        Usage(std::cerr);
        std::exit(2);
      }
    } catch (const std::logic_error&) {
      std::cerr << "gonogo-server: " << a << " needs a number\n";
      std::exit(2);
    }
  }
  return o;
}

int Serve(const Options& o, const gonogo::TierRegistry& tiers, gonogo::server::WorkerPool& pool,
          const sigset_t& signals) {
  using namespace gonogo;
  std::filesystem::create_directories(o.data_dir);
  cache::Database db((std::filesystem::path(o.data_dir) / "gonogo.sqlite").string());

  server::JobManagerConfig config;
  config.data_dir = o.data_dir;
  config.task_delay_ms = o.task_delay_ms;
  config.limits.max_input_cells = o.max_cells;
  config.limits.max_output_cells = o.max_cells;
  config.max_concurrent_jobs = o.max_jobs;
  cache::CurveStore curves(db);
  server::CurveResolver resolver(curves, pool);
  server::JobManager jobs(config, db, tiers, resolver);
  const int resumed = jobs.ResumeUnfinished();
  server::MobilityServiceImpl service(jobs, db, tiers, resolver, server::ServiceLimits{});

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(o.listen, grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&service);
  builder.SetMaxReceiveMessageSize(8 << 20);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    std::cerr << "gonogo-server: cannot listen on " << o.listen << "\n";
    return 1;
  }
  server->GetHealthCheckService()->SetServingStatus(kServiceName, true);
  server->GetHealthCheckService()->SetServingStatus("", true);
  jobs.Start();

  const std::string host = o.listen.substr(0, o.listen.rfind(':'));
  const std::string endpoint = host + ":" + std::to_string(port);
  if (!o.endpoint_file.empty()) {
    const std::string tmp = o.endpoint_file + ".tmp";
    {
      std::ofstream f(tmp);
      f << endpoint << "\n";
    }
    chmod(tmp.c_str(), 0600);
    std::filesystem::rename(tmp, o.endpoint_file);
  }
  std::cout << "gonogo-server listening on " << endpoint << " (pid " << getpid() << ", " << pool.Describe()
            << ", tiers:";
  for (const auto& n : tiers.Names()) std::cout << " " << n;
  std::cout << ", data " << o.data_dir << ", " << resumed << " jobs resumed)" << std::endl;

  // SIGTERM / SIGINT drain: refuse new work, report NOT_SERVING, stop the scheduler (the running
  // job returns to QUEUED), then stop gRPC and the pool.
  int sig = 0;
  sigwait(&signals, &sig);
  std::cout << "gonogo-server: signal " << sig << ", draining" << std::endl;
  service.SetDraining();
  server->GetHealthCheckService()->SetServingStatus(kServiceName, false);
  server->GetHealthCheckService()->SetServingStatus("", false);
  jobs.Drain();
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
  pool.Shutdown();
  std::cout << "gonogo-server: stopped" << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = Parse(argc, argv);
  // Signals are taken by sigwait in Serve(); every thread created later inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  gonogo::TierRegistry tiers;
  gonogo::RegisterBuiltinTiers(tiers);
  if (options.diagnostic_tiers) gonogo::RegisterDiagnosticTiers(tiers);

  if (!gonogo::server::LaunchedUnderMpi()) {
    const int threads =
        options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
    gonogo::server::ThreadPool pool(tiers, threads);
    try {
      return Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      std::cerr << "gonogo-server: " << e.what() << "\n";
      return 1;
    }
  }

  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int rc = 0;
  if (rank > 0) {
    gonogo::server::RunMpiWorker(tiers, rank);
  } else if (provided < MPI_THREAD_SERIALIZED) {
    std::cerr << "gonogo-server: MPI lacks MPI_THREAD_SERIALIZED\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  } else if (size == 1) {
    gonogo::server::ThreadPool pool(tiers, options.threads > 0 ? options.threads : 2);
    try {
      rc = Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      std::cerr << "gonogo-server: " << e.what() << "\n";
      rc = 1;
    }
  } else {
    gonogo::server::MpiPool pool(size);
    try {
      rc = Serve(options, tiers, pool, signals);
    } catch (const std::exception& e) {
      std::cerr << "gonogo-server: " << e.what() << "\n";
      pool.Shutdown();  // releases the worker ranks so that MPI_Finalize can complete
      rc = 1;
    }
  }
  MPI_Finalize();
  return rc;
}
