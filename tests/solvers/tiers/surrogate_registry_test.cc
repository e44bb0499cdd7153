// The fe-ann tier's model registry (solvers/tiers/surrogate_registry.h) on a real directory: models
// registered with their provenance, found, chosen by their held-out error, listed; ids refused
// when malformed or taken; what a crash mid-registration leaves is neither listed nor kept.
#include "solvers/tiers/surrogate_registry.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "solvers/common/errors.h"
#include "tests/solvers/ann/drucker_prager_paths.h"

namespace gonogo::tiers {
namespace {

namespace fs = std::filesystem;

// A small ensemble (seconds to train): what it answers does not matter here, only that it is one.
const ann::SurrogateEnsemble& Ensemble() {
  static const ann::SurrogateEnsemble* ensemble = [] {
    ann::MlpArchitecture architecture;
    architecture.hidden_widths = {8};
    ann::TrainingOptions options;
    options.epochs = 3;
    return new ann::SurrogateEnsemble(ann::SurrogateEnsemble::Train(
        {ann::testing::Path(ann::LabPath::kTriaxial, 30e3, 0.02)}, architecture, options));
  }();
  return *ensemble;
}

RegisteredSurrogate Record(const std::string& id, const std::string& soil, double worst_error,
                           std::int64_t created_unix_ms) {
  RegisteredSurrogate r;
  r.id = id;
  r.soil_name = soil;
  r.soil_parameters = "model=dem-hertz-mindlin;soil=" + soil;
  r.fe_de_preset = "tiny";
  r.architecture = "mlp-8-tanh-anchored";
  r.members = 3;
  r.data_hash = "0123456789abcdef";
  r.samples = 60;
  r.distance_threshold = 12.5;
  r.spread_threshold = 0.04;
  r.tensile_limit_pa = 12.0;
  r.least_principal_ratio = 0.25;
  r.held_out = {{"triaxial 14.1 kPa", worst_error / 2, {}}, {"rig point 1", worst_error, {}}};
  r.worst_held_out_error = worst_error;
  r.training_seconds = 1.5;
  r.training = "epochs=60 batch_size=64";
  r.code_version = "test";
  r.created_unix_ms = created_unix_ms;
  return r;
}

class SurrogateRegistryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("gonogo_registry_" + std::to_string(::getpid()));
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(SurrogateRegistryTest, RegistersFindsChoosesTheBestAndLists) {
  const SurrogateRegistry registry(root_.string());
  EXPECT_TRUE(registry.List().empty());  // no directory yet: no models, no error
  RegisteredSurrogate fine_tuned = Record("sand-a", "sand", 0.05, 1000);
  fine_tuned.fallback_paths = 7;
  fine_tuned.fallback_paths_share = 0.2;
  fine_tuned.walk_share = 0.6;
  // The floor under the triaxial's error: that path on two other packings of the RVE.
  fine_tuned.held_out[0].packings = {{2, 0.125}, {3, 0.0625}};
  const RegisteredSurrogate a = registry.Register(fine_tuned, Ensemble());
  registry.Register(Record("sand-b", "sand", 0.03, 2000), Ensemble());
  registry.Register(Record("sand-c", "sand", 0.03, 1500), Ensemble());
  registry.Register(Record("clay-a", "clay", 0.01, 3000), Ensemble());
  EXPECT_EQ(a.directory, (root_ / "sand-a").string());

  const std::optional<RegisteredSurrogate> described = registry.Describe("sand-a");
  ASSERT_TRUE(described.has_value());
  EXPECT_EQ(described->soil_parameters, "model=dem-hertz-mindlin;soil=sand");
  EXPECT_EQ(described->architecture, "mlp-8-tanh-anchored");
  EXPECT_EQ(described->samples, 60);
  EXPECT_EQ(described->training, "epochs=60 batch_size=64");
  EXPECT_EQ(described->fallback_paths, 7);
  EXPECT_EQ(described->fallback_paths_share, 0.2);
  EXPECT_EQ(described->walk_share, 0.6);
  EXPECT_EQ(registry.Describe("sand-b")->walk_share, 0);
  EXPECT_EQ(registry.Describe("sand-b")->fallback_paths, 0);
  EXPECT_EQ(described->distance_threshold, 12.5);
  EXPECT_EQ(described->tensile_limit_pa, 12.0);
  EXPECT_EQ(described->least_principal_ratio, 0.25);
  ASSERT_EQ(described->held_out.size(), 2u);
  EXPECT_EQ(described->held_out[0].path, "triaxial 14.1 kPa");
  EXPECT_EQ(described->held_out[1].replay_error, 0.05);
  ASSERT_EQ(described->held_out[0].packings.size(), 2u);
  EXPECT_EQ(described->held_out[0].packings[1].packing_seed, 3u);
  EXPECT_EQ(described->held_out[0].packings[1].difference, 0.0625);
  EXPECT_TRUE(described->held_out[1].packings.empty());
  EXPECT_TRUE(registry.Describe("sand-b")->held_out[0].packings.empty());
  // The registered files are the ensemble.
  const ann::SurrogateEnsemble loaded = ann::SurrogateEnsemble::Load(a.directory);
  EXPECT_EQ(loaded.size(), Ensemble().size());
  EXPECT_EQ(loaded.distance_threshold(), Ensemble().distance_threshold());

  // The best: the smallest worst error, the newest of equals; another soil or configuration not.
  EXPECT_EQ(registry.Best("model=dem-hertz-mindlin;soil=sand", "tiny")->id, "sand-b");
  EXPECT_EQ(registry.Best("model=dem-hertz-mindlin;soil=clay", "tiny")->id, "clay-a");
  EXPECT_FALSE(registry.Best("model=dem-hertz-mindlin;soil=sand", "default").has_value());
  EXPECT_FALSE(registry.Best("model=dem-hertz-mindlin;soil=silt", "tiny").has_value());

  const std::vector<RegisteredSurrogate> all = registry.List();
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].id, "clay-a");  // newest first
  EXPECT_EQ(all[3].id, "sand-a");
  EXPECT_EQ(registry.List("sand").size(), 3u);

