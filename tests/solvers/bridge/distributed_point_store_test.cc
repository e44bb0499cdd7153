// The distributed point store for real: `mpirun -np 3` (CTest runs it so), group rank 0 driving,
// ranks 1 and 2 serving. Every test body runs on every rank: rank 0 checks, the others serve.
// Compared with the local store of the same model, bit for bit, through migrations, cut steps and
// a checkpoint read by a group whose ownership differs.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "solvers/bridge/distributed_point_store.h"
#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/material/point_store.h"
#include "solvers/material/registry.h"

namespace gonogo::bridge {
namespace {

using material::ConstitutiveModel;
using material::LocalPointStore;
using material::MaterialPointStore;
using material::MaterialState;
using material::Matrix3;
using material::PointHandle;
using material::TrialResponse;
using material::UpdateStatus;

int Rank() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int GroupSize() {
  int size = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

std::shared_ptr<const ConstitutiveModel> DruckerPrager() {
  material::MaterialRegistry registry;
  material::RegisterBuiltinMaterials(registry);
  return registry.Make("drucker-prager", {{"young_pa", 20e6},
                                          {"poisson", 0.3},
                                          {"cohesion_pa", 2e3},
                                          {"friction_angle_deg", 30},
                                          {"dilation_angle_deg", 5}});
}

// An elastic test model that costs what its increment asks: it spins for 2e5 us per unit of
// |dH|_max (so a point given large increments is expensive) and refuses |dH|_max > 0.5.
class CostlyElastic : public ConstitutiveModel {
 public:
  class State : public MaterialState {
   public:
    Matrix3 stress = Matrix3::Zero();
    std::unique_ptr<MaterialState> Clone() const override { return std::make_unique<State>(*this); }
    std::string Serialize() const override { return material::PackDoubles(stress.data(), 9); }
  };
  std::string Name() const override { return "costly-elastic"; }
  std::unique_ptr<MaterialState> InitialState() const override { return std::make_unique<State>(); }
  std::unique_ptr<MaterialState> RestoreState(const std::string& bytes) const override {
    auto state = std::make_unique<State>();
    const std::vector<double> values = material::UnpackDoubles(bytes, 9, "material.state");
    std::copy(values.begin(), values.end(), state->stress.data());
    return state;
  }
  std::vector<material::PointResponse> Update(const std::vector<material::PointIncrement>& batch,
                                              bool /*want_tangent*/) const override {
    return material::UpdateEachPoint(batch, [](const material::PointIncrement& increment) {
      material::PointResponse response;
      const double size = increment.displacement_gradient_increment.cwiseAbs().maxCoeff();
      if (size > 0.5) {
        response.reason = "increment too large for costly-elastic";
        return response;
      }
      const auto until = std::chrono::steady_clock::now() +
                         std::chrono::microseconds(static_cast<int>(2e5 * size));
      while (std::chrono::steady_clock::now() < until) {
      }
      auto state = std::make_unique<State>(static_cast<const State&>(*increment.committed));
      const Matrix3 strain = 0.5 * (increment.displacement_gradient_increment +
                                    increment.displacement_gradient_increment.transpose());
      state->stress += 1e6 * strain;
      response.stress_pa = state->stress;
      response.state = std::move(state);
      response.status = UpdateStatus::kOk;
      return response;
    });
  }
  material::ElasticModuli InitialElasticModuli() const override { return {1e6, 1e6}; }
};

bool SameBits(const Matrix3& a, const Matrix3& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * 9) == 0;
}

bool SameBits(const TrialResponse& a, const TrialResponse& b) {
  return a.status == b.status && a.reason == b.reason && SameBits(a.stress_pa, b.stress_pa) &&
         a.has_tangent == b.has_tangent &&
         std::memcmp(a.tangent_pa.data(), b.tangent_pa.data(), sizeof(double) * 36) == 0;
}

// Runs `body` on rank 0 with a link to the group and serves `model` on the others.
void OnGroup(const ConstitutiveModel& model,
             const std::function<void(std::shared_ptr<RankGroupLink>)>& body,
             const std::function<void(int)>& on_call = nullptr, int server_threads = 1) {
  if (Rank() != 0) {
    ServeRankGroup(MPI_COMM_WORLD, model, ServeOptions{server_threads}, on_call);
    return;
  }
  auto link = std::make_shared<RankGroupLink>(MPI_COMM_WORLD);
  body(link);
  link->Finish();
}

Matrix3 RandomIncrement(std::mt19937& random, double size) {
  std::uniform_real_distribution<double> uniform(-size, size);
  Matrix3 increment;
  for (int k = 0; k < 9; ++k) increment.data()[k] = uniform(random);
  return increment;
}

// Drives both stores through the same steps: some with a tangent, some cut (tried, discarded,
// tried again at half size), and checks every response and every committed state bit for bit.
void DriveSideBySide(MaterialPointStore& local, MaterialPointStore& distributed, int points,
                     int steps, double size, unsigned seed) {
  const std::vector<PointHandle> handles = local.Create(points);
  ASSERT_EQ(distributed.Create(points), handles);
  std::mt19937 random(seed);
  for (int step = 0; step < steps; ++step) {
    std::vector<Matrix3> increments;
    for (int p = 0; p < points; ++p) increments.push_back(RandomIncrement(random, size));
    const bool want_tangent = step % 3 == 0;
    if (step % 4 == 1) {  // a cut step
      local.TryUpdate(handles, increments, want_tangent);
      distributed.TryUpdate(handles, increments, want_tangent);
      local.Discard(handles);
      distributed.Discard(handles);
      for (Matrix3& increment : increments) increment *= 0.5;
    }
    const std::vector<TrialResponse> expected = local.TryUpdate(handles, increments, want_tangent);
    const std::vector<TrialResponse> got = distributed.TryUpdate(handles, increments, want_tangent);
    ASSERT_EQ(got.size(), expected.size());
    for (int p = 0; p < points; ++p) {
      ASSERT_TRUE(SameBits(got[p], expected[p])) << "step " << step << " point " << p;
    }
    local.Commit(handles);
    distributed.Commit(handles);
  }
  for (PointHandle handle : handles) {
    EXPECT_EQ(distributed.Serialize(handle), local.Serialize(handle)) << "point " << handle;
  }
}

TEST(DistributedPointStore, MatchesTheLocalStoreBitForBitThroughMigrations) {
  const auto model = DruckerPrager();
  OnGroup(*model, [&](std::shared_ptr<RankGroupLink> link) {
    BalanceOptions balance;
    balance.threshold = 0;  // any measured imbalance moves points: migrations nearly every step
    balance.cost_window_commits = 1;
    DistributedPointStore distributed(link, *model, balance);
    LocalPointStore local(*model);
    DriveSideBySide(local, distributed, 31, 40, 2e-4, 7);
    int moved = 0;
    for (const StepBalance& step : distributed.balance_history()) moved += step.points_moved;
    EXPECT_GT(moved, 0) << "the test meant to migrate points";
    // Every owning rank still holds points; all points accounted for.
    std::int64_t total = 0;
    for (std::int64_t count : distributed.PointsPerRank()) total += count;
    EXPECT_EQ(total, 31);
  });
}

// The DE RVE itself, with its contact histories, moved between ranks mid-path.
TEST(DistributedPointStore, RveStatesMoveBetweenRanksBitIdentically) {
  dem::rve::RveMaterialParams params;
  params.rve.grain_count = 100;
  params.rve.consolidation_pressure_pa = 100e3;
  params.min_steps_per_increment = 10;
  params.relax_steps = 10;
  // One consolidated template for every rank (generated once, broadcast as bytes).
  std::string template_bytes;
  if (Rank() == 0) template_bytes = dem::rve::Rve::Generate(params.rve).Save();
  long long length = static_cast<long long>(template_bytes.size());
  MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  template_bytes.resize(static_cast<std::size_t>(length));
  MPI_Bcast(template_bytes.data(), static_cast<int>(length), MPI_BYTE, 0, MPI_COMM_WORLD);
  const dem::rve::RveMaterial model(params, dem::rve::Rve::Restore(template_bytes));
  OnGroup(model, [&](std::shared_ptr<RankGroupLink> link) {
    BalanceOptions balance;
    balance.threshold = 0;
    balance.cost_window_commits = 1;
    DistributedPointStore distributed(link, model, balance);
    LocalPointStore local(model);
    DriveSideBySide(local, distributed, 5, 6, 2e-4, 11);
    int moved = 0;
    for (const StepBalance& step : distributed.balance_history()) moved += step.points_moved;
    EXPECT_GT(moved, 0);
  });
}

TEST(DistributedPointStore, MovesPointsOffTheRankThatMeasuresSlowest) {
  const CostlyElastic model;
  OnGroup(model, [&](std::shared_ptr<RankGroupLink> link) {
    BalanceOptions balance;
    balance.threshold = 0.3;
    balance.cost_window_commits = 1;
    DistributedPointStore store(link, model, balance);
    const int points = 12;
    const std::vector<PointHandle> handles = store.Create(points);
    // Round-robin: rank 1 owns 1, 4, 7, 10. Those four get expensive increments (20 ms each), the
    // rest cheap ones (0.1 ms): a contrast that preemption on a loaded machine does not hide.
    std::vector<Matrix3> increments;
    for (PointHandle h : handles) {
      ASSERT_EQ(store.Owner(h), static_cast<int>(h % GroupSize()));
      increments.push_back(Matrix3::Identity() * (h % GroupSize() == 1 ? 0.1 : 0.0005));
    }
    for (int step = 0; step < 3; ++step) {
      store.TryUpdate(handles, increments, false);
      store.Commit(handles);
    }
    const std::vector<StepBalance>& history = store.balance_history();
    ASSERT_EQ(history.size(), 3u);
    EXPECT_GT(history[0].imbalance, 0.5) << "rank 1 carries all the expensive points; seconds "
                                         << history[0].rank_seconds[0] << " "
                                         << history[0].rank_seconds[1] << " "
                                         << history[0].rank_seconds[2];
    EXPECT_GT(history[0].points_moved, 0);
    EXPECT_LT(history[0].imbalance_after, history[0].imbalance);
    EXPECT_LT(history[2].imbalance, 0.75 * history[0].imbalance)
        << "measured after the moves; seconds " << history[2].rank_seconds[0] << " "
        << history[2].rank_seconds[1] << " " << history[2].rank_seconds[2];
    EXPECT_GT(history[0].bytes_sent, 0);
    EXPECT_GT(history[0].bytes_received, 0);
  });
}

// What time slicing does to one step (a rank descheduled mid-step measures a slow step) must not
// move points; a cost that lasts the whole window must.
TEST(DistributedPointStore, OneSlowStepMovesNothingAWindowOfSlowStepsDoes) {
  const CostlyElastic model;
  OnGroup(model, [&](std::shared_ptr<RankGroupLink> link) {
    BalanceOptions balance;
    // Cheap points cost 4 ms and slow ones 50 ms, so that a timeslice lost on an oversubscribed
    // machine (a few ms) cannot double a rank's load, and the threshold of 1 sits between what
    // such losses can do and the slow rank's imbalance (200 against 16 + 16 ms: 1.6).
    balance.threshold = 1.0;
    balance.cost_window_commits = 5;
    DistributedPointStore store(link, model, balance);
    const std::vector<PointHandle> handles = store.Create(12);
    auto increments_with_rank_one = [&](double rank_one_size) {
      std::vector<Matrix3> increments;
      for (PointHandle h : handles) {
        increments.push_back(Matrix3::Identity() *
                             (store.Owner(h) == 1 ? rank_one_size : 0.02));
      }
      return increments;
    };
    // Commits 1-10 are two windows; commit 7 alone is slow on rank 1.
    for (int commit = 1; commit <= 10; ++commit) {
      store.TryUpdate(handles, increments_with_rank_one(commit == 7 ? 0.25 : 0.02), false);
      store.Commit(handles);
    }
    const std::vector<StepBalance>& history = store.balance_history();
    ASSERT_EQ(history.size(), 10u);
    EXPECT_GT(history[6].imbalance, 1.0) << "the slow step is measured as one";
    for (const StepBalance& step : history) EXPECT_EQ(step.points_moved, 0) << step.step;
    // Commits 11-15: rank 1 slow throughout; the window's end moves points off it.
    for (int commit = 11; commit <= 15; ++commit) {
      store.TryUpdate(handles, increments_with_rank_one(0.25), false);
      store.Commit(handles);
    }
    ASSERT_EQ(history.size(), 15u);
    for (int k = 10; k < 14; ++k) EXPECT_EQ(history[k].points_moved, 0) << k;
    EXPECT_GT(history[14].points_moved, 0);
    EXPECT_LT(history[14].imbalance_after, history[14].imbalance);
  });
}

TEST(DistributedPointStore, RemoteFailuresAndMisuseAreReportedAndChangeNothing) {
  const CostlyElastic model;
  OnGroup(model, [&](std::shared_ptr<RankGroupLink> link) {
    DistributedPointStore store(link, model, BalanceOptions{});
    const std::vector<PointHandle> handles = store.Create(6);
    std::vector<Matrix3> increments(6, Matrix3::Identity() * 1e-3);
    store.TryUpdate(handles, increments, false);
    store.Commit(handles);
    const std::string committed_remote = store.Serialize(4);  // on rank 1
    increments[4] = Matrix3::Identity() * 0.9;               // refused by the model on rank 1
    const std::vector<TrialResponse> trials = store.TryUpdate(handles, increments, false);
    EXPECT_EQ(trials[4].status, UpdateStatus::kFailed);
    EXPECT_NE(trials[4].reason.find("too large"), std::string::npos) << trials[4].reason;
    EXPECT_EQ(trials[3].status, UpdateStatus::kOk);
    EXPECT_THROW(store.Commit(handles), std::logic_error);
    store.Discard(handles);
    EXPECT_EQ(store.Serialize(4), committed_remote);
    EXPECT_THROW(store.TryUpdate({99}, {Matrix3::Zero()}, false), std::out_of_range);
    EXPECT_THROW(store.TryUpdate(handles, {Matrix3::Zero()}, false), std::invalid_argument);
    EXPECT_THROW(store.Restore(5, "not nine doubles"), InputError);
    EXPECT_EQ(store.Serialize(4), committed_remote);
    // The servers still serve after the errors.
    increments[4] = Matrix3::Identity() * 1e-3;
    for (const TrialResponse& trial : store.TryUpdate(handles, increments, false)) {
      EXPECT_EQ(trial.status, UpdateStatus::kOk);
    }
  });
}

TEST(DistributedPointStore, CheckpointIsReadBackUnderAnotherOwnership) {
  const auto model = DruckerPrager();
  std::string directory;
  if (Rank() == 0) {
    char pattern[] = "/tmp/gonogo_points_XXXXXX";
    directory = mkdtemp(pattern);
  }
  OnGroup(*model, [&](std::shared_ptr<RankGroupLink> link) {
    const int points = 10;
    std::mt19937 random(3);
    std::vector<std::vector<Matrix3>> path;
    for (int step = 0; step < 12; ++step) {
      path.emplace_back();
      for (int p = 0; p < points; ++p) path.back().push_back(RandomIncrement(random, 3e-4));
    }
    std::vector<TrialResponse> expected;
    {
      DistributedPointStore first(link, *model, BalanceOptions{});
      const std::vector<PointHandle> handles = first.Create(points);
      for (int step = 0; step < 12; ++step) {
        if (step == 2) first.WriteCheckpoint(directory, 1);
        if (step == 4) first.WriteCheckpoint(directory, 2);
        if (step == 6) first.WriteCheckpoint(directory, 3);  // removes generation 1
        expected = first.TryUpdate(handles, path[step], true);
        first.Commit(handles);
      }
    }
    EXPECT_FALSE(std::filesystem::exists(directory + "/points.1.0.bin")) << "the last two stay";
    EXPECT_FALSE(std::filesystem::exists(directory + "/points.1.manifest"));
    EXPECT_TRUE(std::filesystem::exists(directory + "/points.2.2.bin"));
    EXPECT_TRUE(std::filesystem::exists(directory + "/points.3.manifest"));
    BalanceOptions other;
    other.rank_zero_owns_points = false;  // every point on another rank than before
    DistributedPointStore second(link, *model, other);
    const std::vector<PointHandle> handles = second.Create(points);
    second.ReadCheckpoint(directory, 3);
    std::vector<TrialResponse> got;
    for (int step = 6; step < 12; ++step) {
      got = second.TryUpdate(handles, path[step], true);
      second.Commit(handles);
    }
    for (int p = 0; p < points; ++p) EXPECT_TRUE(SameBits(got[p], expected[p])) << p;

    // A damaged points file is refused and nothing is replaced.
    const std::string before = second.Serialize(3);
    {
      std::ofstream damage(directory + "/points.3.1.bin", std::ios::binary | std::ios::trunc);
      damage << "GNGPTS01 garbage";
    }
    EXPECT_THROW(second.ReadCheckpoint(directory, 3), InputError);
    EXPECT_THROW(second.ReadCheckpoint(directory, 1), InputError) << "removed";
    EXPECT_EQ(second.Serialize(3), before);
    DistributedPointStore wrong_size(link, *model, BalanceOptions{});
    wrong_size.Create(points + 1);
    EXPECT_THROW(wrong_size.ReadCheckpoint(directory, 2), InputError);
    // A local store reads the group's checkpoint and continues bit for bit.
    LocalPointStore local(*model);
    local.Create(points);
    local.ReadCheckpoint(directory, 2);
    EXPECT_EQ(local.Serialize(7), [&] {
      DistributedPointStore third(link, *model, BalanceOptions{});
      third.Create(points);
      third.ReadCheckpoint(directory, 2);
      return third.Serialize(7);
    }());
  });
  if (Rank() == 0) std::filesystem::remove_all(directory);
}

TEST(DistributedPointStore, CallRunsACollectiveOnEveryRankAtOnePoint) {
  const auto model = DruckerPrager();
  int calls_seen = 0;
  OnGroup(
      *model,
      [&](std::shared_ptr<RankGroupLink> link) {
        for (int code = 1; code <= 3; ++code) {
          link->Call(code);
          int sum = 0, mine = 0;
          MPI_Allreduce(&mine, &sum, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
          EXPECT_EQ(sum, code * (GroupSize() - 1));
        }
      },
      [&](int code) {
        ++calls_seen;
        int sum = 0;
        MPI_Allreduce(&code, &sum, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
      });
  if (Rank() != 0) {
    EXPECT_EQ(calls_seen, 3);
  }
}

}  // namespace
}  // namespace gonogo::bridge
