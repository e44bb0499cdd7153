// gonogo-bridge-bench [--rves N,...] [--grains G] [--steps S] [--warmup W] [--hot F,...]
//                     [--hot-factor X] [--balance on|off,...] [--threads T] [--csv] ...
//
// The FE-DE scale-bridging framework measured: a DistributedPointStore of N RVEs of the
// production material (SharedRveMaterial of the dem-hertz-mindlin defaults, G grains), driven
// from rank 0 as the FE rank drives it: per "FE step" one TryUpdate of every point with a small
// simple-shear increment (dH_xz, a fraction F of the points X times larger: the RVEs under the
// wheel) and one Commit. Run alone (a group of one) or under `mpirun -np K`: every rank of
// MPI_COMM_WORLD is in the group, rank 0 drives and owns a share, the others serve theirs. Prints
// figures only; not a test (README.md, "Benchmark").
//
// Per configuration (every combination of --rves, --hot and --balance; one row each):
//   step_s              wall seconds per FE step (TryUpdate + Commit, rebalancing included),
//                       mean over the S timed steps after W warm-up steps
//   rve_steps_s_core    N x DE steps per increment / step_s / cores, cores = min(K T, CPUs);
//                       DE steps per increment read from a cold and a hot point's RVE clock
//   rve_steps_cpu_s     the same RVE-steps over the CPU seconds every rank spent in the timed
//                       steps (getrusage, gathered through RankGroupLink::Call): the per-core
//                       figure less the waits and, on a loaded machine, less other programs' share
//   bytes_step          mean of StepBalance bytes_sent + bytes_received (the TryUpdate traffic of
//                       rank 0); link_bytes_step adds the Commit commands (migrated states go
//                       point to point and are counted in neither: moved x state_bytes)
//   state_bytes         Serialize().size() of a point's state after the run
//   rss_kb_rve          growth of rank 0's VmRSS over Create(N), per point rank 0 owns
//   imb_*               StepBalance imbalance (max / mean - 1 of the ranks' point seconds):
//                       mean over the timed steps up to commit --balance-every (before the first
//                       rebalance can happen) and after it; pred: the predicted imbalance_after of
//                       the last rebalance; moved: points migrated over the run
//
// Hot points are placed on one rank's points (rank 1's; rank 0's when alone), so balancing has
// work to do.
#include <CLI/CLI.hpp>
#include <malloc.h>
#include <mpi.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "solvers/bridge/distributed_point_store.h"
#include "solvers/common/cli_checks.h"
#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"

namespace {

using namespace gonogo;

struct Options {
  std::vector<int> rves = {64};
  int grains = 100;
  int steps = 20;
  int warmup = 2;
  double dh = 1e-5;
  std::vector<double> hot = {0.0};
  // 200: the hot points' 2e-3 takes about 190 rate-capped DE steps; at 20x (2e-4, 19 capped
  // steps) they would still take the 20 minimum steps and cost what the others cost.
  double hot_factor = 200;
  std::vector<std::string> balance = {"on"};
  double balance_threshold = 0.25;
  int balance_every = 10;
  int threads = 1;
  int min_de_steps = 20;
  int relax_steps = 50;
  double inertial_number = 1e-3;
  bool tangent = false;
  bool dedicated_fe = false;  // rank 0 owns no points
  bool csv = false;
  bool no_header = false;
};

// VmRSS of this process, kB (0 if unreadable).
double VmRssKb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) {
      std::istringstream fields(line.substr(6));
      double kb = 0;
      fields >> kb;
      return kb;
    }
  }
  return 0;
}

// CPU seconds of this process, every thread (user + system).
double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// The RankGroupLink::Call code on which every rank gathers its CPU seconds to rank 0.
constexpr int kCallGatherCpu = 1;