  EXPECT_EQ(registry.NewId("seed000 sand", "mlp-8"), "seed000-sand-mlp-8-1");
  // An architecture that would make the id too long is named in its short form; one that even
  // then would is cut after a whole word (the record keeps the whole name).
  EXPECT_EQ(
      registry.NewId("seed000_sand_rve100", "mlp-128x128-tanh-anchored-pressure-scaled-3000pa"),
      "seed000_sand_rve100-mlp-128x128-anchored-ps3000pa-1");
  EXPECT_EQ(registry.NewId("seed000_sand_rve100",
                           "mlp-128x128-tanh-anchored-pressure-scaled-3000pa-carrying-"
                           "coordination_number+solid_fraction"),
            "seed000_sand_rve100-mlp-128x128-anchored-ps3000pa-cn-sf-1");
  EXPECT_EQ(registry.NewId("seed000_sand_rve100",
                           "mlp-128x128-tanh-anchored-hybrid-pressure-scaled-3000pa-carrying-"
                           "coordination_number"),
            "seed000_sand_rve100-mlp-128x128-anchored-hy-ps3000pa-cn-1");
  EXPECT_EQ(registry.NewId("seed000_sand_rve100",
                           "mlp-64x64x64x64x64x64-tanh-anchored-carrying-"
                           "fabric_xx+fabric_yy+fabric_zz+fabric_xy"),
            "seed000_sand_rve100-mlp-64x64x64x64x64x64-anchored-fxx-1");
  EXPECT_EQ(registry.NewId("seed000_sand_rve100", "mlp-128x128-tanh-anchored"),
            "seed000_sand_rve100-mlp-128x128-tanh-anchored-1")
      << "an id within the limit keeps the whole name";
  EXPECT_FALSE(registry.Find("no-such").has_value());
  EXPECT_FALSE(registry.Find("../sand-a").has_value());
}

