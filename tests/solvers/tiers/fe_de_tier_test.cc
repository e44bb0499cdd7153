// The fe-de tier for real under `mpirun -np 3` (CTest runs it so): the same curve, bit for bit,
// computed alone on rank 0 (on one thread, and on two over which its RVEs spread), on a group of 2
// ranks and on a group of 3 with load balancing that migrates RVEs mid-run and 2 threads on one
// rank; cancellation stops the whole group.
#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "solvers/common/errors.h"
#include "solvers/rig/wheel_rig.h"
#include "solvers/tiers/fe_de_tier.h"
#include "tests/solvers/tiers/fe_de_test_configuration.h"

namespace gonogo::tiers {
namespace {

int WorldRank() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}


TractionRequest Request() {
  TractionRequest request;
  request.soil.soil_name = "seed000_sand_rve100";
  request.tyre.diameter_m = 0.5;
  request.tyre.width_m = 0.2;
  request.tyre.section_height_m = 0.1;
  request.wheel_load_n = 1000;
  request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
  return request;
}

// The tiny configuration's curve computed alone (the first test's; computed on demand).
TractionCurve* reference_curve = nullptr;

bool SameBits(const TractionCurve& a, const TractionCurve& b) {
  if (a.points.size() != b.points.size() || a.immobile_reason != b.immobile_reason) return false;
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    if (std::memcmp(&a.points[k], &b.points[k], sizeof(TractionPoint)) != 0) return false;
  }
  return true;
}

// Runs the tier on `communicator` (MPI_COMM_NULL: alone) on the ranks that belong to it;
// `points_moved` (if given) receives the RVEs migrated during the run (group rank 0's count).
TractionCurve RunOn(const FeDeTier& tier, MPI_Comm communicator, int threads,
                    int* points_moved = nullptr) {
  ComputeContext context;
  context.communicator = communicator;
  context.threads = threads;
  const auto start = std::chrono::steady_clock::now();
  const FeDeRunReport report = tier.Run(Request(), context);
  if (points_moved != nullptr) *points_moved = report.PointsMoved();
  if (WorldRank() == 0) {
    std::cout << "  fe-de curve in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
              << " s, " << report.PointsMoved() << " RVEs migrated\n";
    // The rig's records come with the curve, the whole run's (settling 0.15 s, rolling 0.1 s,
    // the 0.2 s ramp: a record every 5 ms), and filtered again they give the curve's bits.
    rig::RigRun run;
    run.samples = report.samples;
    EXPECT_GE(run.samples.size(), 85u);
    EXPECT_TRUE(!run.samples.empty() && run.samples.back().phase == 4);
    TractionCurve filtered_again;
    filtered_again.points = rig::CurveFromRun(run, Request().slips, 0.25);
    EXPECT_TRUE(SameBits(filtered_again, report.curve));
  }
  return report.curve;
}

TEST(FeDeTier, SameCurveBitForBitAloneAndOnTwoAndThreeRanks) {
  const int rank = WorldRank();
  FeDeOptions options = TinyFeDeOptions();
  // Any measured imbalance moves points, and a rebalance is considered every 10 commits: the
  // runs cross migrations whatever this machine's timings (a 5 % threshold over 50-commit
  // windows left a quiet machine with none).
  options.balance.threshold = 0;
  options.balance.cost_window_commits = 10;
  const FeDeTier tier(options);

  TractionCurve alone, alone_on_two_threads;
  int alone_rve_threads = 0;
  if (rank == 0) {
    alone = RunOn(tier, MPI_COMM_NULL, 1);
    // Alone on two threads: the RVEs themselves spread over them (the tier's RVE, handed to a
    // stand-in that answers with it unchanged), to the same bits.
    ComputeContext context;
    context.threads = 2;
    alone_on_two_threads = tier.RunWithStandIn(
                                   Request(),
                                   [&](std::shared_ptr<const dem::rve::RveMaterial> rve) {
                                     alone_rve_threads = rve->params().batch_threads;
                                     return PointStandIn{rve, {}};
                                   },
                                   context)
                               .curve;
  }
  MPI_Barrier(MPI_COMM_WORLD);

  MPI_Comm pair = MPI_COMM_NULL;
  MPI_Comm_split(MPI_COMM_WORLD, rank < 2 ? 0 : MPI_UNDEFINED, rank, &pair);
  TractionCurve on_two;
  int moved_on_two = 0, moved_on_three = 0;
  if (pair != MPI_COMM_NULL) {
    on_two = RunOn(tier, pair, rank == 1 ? 2 : 1, &moved_on_two);
    MPI_Comm_free(&pair);
  }
  MPI_Barrier(MPI_COMM_WORLD);

  const TractionCurve on_three = RunOn(tier, MPI_COMM_WORLD, 1, &moved_on_three);
  if (rank != 0) return;
  // The group runs must cross migrations for the comparison to cover them.
  EXPECT_GT(moved_on_two + moved_on_three, 0);
  ASSERT_EQ(alone.points.size(), 5u) << alone.immobile_reason;
  reference_curve = new TractionCurve(alone);
  EXPECT_TRUE(SameBits(on_two, alone));
  EXPECT_TRUE(SameBits(on_three, alone));
  EXPECT_EQ(alone_rve_threads, 2);
  EXPECT_TRUE(SameBits(alone_on_two_threads, alone));
  for (const TractionPoint& p : alone.points) {
    std::cout << "  s " << p.slip << " D " << p.drawbar_pull_n << " N, T " << p.torque_nm
              << " N m, z " << p.sinkage_m << " m\n";
  }
}