void GatherCpuOnServer() {
  double cpu = CpuSeconds();
  MPI_Gather(&cpu, 1, MPI_DOUBLE, nullptr, 0, MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

// Every rank's CPU seconds summed, on rank 0 (collective through the link).
double GroupCpuSeconds(bridge::RankGroupLink& link) {
  link.Call(kCallGatherCpu);
  double cpu = CpuSeconds();
  std::vector<double> all(static_cast<std::size_t>(link.size()), 0.0);
  MPI_Gather(&cpu, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  double sum = 0;
  for (double c : all) sum += c;
  return sum;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

struct Row {
  int ranks = 1, threads = 1, cores = 1;
  bool oversubscribed = false;
  int grains = 0, rves = 0, hot_count = 0, steps = 0;
  double hot = 0, hot_factor = 0;
  bool balance = false;
  int de_steps_cold = 0, de_steps_hot = 0;
  double step_s = 0, step_s_before = 0, step_s_after = 0;
  double rve_steps_s_core = 0;
  double cpu_s_step = 0;       // every rank's CPU seconds per timed step
  double rve_steps_cpu_s = 0;  // RVE-steps per CPU second of the whole group
  double bytes_step = 0, link_bytes_step = 0;
  std::size_t state_bytes = 0;
  double rss_kb_rve = 0;
  int rank0_points = 0;
  double imb_before = 0, imb_after = 0, imb_pred = 0;
  int moved = 0, rebalances = 0;
};

// DE steps a point took per increment: its RVE clock against the template's, over `increments`.
int DeStepsPerIncrement(const dem::rve::RveMaterial& material, const std::string& bytes,
                        int increments) {
  const std::unique_ptr<material::MaterialState> state = material.RestoreState(bytes);
  const auto* rve_state = dynamic_cast<const dem::rve::RveState*>(state.get());
  if (rve_state == nullptr) throw std::logic_error("not an RVE state");
  const double dt = material.initial().time_step_s();
  const double steps =
      (rve_state->rve().Snapshot().time_s - material.initial().Snapshot().time_s) / dt;
  return static_cast<int>(std::lround(steps / increments));
}

Row RunConfiguration(const Options& options, const dem::rve::RveMaterial& material,
                     const std::shared_ptr<bridge::RankGroupLink>& link, int rves, double hot,
                     bool balance_on) {
  Row row;
  row.ranks = link->size();
  row.threads = options.threads;
  const int cpus = std::max(1u, std::thread::hardware_concurrency());
  row.cores = std::min(row.ranks * row.threads, cpus);
  row.oversubscribed = row.ranks * row.threads > cpus;
  row.grains = options.grains;
  row.rves = rves;
  row.hot = hot;
  row.hot_factor = options.hot_factor;
  row.balance = balance_on;
  row.steps = options.steps;

  bridge::BalanceOptions balance;
  balance.enabled = balance_on;
  balance.threshold = options.balance_threshold;
  balance.cost_window_commits = options.balance_every;
  balance.rank_zero_owns_points = !options.dedicated_fe;
  balance.rank_zero_threads = options.threads;

  malloc_trim(0);
  const double rss_before_kb = VmRssKb();
  bridge::DistributedPointStore store(link, material, balance);
  const std::vector<material::PointHandle> handles = store.Create(rves);
  const double rss_after_kb = VmRssKb();
  const std::vector<std::int64_t> per_rank = store.PointsPerRank();
  row.rank0_points = static_cast<int>(per_rank[0]);
  row.rss_kb_rve = per_rank[0] > 0 ? (rss_after_kb - rss_before_kb) / per_rank[0] : 0;

  // Hot points: rank 1's (rank 0's when alone) first, then the others in handle order.
  const int hot_rank = row.ranks > 1 ? 1 : 0;
  row.hot_count = static_cast<int>(std::lround(hot * rves));
  std::vector<material::PointHandle> order;
  for (material::PointHandle h : handles) {
    if (store.Owner(h) == hot_rank) order.push_back(h);
  }
  for (material::PointHandle h : handles) {
    if (store.Owner(h) != hot_rank) order.push_back(h);
  }
  std::vector<char> is_hot(handles.size(), 0);
  for (int k = 0; k < row.hot_count; ++k) is_hot[order[k]] = 1;
  std::vector<material::Matrix3> increments(handles.size(), material::Matrix3::Zero());
  for (std::size_t k = 0; k < handles.size(); ++k) {
    increments[k](0, 2) = options.dh * (is_hot[k] ? options.hot_factor : 1.0);
  }

  std::vector<double> step_seconds;
  std::int64_t link_bytes_before = 0;
  double cpu_before = 0;
  const std::size_t history_before = store.balance_history().size();
  for (int step = 0; step < options.warmup + options.steps; ++step) {
    if (step == options.warmup) {
      cpu_before = GroupCpuSeconds(*link);
      link_bytes_before = link->bytes_sent() + link->bytes_received();
    }
    const auto start = std::chrono::steady_clock::now();
    const std::vector<material::TrialResponse> trials =
        store.TryUpdate(handles, increments, options.tangent);
    for (std::size_t k = 0; k < trials.size(); ++k) {
      if (trials[k].status != material::UpdateStatus::kOk) {
        throw std::runtime_error("point " + std::to_string(handles[k]) + " failed: " +
                                 trials[k].reason);
      }
    }
    store.Commit(handles);
    if (step >= options.warmup) step_seconds.push_back(Seconds(start));
  }
  const double link_bytes =
      static_cast<double>(link->bytes_sent() + link->bytes_received() - link_bytes_before);
  row.cpu_s_step = (GroupCpuSeconds(*link) - cpu_before) / options.steps;

  // Figures over the timed steps; "before" = steps up to commit balance_every (the first
  // rebalance can follow that commit), "after" = the rest.
  const std::vector<bridge::StepBalance>& history = store.balance_history();
  double sum = 0, sum_before = 0, sum_after = 0, bytes = 0, imb_before = 0, imb_after = 0;
  int n_before = 0, n_after = 0;
  for (int s = 0; s < options.steps; ++s) {
    const int commit = options.warmup + s + 1;  // 1-based FE step of this store
    const bridge::StepBalance& record = history[history_before + options.warmup + s];
    sum += step_seconds[s];
    bytes += static_cast<double>(record.bytes_sent + record.bytes_received);
    if (commit <= options.balance_every) {
      sum_before += step_seconds[s];
      imb_before += record.imbalance;
      ++n_before;
    } else {
      sum_after += step_seconds[s];
      imb_after += record.imbalance;
      ++n_after;
    }
  }
  for (std::size_t s = history_before; s < history.size(); ++s) {
    if (history[s].points_moved > 0) {
      row.moved += history[s].points_moved;
      ++row.rebalances;
      row.imb_pred = history[s].imbalance_after;
    }
  }
  row.step_s = sum / options.steps;
  row.step_s_before = n_before ? sum_before / n_before : NAN;
  row.step_s_after = n_after ? sum_after / n_after : NAN;
  row.imb_before = n_before ? imb_before / n_before : NAN;
  row.imb_after = n_after ? imb_after / n_after : NAN;
  if (row.rebalances == 0) row.imb_pred = NAN;
  row.bytes_step = bytes / options.steps;
  row.link_bytes_step = link_bytes / options.steps;

  // DE steps per increment from a cold and a hot point's clock (all points of a class start from
  // the same template and take the same increments, so they take the same steps).
  const int increments_applied = options.warmup + options.steps;
  material::PointHandle cold_point = -1, hot_point = -1;
  for (std::size_t k = 0; k < handles.size(); ++k) {
    if (is_hot[k] && hot_point < 0) hot_point = handles[k];
    if (!is_hot[k] && cold_point < 0) cold_point = handles[k];
  }
  if (cold_point >= 0) {
    const std::string bytes_cold = store.Serialize(cold_point);
    row.state_bytes = bytes_cold.size();
    row.de_steps_cold = DeStepsPerIncrement(material, bytes_cold, increments_applied);
  }
  if (hot_point >= 0) {
    const std::string bytes_hot = store.Serialize(hot_point);
    if (row.state_bytes == 0) row.state_bytes = bytes_hot.size();
    row.de_steps_hot = DeStepsPerIncrement(material, bytes_hot, increments_applied);
  }
  const double de_steps = static_cast<double>(rves - row.hot_count) * row.de_steps_cold +
                          static_cast<double>(row.hot_count) * row.de_steps_hot;
  row.rve_steps_s_core = de_steps / row.step_s / row.cores;
  row.rve_steps_cpu_s = de_steps / row.cpu_s_step;
  return row;
}

std::string Fixed(double value, int precision) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", precision, value);
  return text;
}

std::string Sci(double value) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, "%.3e", value);
  return text;
}

void PrintHeader(bool csv) {
  if (csv) {
    std::printf(
        "ranks,threads,cores,oversubscribed,grains,rves,hot,hot_count,hot_factor,balance,"
        "de_steps_cold,de_steps_hot,steps,step_s,step_s_before,step_s_after,rve_steps_s_core,"
        "cpu_s_step,rve_steps_cpu_s,"
        "bytes_step,link_bytes_step,state_bytes,rss_kb_rve,rank0_points,imb_before,imb_after,"
        "imb_pred,moved,rebalances\n");
  } else {
    std::printf("%5s %3s %5s %6s %5s %5s %4s %7s %9s %9s %9s %10s %10s %10s %10s %9s %8s %6s "
                "%6s %6s %5s\n",
                "ranks", "thr", "cores", "grains", "rves", "hot", "bal", "de_st", "step_s",
                "before_s", "after_s", "rvestep/sc", "rvestep/cs", "bytes/step", "link_b/st",
                "state_B", "rss_kB/r", "imb_b", "imb_a", "pred", "moved");
  }
  std::fflush(stdout);
}

void PrintRow(const Row& r, bool csv) {
  if (csv) {
    std::printf("%d,%d,%d,%d,%d,%d,%.3f,%d,%g,%s,%d,%d,%d,%.5f,%s,%s,%.4e,%.5f,%.4e,%.0f,%.0f,"
                "%zu,%.1f,%d,%s,%s,%s,%d,%d\n",
                r.ranks, r.threads, r.cores, r.oversubscribed ? 1 : 0, r.grains, r.rves, r.hot,
                r.hot_count, r.hot_factor, r.balance ? "on" : "off", r.de_steps_cold,
                r.de_steps_hot, r.steps, r.step_s, Fixed(r.step_s_before, 5).c_str(),
                Fixed(r.step_s_after, 5).c_str(), r.rve_steps_s_core, r.cpu_s_step,
                r.rve_steps_cpu_s, r.bytes_step,
                r.link_bytes_step, r.state_bytes, r.rss_kb_rve, r.rank0_points,
                Fixed(r.imb_before, 3).c_str(), Fixed(r.imb_after, 3).c_str(),
                Fixed(r.imb_pred, 3).c_str(), r.moved, r.rebalances);
  } else {
    const std::string de_steps = r.hot_count > 0 ? std::to_string(r.de_steps_cold) + "/" +
                                                       std::to_string(r.de_steps_hot)
                                                 : std::to_string(r.de_steps_cold);
    std::printf("%5d %3d %4d%s %6d %5d %5.2f %4s %7s %9.4f %9s %9s %10s %10s %10.0f %10.0f %9zu "
                "%8.1f %6s %6s %6s %5d\n",
                r.ranks, r.threads, r.cores, r.oversubscribed ? "*" : " ", r.grains, r.rves,
                r.hot, r.balance ? "on" : "off", de_steps.c_str(), r.step_s,
                Fixed(r.step_s_before, 4).c_str(), Fixed(r.step_s_after, 4).c_str(),
                Sci(r.rve_steps_s_core).c_str(), Sci(r.rve_steps_cpu_s).c_str(), r.bytes_step,
                r.link_bytes_step, r.state_bytes,
                r.rss_kb_rve, Fixed(r.imb_before, 3).c_str(), Fixed(r.imb_after, 3).c_str(),
                Fixed(r.imb_pred, 3).c_str(), r.moved);
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app(
      "The FE-DE scale-bridging framework measured: a DistributedPointStore of N RVEs driven from "
      "rank 0 as the FE rank drives it (one TryUpdate + Commit of every point per FE step). Alone "
      "or under mpirun -np K (rank 0 drives and owns a share, the others serve). Prints figures "
      "only; not a test.",
      "gonogo-bridge-bench");
  const CLI::Validator at_least_one = gonogo::cli_checks::AtLeastOne();
  app.add_option("--rves", options.rves, "RVEs N in the store (a list: one row each)")
      ->check(at_least_one)
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--grains", options.grains, "grains G per RVE (soil grains_per_rve, >= 100)")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--steps", options.steps, "timed FE steps S")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--warmup", options.warmup, "FE steps before the timed ones")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--dh", options.dh, "simple-shear increment dH_xz per FE step")
      ->check(gonogo::cli_checks::FiniteNumber(0))
      ->capture_default_str();
  app.add_option("--hot", options.hot,
                 "fraction of the points given hot-factor x dH, placed on rank 1's points first "
                 "(a list: one row each)")
      ->check(CLI::Range(0.0, 1.0))
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--hot-factor", options.hot_factor,
                 "hot points' increment over dH (at the default numerics 20 would still take the "
                 "minimum DE steps)")
      ->check(gonogo::cli_checks::FiniteNumber(1))
      ->capture_default_str();
  app.add_option("--balance", options.balance, "on or off (a list: one row each)")
      ->check(CLI::IsMember({"on", "off"}))
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--balance-threshold", options.balance_threshold,
                 "BalanceOptions::threshold (max / mean - 1 that triggers a rebalance)")
      ->check(gonogo::cli_checks::FiniteNumber(0))
      ->capture_default_str();
  app.add_option("--balance-every", options.balance_every,
                 "BalanceOptions::cost_window_commits: commits per cost window (also where imb_before ends)")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--threads", options.threads, "OpenMP threads per rank over its points")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--min-de-steps", options.min_de_steps, "DE steps at least per FE increment")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--relax-steps", options.relax_steps, "DE steps with the cell held after each")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--inertial-number", options.inertial_number, "DE strain-rate cap")
      ->check(gonogo::cli_checks::FiniteNumber(0))
      ->capture_default_str();
  app.add_flag("--tangent", options.tangent, "ask every point for its tangent");
  app.add_flag("--dedicated-fe", options.dedicated_fe, "rank 0 (the FE rank) owns no points");
  app.add_flag("--csv", options.csv, "machine-readable rows");
  app.add_flag("--no-header", options.no_header, "rows only");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int status = 0;
  try {
    // The production material: dem-hertz-mindlin defaults (seed 000) with G grains and the
    // bridge's numerics; every rank builds the same template.
    SoilParameters soil{dem::rve::kRveSoilModel,
                        {{"grains_per_rve", static_cast<double>(options.grains)}}};
    dem::rve::RveNumerics numerics;
    numerics.min_steps_per_increment = options.min_de_steps;
    numerics.relax_steps = options.relax_steps;
    numerics.max_inertial_number = options.inertial_number;
    const auto generate_start = std::chrono::steady_clock::now();
    const std::shared_ptr<const dem::rve::RveMaterial> material =
        dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(soil, numerics));
    const double generate_s = Seconds(generate_start);
    if (rank != 0) {
      const std::function<void(int)> on_call = [](int code) {
        if (code == kCallGatherCpu) GatherCpuOnServer();
      };
      bridge::ServeRankGroup(MPI_COMM_WORLD, *material, bridge::ServeOptions{options.threads},
                             on_call);
    } else {
      if (options.dedicated_fe && size < 2) {
        throw InputError("--dedicated-fe", "needs at least 2 ranks");
      }
      auto link = std::make_shared<bridge::RankGroupLink>(MPI_COMM_WORLD);
      const dem::rve::Rve& initial = material->initial();
      std::fprintf(stderr,
                   "gonogo-bridge-bench: %d rank(s) x %d thread(s), %d grains, template %.2f s, "
                   "dt %.3e s, quasi-static rate %.3f /s (%.3e strain per DE step)\n",
                   size, options.threads, options.grains, generate_s, initial.time_step_s(),
                   initial.StableRate1S(), initial.StableRate1S() * initial.time_step_s());
      if (!options.no_header) PrintHeader(options.csv);
      for (int rves : options.rves) {
        for (double hot : options.hot) {
          for (const std::string& balance : options.balance) {
            PrintRow(RunConfiguration(options, *material, link, rves, hot, balance == "on"),
                     options.csv);
          }
        }
      }
      link->Finish();
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "gonogo-bridge-bench: %s\n", e.what());
    status = 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gonogo-bridge-bench (rank %d): %s\n", rank, e.what());
    status = 1;
  }
  if (status != 0) MPI_Abort(MPI_COMM_WORLD, status);
  MPI_Finalize();
  return status;
}