TEST_F(SurrogateRegistryTest, BestJudgesAHeldOutErrorAgainstItsRvesOwnSpread) {
  const SurrogateRegistry registry(root_.string());
  const auto with_held_out = [](const std::string& id, std::vector<HeldOutResult> held_out,
                                std::int64_t created_unix_ms) {
    RegisteredSurrogate r = Record(id, "sand", 0, created_unix_ms);
    r.held_out = std::move(held_out);
    r.worst_held_out_error = 0;
    for (const HeldOutResult& path : r.held_out) {
      r.worst_held_out_error = std::max(r.worst_held_out_error, path.replay_error);
    }
    return r;
  };
  // No floor measured: the whole error (triaxial 0.0234375, rig point 0.046875).
  const RegisteredSurrogate plain = Record("sand-plain", "sand", 0.046875, 4000);
  // The walk within the median of its other packings (0.128125): the triaxial's error is what is
  // left.
  const RegisteredSurrogate floored = with_held_out(
      "sand-floored",
      {{"walk 3.5 kPa", 0.125, {{2, 0.1}, {3, 0.15625}}}, {"triaxial", 0.03125, {}}}, 3000);
  // As far beyond its floor, a smaller worst error: it wins the tie though older.
  const RegisteredSurrogate tied = with_held_out(
      "sand-tied", {{"walk 3.5 kPa", 0.09375, {{2, 0.125}}}, {"triaxial", 0.03125, {}}}, 1000);
  // The walk 0.0625 beyond its floor.
  const RegisteredSurrogate beyond = with_held_out(
      "sand-beyond", {{"walk 3.5 kPa", 0.25, {{2, 0.1875}}}, {"triaxial", 0.015625, {}}}, 2000);
  EXPECT_EQ(WorstErrorBeyondFloor(plain), 0.046875);
  EXPECT_EQ(WorstErrorBeyondFloor(floored), 0.03125);
  EXPECT_EQ(WorstErrorBeyondFloor(tied), 0.03125);
  EXPECT_EQ(WorstErrorBeyondFloor(beyond), 0.0625);
  // Within the furthest packing but beyond the median: judged by the median (0.09375).
  const RegisteredSurrogate past_median = with_held_out(
      "sand-past-median", {{"walk 3.5 kPa", 0.125, {{2, 0.5}, {3, 0.0625}, {4, 0.09375}}}}, 500);
  EXPECT_EQ(WorstErrorBeyondFloor(past_median), 0.03125);
  EXPECT_EQ(PackingFloor({{2, 0.5}, {3, 0.0625}, {4, 0.09375}, {5, 0.125}}), 0.109375);
  EXPECT_EQ(PackingFloor({}), 0);
  for (const RegisteredSurrogate& model : {plain, floored, beyond}) {
    registry.Register(model, Ensemble());
  }
  // Worst errors 0.047, 0.125, 0.25: the floored model is chosen, though its worst is not least.
  EXPECT_EQ(registry.Best("model=dem-hertz-mindlin;soil=sand", "tiny")->id, "sand-floored");
  registry.Register(tied, Ensemble());
  EXPECT_EQ(registry.Best("model=dem-hertz-mindlin;soil=sand", "tiny")->id, "sand-tied");

  // A record without held-out paths is judged by its worst error.
  RegisteredSurrogate bare = Record("sand-bare", "sand", 0.5, 5000);
  bare.held_out.clear();
  EXPECT_EQ(WorstErrorBeyondFloor(bare), 0.5);
}

TEST_F(SurrogateRegistryTest, RefusesMalformedAndTakenIds) {
  const SurrogateRegistry registry(root_.string());
  registry.Register(Record("taken", "sand", 0.05, 1000), Ensemble());
  for (const std::string& id : {std::string(""), std::string(".hidden"), std::string("a/b"),
                                std::string("with space"), std::string(65, 'x'),
                                std::string("taken")}) {
    try {
      registry.Register(Record(id, "sand", 0.05, 1000), Ensemble());
      ADD_FAILURE() << "id '" << id << "' was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "model.id") << id;
    }
  }
  EXPECT_EQ(registry.List().size(), 1u);
}

// A record written before a field existed reads as that field's "none": no fallback paths, no
// cap, no cone, no training line, no walk share.
TEST_F(SurrogateRegistryTest, ReadsARecordMadeBeforeItsLaterFields) {
  const SurrogateRegistry registry(root_.string());
  RegisteredSurrogate record = Record("old", "sand", 0.05, 1000);
  record.fallback_paths = 3;
  record.fallback_paths_share = 0.1;
  record.walk_share = 0.6;
  registry.Register(record, Ensemble());
  const fs::path file = root_ / "old" / "model.txt";
  std::ifstream in(file);
  std::string kept, line;
  int dropped = 0;
  while (std::getline(in, line)) {
    const bool later = line.rfind("fallback_paths", 0) == 0 ||
                       line.rfind("tensile_limit_pa", 0) == 0 ||
                       line.rfind("least_principal_ratio", 0) == 0 ||
                       line.rfind("training = ", 0) == 0 || line.rfind("walk_share = ", 0) == 0;
    dropped += later;
    if (!later) kept += line + "\n";
  }
  in.close();
  ASSERT_EQ(dropped, 6) << "the record's later fields were not where this test looks";
  std::ofstream(file) << kept;
  const std::optional<RegisteredSurrogate> old = registry.Describe("old");
  ASSERT_TRUE(old.has_value());
  EXPECT_EQ(old->fallback_paths, 0);
  EXPECT_EQ(old->fallback_paths_share, 0);
  EXPECT_EQ(old->walk_share, 0);
  EXPECT_TRUE(std::isinf(old->tensile_limit_pa));
  EXPECT_EQ(old->least_principal_ratio, 0);
  EXPECT_EQ(old->training, "");
  EXPECT_EQ(old->samples, 60);
}