// The pool's collective cancellation: every member asks, the group agrees (logical or). Rank 2
// wants out at its third check; the whole group stops there, every rank with CancelledError, the
// leader's carrying the rig's records up to the stop (rig::StoppedRunError).
TEST(FeDeTier, ACancelOnOneRankStopsTheWholeGroupAtTheSameCheck) {
  const int rank = WorldRank();
  const FeDeTier tier(TinyFeDeOptions());
  int checks = 0;
  ComputeContext context;
  context.communicator = MPI_COMM_WORLD;
  context.cancelled = [&]() {
    ++checks;
    int mine = rank == 2 && checks >= 3 ? 1 : 0;
    int any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    return any != 0;
  };
  const auto start = std::chrono::steady_clock::now();
  try {
    tier.Compute(Request(), context);
    ADD_FAILURE() << "rank " << rank << " was not stopped";
  } catch (const rig::StoppedRunError& stopped) {
    EXPECT_EQ(rank, 0) << "only the leader runs the rig";
    ASSERT_FALSE(stopped.samples().empty());
    for (std::size_t k = 1; k < stopped.samples().size(); ++k) {
      EXPECT_GT(stopped.samples()[k].time_s, stopped.samples()[k - 1].time_s);
    }
    EXPECT_EQ(stopped.samples().front().phase, 1) << "the records from the run's start";
  } catch (const CancelledError&) {
    EXPECT_NE(rank, 0) << "the leader's stop carries no records";
  }
  EXPECT_EQ(checks, 3) << "rank " << rank;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 60) << "three checks 20 FE steps apart, after the RVE templates";
  // The group is usable again at once.
  int one = 1, sum = 0;
  MPI_Allreduce(&one, &sum, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(sum, 3);
}

// A run stopped mid-curve (here cancelled after its checkpoints, as a crash or a drain stops it)
// resumes from its checkpoint directory on a group of another size, to the same curve bit for bit
// as the uninterrupted run.
TEST(FeDeTier, ResumesFromItsCheckpointOnAnotherGroupToTheSameCurve) {
  const int rank = WorldRank();
  FeDeOptions options = TinyFeDeOptions();
  options.checkpoint_every_s = 0;  // at every poll (20 FE steps)
  const FeDeTier tier(options);
  if (rank == 0 && reference_curve == nullptr) {
    reference_curve = new TractionCurve(RunOn(FeDeTier(TinyFeDeOptions()), MPI_COMM_NULL, 1));
  }
  char path[64] = "/tmp/gonogo_fe_de_resume_XXXXXX";
  if (rank == 0) {
    ASSERT_NE(mkdtemp(path), nullptr);
  }
  MPI_Bcast(path, sizeof path, MPI_CHAR, 0, MPI_COMM_WORLD);

  int checks = 0;
  ComputeContext first;
  first.communicator = MPI_COMM_WORLD;
  first.checkpoint_dir = path;
  first.cancelled = [&]() {  // stop at the 20th poll, about 400 of the run's 900 FE steps
    ++checks;
    int mine = rank == 0 && checks >= 20 ? 1 : 0;
    int any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    return any != 0;
  };
  EXPECT_THROW(tier.Compute(Request(), first), CancelledError);
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0) {
    for (const char* file : {"/rig.state", "/points.19.manifest", "/points.19.2.bin",
                             "/points.18.manifest"}) {
      EXPECT_TRUE(std::filesystem::exists(std::string(path) + file)) << file;
    }
    EXPECT_FALSE(std::filesystem::exists(std::string(path) + "/points.17.manifest"));
  }

  MPI_Comm pair = MPI_COMM_NULL;
  MPI_Comm_split(MPI_COMM_WORLD, rank < 2 ? 0 : MPI_UNDEFINED, rank, &pair);
  if (pair != MPI_COMM_NULL) {
    ComputeContext second;
    second.communicator = pair;
    second.checkpoint_dir = path;
    FeDeOptions no_more = TinyFeDeOptions();
    no_more.checkpoint_every_s = 1e9;
    const auto start = std::chrono::steady_clock::now();
    const TractionCurve resumed = FeDeTier(no_more).Compute(Request(), second);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    MPI_Comm_free(&pair);
    if (rank == 0) {
      std::cout << "  resumed run: " << seconds << " s\n";
      ASSERT_NE(reference_curve, nullptr);
      EXPECT_TRUE(SameBits(resumed, *reference_curve));
      std::filesystem::remove_all(path);
    }
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

}  // namespace
}  // namespace gonogo::tiers