// A packing's difference belongs to the held-out path on the line before it; one that names
// another path, or cannot be read, makes the record unreadable rather than misattributed.
TEST_F(SurrogateRegistryTest, RefusesAPackingDifferenceOfAnotherPath) {
  const SurrogateRegistry registry(root_.string());
  for (const std::string& line : {std::string("held_out_packing = 2 0.1 triaxial 99 kPa"),
                                  std::string("held_out_packing = two 0.1 rig point 1")}) {
    const std::string id = line.find("two") == std::string::npos ? "stray" : "unreadable";
    registry.Register(Record(id, "sand", 0.05, 1000), Ensemble());
    ASSERT_TRUE(registry.Describe(id).has_value());
    std::ofstream(root_ / id / "model.txt", std::ios::app) << line << "\n";
    EXPECT_FALSE(registry.Describe(id).has_value()) << line;
  }
  registry.Register(Record("kept", "sand", 0.05, 1000), Ensemble());
  std::ofstream(root_ / "kept" / "model.txt", std::ios::app)
      << "held_out_packing = 4 0.25 rig point 1\n";
  const std::optional<RegisteredSurrogate> kept = registry.Describe("kept");
  ASSERT_TRUE(kept.has_value());
  ASSERT_EQ(kept->held_out[1].packings.size(), 1u);
  EXPECT_EQ(kept->held_out[1].packings[0].difference, 0.25);
}

TEST_F(SurrogateRegistryTest, WhatACrashLeavesIsNeitherListedNorKept) {
  const SurrogateRegistry registry(root_.string());
  registry.Register(Record("whole", "sand", 0.05, 1000), Ensemble());
  fs::create_directories(root_ / ".half.registering.99");
  fs::create_directories(root_ / "no-record");
  fs::create_directories(root_ / "damaged");
  std::ofstream(root_ / "damaged" / "model.txt") << "# gonogo surrogate model 1\nid = damaged\n";
  ASSERT_EQ(registry.List().size(), 1u);
  EXPECT_FALSE(registry.Find("damaged").has_value());
  EXPECT_EQ(registry.CollectAbandoned(), 1);
  EXPECT_FALSE(fs::exists(root_ / ".half.registering.99"));
  EXPECT_TRUE(fs::exists(root_ / "whole"));
}

// A model's record says how its members were trained: the rollout term's weight only when the
// term is on, the training noise only when there is some, and how many histories the loss weighs
// other than 1.
TEST(TrainingText, NamesTheOptionsThatShapedTheMembers) {
  ann::TrainingOptions options;
  options.epochs = 300;
  options.batch_size = 64;
  options.learning_rate = 0.003;
  options.seed = 7;
  EXPECT_EQ(TrainingText(options),
            "epochs=300 batch_size=64 learning_rate=0.003 seed=7 path_stress_weighting=0 "
            "rollout_steps=0 weighted_histories=0");
  options.path_stress_weighting = 0.5;
  options.rollout_steps = 20;
  options.rollout_weight = 0.1;
  options.history_weights = {1.0, 2.5, 1.0, 0.25};
  EXPECT_EQ(TrainingText(options),
            "epochs=300 batch_size=64 learning_rate=0.003 seed=7 path_stress_weighting=0.5 "
            "rollout_steps=20 rollout_weight=0.1 weighted_histories=2");
  options.stress_noise = 0.02;
  options.noise_correction = 0.5;
  EXPECT_EQ(TrainingText(options),
            "epochs=300 batch_size=64 learning_rate=0.003 seed=7 path_stress_weighting=0.5 "
            "rollout_steps=20 rollout_weight=0.1 stress_noise=0.02 noise_correction=0.5 "
            "weighted_histories=2");
}

}  // namespace
}  // namespace gonogo::tiers
