// The fe-ann tier on the fe-de tier's test configuration: a surrogate trained on the soil's own
// RVE by the recipe (surrogate_training.h), its curve against the fe-de curve of the same rig and
// mesh, and the fallback: with every input flagged, every point is answered by its RVE, and the
// curve is the fe-de curve bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "solvers/ann/stress_surrogate.h"
#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/tiers/empirical_tier.h"
#include "solvers/tiers/fe_ann_tier.h"
#include "solvers/tiers/soil_catalogue.h"
#include "solvers/tiers/surrogate_training.h"
#include "tests/solvers/tiers/fe_de_test_configuration.h"

namespace gonogo::tiers {
namespace {

constexpr char kSoil[] = "seed000_sand_rve100";

TractionRequest Request() {
  TractionRequest request;
  request.soil.soil_name = kSoil;
  request.tyre.diameter_m = 0.5;
  request.tyre.width_m = 0.2;
  request.tyre.section_height_m = 0.1;
  request.wheel_load_n = 1000;
  request.slips = {0.0, 0.25, 0.5, 0.75, 1.0};
  return request;
}

std::string SoilText() {
  return CanonicalText(BuiltinSoilCatalogue().Find(kSoil, dem::rve::kRveSoilModel)->parameters);
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

bool SameBits(const TractionCurve& a, const TractionCurve& b) {
  if (a.points.size() != b.points.size() || a.immobile_reason != b.immobile_reason) return false;
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    if (std::memcmp(&a.points[k], &b.points[k], sizeof(TractionPoint)) != 0) return false;
  }
  return true;
}

// Each slip's drawbar pull, torque and sinkage of fe-ann beside fe-de's: the figures the README
// quotes.
void PrintSideBySide(const TractionCurve& ann_curve, const TractionCurve& de_curve) {
  for (std::size_t k = 0; k < ann_curve.points.size(); ++k) {
    const TractionPoint& ann = ann_curve.points[k];
    const TractionPoint& de = de_curve.points[k];
    std::cout << "  s " << ann.slip << ": D " << ann.drawbar_pull_n << " (fe-de "
              << de.drawbar_pull_n << ") N, T " << ann.torque_nm << " (" << de.torque_nm
              << ") N m, z " << 1e3 * ann.sinkage_m << " (" << 1e3 * de.sinkage_m << ") mm\n";
  }
}

// The recipe of this file's models: 40-step paths of the soil's RVE at the tiny preset's
// numerics, `walks` random walks, 3 x MLP 64 x 64 carrying `carried` internal variables of the
// RVE, 200 epochs.
SurrogateRecipe TinyRecipe(int walks, const std::vector<std::string>& carried = {}) {
  SurrogateRecipe recipe;
  recipe.steps = 40;
  recipe.walks = walks;
  recipe.architecture.carried_variables = carried;
  recipe.training.epochs = 200;
  recipe.threads = 2;
  return recipe;
}

TrainedSurrogate TrainOnTheSoilsRve(const SurrogateRecipe& recipe) {
  const SoilParameters soil =
      BuiltinSoilCatalogue().Find(kSoil, dem::rve::kRveSoilModel)->parameters;
  return TrainSurrogateOnRve(soil, TinyFeDeOptions(), recipe);
}

// `ensemble` saved in `directory` and listed as the soil's one model of the tiny configuration.
std::shared_ptr<const SurrogateModelSource> SavedAsTheOnlyModel(
    const ann::SurrogateEnsemble& ensemble, const std::string& directory, const std::string& id) {
  ensemble.Save(directory + "/model");
  SurrogateModelRecord record;
  record.id = id;
  record.directory = directory + "/model";
  record.soil_parameters = SoilText();
  record.fe_de_preset = "tiny";
  return std::make_shared<ListedSurrogateModels>(std::vector<SurrogateModelRecord>{record});
}

// One model and one fe-de curve for the whole suite. The model carries the RVE's coordination
// number (stress_surrogate.h): the same recipe's network carrying nothing was 3.9 % of W off
// fe-de's curve below, and 8.9 % of rW on the scaled tyre (solvers/ann/README.md, "Carrying the
// coordination number").
class FeAnnTierTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char path[] = "/tmp/gonogo_fe_ann_XXXXXX";
    ASSERT_NE(mkdtemp(path), nullptr);
    directory_ = new std::string(path);
    const TrainedSurrogate trained = TrainOnTheSoilsRve(TinyRecipe(12, {"coordination_number"}));
    EXPECT_EQ(trained.ensemble.member(0).architecture(),
              "mlp-64x64-tanh-anchored-carrying-coordination_number");
    std::cout << "  model: " << trained.samples << " samples, paths " << trained.generation_seconds
              << " s, training " << trained.training_seconds << " s; held-out errors:";
    for (const HeldOutResult& result : trained.held_out_errors) {
      std::cout << " " << result.path << " " << 100 * result.replay_error << " %;";
    }
    std::cout << "\n";
    models_ = new std::shared_ptr<const SurrogateModelSource>(
        SavedAsTheOnlyModel(trained.ensemble, *directory_, "test-model"));

    const auto start = std::chrono::steady_clock::now();
    fe_de_ = new FeDeRunReport(FeDeTier(TinyFeDeOptions()).Run(Request(), {}));
    fe_de_seconds_ = Seconds(start);
    std::cout << "  fe-de curve: " << fe_de_seconds_ << " s, " << fe_de_->elements
              << " elements, " << fe_de_->fe_steps << " FE steps\n";
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*directory_);
    delete directory_;
    delete models_;
    delete fe_de_;
  }
  static FeAnnOptions Options() {
    FeAnnOptions options;
    options.fe_de = TinyFeDeOptions();
    return options;
  }

  static std::string* directory_;
  static std::shared_ptr<const SurrogateModelSource>* models_;
  static FeDeRunReport* fe_de_;
  static double fe_de_seconds_;
};

std::string* FeAnnTierTest::directory_ = nullptr;
std::shared_ptr<const SurrogateModelSource>* FeAnnTierTest::models_ = nullptr;
FeDeRunReport* FeAnnTierTest::fe_de_ = nullptr;
double FeAnnTierTest::fe_de_seconds_ = 0;

// One model meets both of the measures on the laboratory paths: the held-out paths and
// the curve against fe-de. Not held here: its held-out paths of the rig's points, replayed
// open-loop 1.6 and 16.7 % off where the RVE's other packings differ by 1.7 and 6.5 %, and 1.6 and
// 16.6 % as the tier answers their points (ReplayGuarded), the guard flagging no step of either
// (solvers/ann/README.md, "One model for both").
//
// Held-out paths (ReplayError: the ensemble replays each path from its initial stress on its own
// answers, admissible stresses included; the mean |sigma error| over the path's mean |sigma|): a
// triaxial, a simple shear and an unload-reload between the training pressures, and four random
// walks of seeds not trained on, at 3.5, 14, 28 and 57 kPa. Each is held to the 5 %, or
// where the soil's RVE cannot be told apart from itself at 5 %, to its floor: the median of the
// same path's differences on 16 other packings of the RVE (PackingFloor; seeds 2-17, run here).
// Measured floors: triaxial 20 %, simple shear 27.6 %, unload-reload 8.8 %, walks at 14 / 28 / 57 /
// 3.5 kPa 7.8 / 5.9 / 3.6 / 15.1 %.
//
// The curve: the fe-ann tier with this model against fe-de on the test's rig at 1,000 N, whose
// points' paths four of the training paths are, and at 1,500 N, a load it has no path of; within
// 5 % of W, of rW and of r at every slip.
//
// The model: 96 training walks carrying 60 % of the loss, 3 x MLP 128 x 128 pressure-scaled at
// 3 kPa carrying the coordination number, the rig's four paths, training seed 2, at its own
// thresholds (the spread's kSpreadThresholdFactor). Measured (solvers/ann/README.md, "One model
// for both"): held out 2.71 / 1.63 / 2.44 %, walks 5.99 / 3.84 / 4.35 / 10.42 %; the curve 2.69 %
// of W and 3.06 % of rW at 1,000 N, 4.09 / 4.08 % at 1,500 N. Training seed 1 of the same recipe
// meets both too (walks 6.66 / 4.86 / 4.71 / 13.53 %, the curve 2.30 / 3.16 % and 3.13 / 4.31 %).
// Unscaled and with the walks at their share of the steps, one training of three met both.
TEST(SurrogateOnRve, OneModelMeetsTheHeldOutLaboratoryPathsAndTheCurve) {
  const std::vector<std::string> carried = {"coordination_number"};
  SurrogateRecipe recipe = TinyRecipe(96, carried);
  recipe.architecture.hidden_widths = {128, 128};
  recipe.architecture.pressure_reference_pa = 3000;
  recipe.walk_share = 0.6;
  recipe.training.seed = 2;
  const auto start = std::chrono::steady_clock::now();
  const RecordedRigRun rig =
      RecordRigPaths(FeDeTier(TinyFeDeOptions()), Request(), {}, RveVariables(carried, "carried"));
  const double rig_seconds = Seconds(start);
  recipe.rig_training = EvenlySpread(rig.paths, 4, 0);
  const TrainedSurrogate trained = TrainOnTheSoilsRve(recipe);
  const std::vector<NamedLabPath> paths = HeldOutPaths(recipe);
  ASSERT_EQ(recipe.held_out_walks, 4);
  ASSERT_EQ(trained.held_out_errors.size(), paths.size());
  std::cout << "  rig run " << rig_seconds << " s; " << trained.samples << " samples, paths "
            << trained.generation_seconds << " s, training " << trained.training_seconds << " s\n";

  // The floors: every held-out path on 16 other packings of the soil's RVE.
  std::vector<std::vector<PackingDifference>> packings(paths.size());
  for (unsigned seed = 2; seed <= 17; ++seed) {
    FeDeOptions other = TinyFeDeOptions();
    other.numerics.seed = seed;
    const auto rve = dem::rve::SharedRveMaterial(dem::rve::RveMaterialParamsFromSoil(
        BuiltinSoilCatalogue().Find(kSoil, dem::rve::kRveSoilModel)->parameters, other.numerics,
        "soil"));
    const std::vector<ann::StrainHistory> on_packing = RunLabPaths(*rve, paths, 2);
    for (std::size_t k = 0; k < paths.size(); ++k) {
      packings[k].push_back({seed, ann::HistoryDifference(on_packing[k], trained.held_out[k])});
    }
  }
  int within_five_percent = 0;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    const double error = trained.held_out_errors[k].replay_error;
    const double floor = PackingFloor(packings[k]);
    std::cout << "  held out " << paths[k].name << ": " << 100 * error << " % (floor "
              << 100 * floor << " %)\n";
    EXPECT_LE(error, std::max(0.05, floor))
        << paths[k].name << ": beyond the issue's 5 % and further from its RVE than a typical "
        << "other packing";
    within_five_percent += error <= 0.05;
  }
  // The floor is what lets a path past 5 %, not what the test mostly holds.
  EXPECT_GE(within_five_percent, 5);

  char directory[] = "/tmp/gonogo_fe_ann_one_XXXXXX";
  ASSERT_NE(mkdtemp(directory), nullptr);
  FeAnnOptions options;
  options.fe_de = TinyFeDeOptions();
  const FeAnnTier tier(options, SavedAsTheOnlyModel(trained.ensemble, directory, "one-model"));
  for (const double load_n : {1000.0, 1500.0}) {
    TractionRequest request = Request();
    request.wheel_load_n = load_n;
    const FeDeRunReport fe_de =
        load_n == 1000 ? rig.run : FeDeTier(TinyFeDeOptions()).Run(request, {});
    const AnnRunReport report = tier.Run(request, {});
    ASSERT_EQ(report.curve.points.size(), 5u) << report.curve.immobile_reason;
    ASSERT_EQ(fe_de.curve.points.size(), 5u) << fe_de.curve.immobile_reason;
    PrintSideBySide(report.curve, fe_de.curve);
    const CurveDifference worst = WorstDifference(report.curve, fe_de.curve, request);
    std::cout << "  at " << load_n << " N: " << report.fallbacks << " fallbacks; worst: D "
              << 100 * worst.drawbar_pull_over_w << " % of W, T " << 100 * worst.torque_over_rw
              << " % of rW, z " << 100 * worst.sinkage_over_r << " % of r\n";
    EXPECT_LE(report.fallbacks, report.elements / 16) << "more than a few points left the envelope";
    EXPECT_LT(worst.drawbar_pull_over_w, 0.05) << load_n << " N";
    EXPECT_LT(worst.torque_over_rw, 0.05) << load_n << " N";
    EXPECT_LT(worst.sinkage_over_r, 0.05) << load_n << " N";
  }
  std::filesystem::remove_all(directory);
}

// The recipe's network carries what the RVE's state has; anything else is refused by name before
// a path runs.
TEST(SurrogateOnRve, ARecipeCarriesOnlyWhatTheRvesStateHas) {
  try {
    TrainOnTheSoilsRve(TinyRecipe(0, {"void_ratio"}));
    ADD_FAILURE() << "a variable the RVE does not read was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "recipe.architecture.carried_variables");
    EXPECT_NE(std::string(e.what()).find("coordination_number"), std::string::npos) << e.what();
  }
  try {
    TrainOnTheSoilsRve(TinyRecipe(0, {"fabric_xz"}));
    ADD_FAILURE() << "a tensor's component was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "recipe.architecture.carried_variables");
  }
}

TEST_F(FeAnnTierTest, ChoosesTheSoilsModelAndRefusesWhatItCannotAnswer) {
  const FeAnnTier tier(Options(), *models_);
  TractionRequest request = Request();
  tier.ResolveChoices(request, "");
  EXPECT_EQ(request.surrogate_model, "test-model");

  request.surrogate_model = "no-such-model";
  try {
    tier.ResolveChoices(request, "curve.");
    ADD_FAILURE() << "an unknown model was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "curve.surrogate_model");
    EXPECT_NE(std::string(e.what()).find("gonogo models"), std::string::npos) << e.what();
  }

  // Another configuration's RVE numerics: no model, and the error says how to train one.
  FeAnnOptions other = Options();
  other.fe_de = FeDeOptions::Preset("default");
  const FeAnnTier default_tier(other, *models_);
  request.surrogate_model.clear();
  try {
    default_tier.ResolveChoices(request, "");
    ADD_FAILURE() << "a soil with no model was accepted";
  } catch (const PreconditionError& e) {
    EXPECT_EQ(e.field(), "surrogate_model");
    EXPECT_NE(std::string(e.what()).find("gonogo train --soil NAME"),
              std::string::npos)
        << e.what();
  }
  request.surrogate_model = "test-model";
  EXPECT_THROW(default_tier.ResolveChoices(request, ""), InputError);

  // A tier without models refuses one by name.
  TractionRequest empirical = Request();
  empirical.surrogate_model = "test-model";
  try {
    EmpiricalTier().ResolveChoices(empirical, "");
    ADD_FAILURE() << "the empirical tier took a surrogate model";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "surrogate_model");
  }
  empirical.surrogate_model = "bad id!";
  EXPECT_THROW(empirical.Validate(), InputError);

  // The guard's return is in the tier's version (so in the cache key), and refused by field where
  // it cannot hold.
  FeAnnOptions returning = Options();
  returning.return_after_steps = 10;
  EXPECT_NE(FeAnnTier(returning, *models_).Version().find("-return10"), std::string::npos);
  EXPECT_EQ(tier.Version().find("-return"), std::string::npos);
  for (const auto& [steps, fallback] : {std::pair{10, false}, std::pair{-1, true}}) {
    returning.return_after_steps = steps;
    returning.fallback_enabled = fallback;
    try {
      FeAnnTier refused(returning, *models_);
      ADD_FAILURE() << "return_after_steps " << steps << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "fe_ann.return_after_steps");
    }
  }
}

// A request's own guard over the deployment's: written whole into the request before it is keyed,
// named in the version the key carries, refused by field where it cannot hold, and refused by a
// tier without a surrogate.
TEST_F(FeAnnTierTest, ARequestSetsItsOwnGuardOverTheDeployments) {
  FeAnnOptions returning = Options();
  returning.return_after_steps = 10;
  const FeAnnTier tier(returning, *models_);
  TractionRequest request = Request();
  tier.ResolveChoices(request, "");
  EXPECT_TRUE(request.surrogate_guard.Empty()) << "no guard asked, none written";
  EXPECT_EQ(tier.VersionFor(request), tier.Version());

  request.surrogate_guard.fallback_enabled = false;
  tier.ResolveChoices(request, "curve.");
  const SurrogateGuard& whole = request.surrogate_guard;
  ASSERT_TRUE(whole.distance_threshold && whole.spread_threshold && whole.fallback_enabled &&
              whole.return_after_steps);
  EXPECT_EQ(*whole.distance_threshold, 0);
  EXPECT_FALSE(*whole.fallback_enabled);
  EXPECT_EQ(*whole.return_after_steps, 0) << "with the fallback off there is nothing to return from";
  EXPECT_EQ(tier.VersionFor(request), "fe-ann-3-tiny-nofallback");
  EXPECT_EQ(tier.Version(), "fe-ann-3-tiny-return10");
  TractionRequest again = request;  // resolving a resolved request changes nothing
  tier.ResolveChoices(again, "");
  EXPECT_EQ(tier.VersionFor(again), tier.VersionFor(request));

  TractionRequest tighter = Request();
  tighter.surrogate_guard.distance_threshold = 30.00004;
  EXPECT_EQ(tier.VersionFor(tighter), "fe-ann-3-tiny-d30-s0-return10");
  TractionRequest floored = Request();
  floored.surrogate_guard.pressure_floor_pa = 4000.00004;
  EXPECT_EQ(tier.VersionFor(floored), "fe-ann-3-tiny-p4000-return10")
      << "a floor computes another curve, cached apart";
  EXPECT_EQ(tier.OptionsFor(floored, "").pressure_floor_pa, 4000)
      << "a floor counts to the digits its version names";
  tier.ResolveChoices(tighter, "");
  EXPECT_EQ(*tighter.surrogate_guard.distance_threshold, 30)
      << "a threshold counts to the digits its version (so its key) names";
  EXPECT_EQ(tier.OptionsFor(tighter, "").distance_threshold, 30);

  const auto refused_field = [&](const FeAnnTier& on, SurrogateGuard guard) -> std::string {
    TractionRequest bad = Request();
    bad.surrogate_guard = guard;
    try {
      on.ResolveChoices(bad, "curve.");
    } catch (const InputError& e) {
      return e.field();
    }
    return "(accepted)";
  };
  SurrogateGuard negative;
  negative.spread_threshold = -0.1;
  EXPECT_EQ(refused_field(tier, negative), "curve.surrogate_guard.spread_threshold");
  SurrogateGuard negative_floor;
  negative_floor.pressure_floor_pa = -1;
  EXPECT_EQ(refused_field(tier, negative_floor), "curve.surrogate_guard.pressure_floor_pa");
  SurrogateGuard returns_from_nothing;
  returns_from_nothing.fallback_enabled = false;
  returns_from_nothing.return_after_steps = 5;
  EXPECT_EQ(refused_field(tier, returns_from_nothing), "curve.surrogate_guard.return_after_steps");
  FeAnnOptions no_fallback = Options();
  no_fallback.fallback_enabled = false;
  SurrogateGuard returns;
  returns.return_after_steps = 5;
  EXPECT_EQ(refused_field(FeAnnTier(no_fallback, *models_), returns),
            "curve.surrogate_guard.return_after_steps")
      << "the deployment's fallback is off";
  returns.fallback_enabled = true;
  EXPECT_EQ(refused_field(FeAnnTier(no_fallback, *models_), returns), "(accepted)");

  TractionRequest empirical = Request();
  empirical.surrogate_guard.fallback_enabled = false;
  try {
    EmpiricalTier().ResolveChoices(empirical, "");
    ADD_FAILURE() << "the empirical tier took a surrogate guard";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "surrogate_guard");
  }
}

// The request's guard is the one its points are flagged by: thresholds no input can meet with the
// fallback off flag every point and leave every one to the network (counted), where the
// deployment's guard would have flagged a few and answered them by their RVEs.
TEST_F(FeAnnTierTest, ARequestsGuardIsTheOneItsPointsAreFlaggedBy) {
  const FeAnnTier tier(Options(), *models_);
  TractionRequest request = Request();
  request.surrogate_guard.distance_threshold = 1e-12;
  request.surrogate_guard.spread_threshold = 1e-12;
  request.surrogate_guard.fallback_enabled = false;
  const AnnRunReport report = tier.Run(request, {});
  ASSERT_EQ(report.curve.points.size(), 5u) << report.curve.immobile_reason;
  EXPECT_EQ(report.fallbacks, 0);
  EXPECT_GE(report.unanswered_flags, report.network_point_updates - 4)
      << "every point's every update flagged";
  ASSERT_TRUE(report.curve.surrogate_run.has_value());
  EXPECT_EQ(report.curve.surrogate_run->unanswered_flags, report.unanswered_flags);
  EXPECT_EQ(report.curve.surrogate_run->fallbacks, 0);
  EXPECT_EQ(report.curve.surrogate_run->fallback_paths_kept, 0) << "none asked for";
  EXPECT_EQ(report.curve.tier_version, "fe-ann-3-tiny-nofallback-d1e-12-s1e-12");
}

// The fe-de rig run with every point's path recorded (RecordRigPaths), once for the suite.
const RecordedRigRun& RecordedFeDeRun() {
  static const RecordedRigRun* recorded =
      new RecordedRigRun(RecordRigPaths(FeDeTier(TinyFeDeOptions()), Request()));
  return *recorded;
}

// Thresholds no input can meet: every point is flagged at its first increment and answered from
// then on by the RVE its depth starts with, which is exactly what the fe-de tier computes. The
// run records its fallen-back points' paths (FeAnnTier::Run's fallback_paths), which changes
// nothing: the curve is still fe-de's bit for bit, and each point's path is the path its RVE
// takes in the fe-de run, bit for bit, with the coordination number the model carries recorded.
TEST_F(FeAnnTierTest, EveryPointFlaggedIsAnsweredByItsRveAndGivesTheFeDeCurve) {
  FeAnnOptions options = Options();
  options.distance_threshold = 1e-12;
  options.spread_threshold = 1e-12;
  const FeAnnTier tier(options, *models_);
  std::vector<ann::StrainHistory> fallback_paths;
  const AnnRunReport report = tier.Run(Request(), {}, {}, &fallback_paths);
  ASSERT_EQ(report.curve.points.size(), 5u) << report.curve.immobile_reason;
  EXPECT_GE(report.fallbacks, report.elements);
  EXPECT_LE(report.fallbacks, report.elements + 4);
  // Each was flagged by the distance, and none by a floor (none is set). The spread may flag none:
  // at a point's first increment, from rest, the anchored members can agree exactly (measured:
  // 0 of 130).
  EXPECT_EQ(report.fallbacks_flagged.beyond_distance, report.fallbacks);
  EXPECT_LE(report.fallbacks_flagged.beyond_spread, report.fallbacks);
  EXPECT_EQ(report.fallbacks_flagged.below_pressure_floor, 0);
  EXPECT_TRUE(std::all_of(report.fallback_steps.begin(), report.fallback_steps.end(),
                          [](std::int64_t step) { return step == 0; }));
  EXPECT_TRUE(SameBits(report.curve, fe_de_->curve)) << "the RVEs' curve differs from fe-de's";
  EXPECT_EQ(report.curve.tier, "fe-ann");
  const RecordedRigRun& fe_de = RecordedFeDeRun();
  EXPECT_GE(fallback_paths.size(), fe_de.paths.size());
  EXPECT_LE(fallback_paths.size(), static_cast<std::size_t>(report.fallbacks));
  for (const ann::StrainHistory& path : fallback_paths) {
    ASSERT_EQ(path.internal_variable_names, std::vector<std::string>{"coordination_number"});
    ASSERT_EQ(path.internal_variables.size(), path.steps());
    ASSERT_EQ(path.initial_internal_variables.size(), 1u);
    EXPECT_GT(path.initial_internal_variables[0], 2.0) << "a settled packing's coordination";
  }
  std::size_t matched = 0;
  for (const ann::StrainHistory& rig_path : fe_de.paths) {
    const auto same = std::find_if(
        fallback_paths.begin(), fallback_paths.end(), [&](const ann::StrainHistory& path) {
          return path.initial_stress_pa == rig_path.initial_stress_pa &&
                 path.increments == rig_path.increments && path.stresses_pa == rig_path.stresses_pa;
        });
    matched += same != fallback_paths.end() ? 1 : 0;
  }
  std::cout << "  " << fallback_paths.size() << " fallen-back points' paths recorded; "
            << matched << " of the fe-de run's " << fe_de.paths.size() << " paths among them\n";
  EXPECT_EQ(matched, fe_de.paths.size());
}

// The network answers the points of every FE step, all but a few that leave its envelope under
// the wheel (those fall back to their RVEs), at a fraction of the RVEs' cost, and its curve is
// within the target of fe-de's: 5 % of W and of rW at every slip (training is seeded and
// single-threaded, the paths deterministic). Without the ensemble's admissible stresses
// (SurrogateEnsemble::Admissible) the same model was 9.1 % of W and 11.6 % of rW off; with the
// tensile cap alone 4.7 and 4.8 % (solvers/ann/README.md): the cap and the cone are what this
// test holds.
TEST_F(FeAnnTierTest, NetworkAnswersNearlyEveryPointAndItsCurveIsComparedWithFeDe) {
  const FeAnnTier tier(Options(), *models_);
  const auto start = std::chrono::steady_clock::now();
  std::vector<AnnProgress> progress;
  std::vector<ann::StrainHistory> fallback_paths;
  // The notes a job's progress shows, each before the fraction it goes with.
  std::vector<std::string> notes;
  std::vector<double> fractions;
  ComputeContext context;
  context.progress_note = [&](const std::string& note) { notes.push_back(note); };
  context.progress = [&](double fraction) {
    fractions.push_back(fraction);
    EXPECT_EQ(notes.size(), fractions.size()) << "a note before each fraction";
  };
  const AnnRunReport report = tier.Run(
      Request(), context, [&](const AnnProgress& p) { progress.push_back(p); }, &fallback_paths);
  const double seconds = Seconds(start);
  ASSERT_EQ(report.curve.points.size(), fe_de_->curve.points.size())
      << report.curve.immobile_reason;
  EXPECT_EQ(report.model_id, "test-model");
  std::cout << "  fe-ann curve: " << seconds << " s (fe-de " << fe_de_seconds_ << " s, "
            << fe_de_seconds_ / seconds << "x); network " << report.network_seconds << " s for "
            << report.network_point_updates << " point updates (" << report.stress_returns
            << " capped or returned onto the cone), fallbacks "
            << report.fallbacks << ", " << report.fallback_seconds
            << " s, model load " << report.model_load_seconds << " s\n";
  PrintSideBySide(report.curve, fe_de_->curve);
  const CurveDifference worst = WorstDifference(report.curve, fe_de_->curve, Request());
  const double worst_pull = worst.drawbar_pull_over_w;
  const double worst_torque = worst.torque_over_rw;
  const double worst_sinkage = worst.sinkage_over_r;
  std::cout << "  worst: D " << 100 * worst_pull << " % of W, T " << 100 * worst_torque
            << " % of rW, z " << 100 * worst_sinkage << " % of r\n";
  // Measured: 6 of 128 (the carried coordination number is one more dimension of the envelope;
  // the network that carries nothing had 0-3).
  EXPECT_LE(report.fallbacks, report.elements / 16) << "more than a few points left the envelope";
  // Every point at every FE step, less the steps of fallen-back points after their fallback (and
  // the bin's start, which asks a point or two more).
  const std::int64_t point_steps = static_cast<std::int64_t>(report.elements) * report.fe_steps;
  std::int64_t steps_on_rves = 0;
  for (std::int64_t step : report.fallback_steps) steps_on_rves += report.fe_steps - step;
  EXPECT_NEAR(static_cast<double>(report.network_point_updates),
              static_cast<double>(point_steps - steps_on_rves), 4.0 + 2 * report.fallbacks);
  EXPECT_GT(fe_de_seconds_ / seconds, 4.0) << "the network is not cheaper than the RVEs";
  EXPECT_GT(report.stress_returns, 0) << "no answer was made admissible: the cap and cone are untested";
  // The run's progress, as it went: how far, and its fallbacks so far.
  ASSERT_GE(progress.size(), 10u);
  for (std::size_t i = 1; i < progress.size(); ++i) {
    EXPECT_GE(progress[i].fraction, progress[i - 1].fraction);
    EXPECT_GE(progress[i].fallbacks, progress[i - 1].fallbacks);
    EXPECT_GE(progress[i].network_seconds, progress[i - 1].network_seconds);
  }
  EXPECT_LE(progress.back().fraction, 1.0);
  EXPECT_GT(progress.back().fraction, 0.9);
  EXPECT_GT(progress.back().fallbacks, 0) << "the fallbacks happen during the run";
  EXPECT_LE(progress.back().fallbacks, report.fallbacks);
  EXPECT_LE(progress.back().network_seconds, report.network_seconds);
  // Which of the guard's tests flagged the fallbacks: with no floor, the distance or the spread
  // flagged each one, so far and in the end.
  const auto expect_each_flagged = [](int fallbacks, const FallbackFlagCounts& flagged) {
    EXPECT_LE(std::max(flagged.beyond_distance, flagged.beyond_spread), fallbacks);
    EXPECT_GE(flagged.beyond_distance + flagged.beyond_spread, fallbacks);
    EXPECT_EQ(flagged.below_pressure_floor, 0);
  };
  const AnnProgress& last = progress.back();
  expect_each_flagged(last.fallbacks, last.fallbacks_flagged);
  expect_each_flagged(report.fallbacks, report.fallbacks_flagged);
  EXPECT_LE(progress.back().fallbacks_flagged.beyond_distance,
            report.fallbacks_flagged.beyond_distance);
  EXPECT_LE(progress.back().fallbacks_flagged.beyond_spread,
            report.fallbacks_flagged.beyond_spread);
  ASSERT_EQ(notes.size(), progress.size());
  EXPECT_EQ(notes.front().rfind("no point fallen back to its RVE (RVEs ", 0), 0u)
      << notes.front();
  const std::string last_count = std::to_string(progress.back().fallbacks);
  EXPECT_EQ(notes.back().rfind(last_count + (progress.back().fallbacks == 1 ? " point" : " points") +
                                   " fallen back to ",
                               0),
            0u)
      << notes.back();
  EXPECT_NE(notes.back().find(" (flagged: distance " +
                              std::to_string(last.fallbacks_flagged.beyond_distance) + ", spread " +
                              std::to_string(last.fallbacks_flagged.beyond_spread) + ")"),
            std::string::npos)
      << notes.back();
  std::cout << "  the last progress note: " << notes.back() << "\n";
  // Each fallen-back point's path on its RVE, from its start to the end of its bin's run.
  ASSERT_GE(fallback_paths.size(), 1u);
  EXPECT_LE(fallback_paths.size(), static_cast<std::size_t>(report.fallbacks));
  const std::int64_t first_fallback =
      *std::min_element(report.fallback_steps.begin(), report.fallback_steps.end());
  for (const ann::StrainHistory& path : fallback_paths) {
    EXPECT_GT(static_cast<std::int64_t>(path.steps()), first_fallback);
    EXPECT_LE(path.steps(), static_cast<std::size_t>(report.fe_steps) + 2);
  }
  // The curve carries the run's provenance (the service caches and shows it).
  ASSERT_TRUE(report.curve.surrogate_run.has_value());
  const SurrogateRun& run = *report.curve.surrogate_run;
  EXPECT_EQ(run.fe_steps, report.fe_steps);
  EXPECT_EQ(run.fallbacks, report.fallbacks);
  EXPECT_EQ(run.fallback_point_steps, report.fallback_steps);
  EXPECT_EQ(run.fallbacks_flagged.beyond_distance, report.fallbacks_flagged.beyond_distance);
  EXPECT_EQ(run.fallbacks_flagged.beyond_spread, report.fallbacks_flagged.beyond_spread);
  EXPECT_EQ(run.fallbacks_flagged.below_pressure_floor,
            report.fallbacks_flagged.below_pressure_floor);
  EXPECT_EQ(run.fallback_paths_kept, static_cast<int>(fallback_paths.size()));
  EXPECT_EQ(run.network_point_updates, report.network_point_updates);
  EXPECT_EQ(run.network_seconds, report.network_seconds);
  EXPECT_EQ(run.fallback_seconds, report.fallback_seconds);
  EXPECT_LT(worst_pull, 0.05);
  EXPECT_LT(worst_torque, 0.05);
  EXPECT_LT(worst_sinkage, 0.05);
}

// Seed 000's point, a scenario not in the training data: the same model (laboratory paths only,
// so no rig is in its training) on a tyre scaled by 1.2 (0.6 x 0.24 m) at 1,440 N (the load
// scaled by the contact area), against fe-de on that rig: within the 5 % of W and of rW.
// The same recipe's network carrying nothing was 5.9 % of W and 8.9 % of rW off
// (solvers/ann/README.md, "A wheel it was not trained near").
TEST_F(FeAnnTierTest, AWheelItWasNotTrainedNearIsComparedWithFeDe) {
  TractionRequest scaled = Request();
  scaled.tyre.diameter_m = 0.6;
  scaled.tyre.width_m = 0.24;
  scaled.tyre.section_height_m = 0.12;
  scaled.wheel_load_n = 1440;
  auto start = std::chrono::steady_clock::now();
  const FeDeRunReport fe_de = FeDeTier(TinyFeDeOptions()).Run(scaled, {});
  const double fe_de_seconds = Seconds(start);
  start = std::chrono::steady_clock::now();
  const AnnRunReport report = FeAnnTier(Options(), *models_).Run(scaled, {});
  const double seconds = Seconds(start);
  ASSERT_EQ(fe_de.curve.points.size(), 5u) << fe_de.curve.immobile_reason;
  ASSERT_EQ(report.curve.points.size(), 5u) << report.curve.immobile_reason;
  PrintSideBySide(report.curve, fe_de.curve);
  const CurveDifference worst = WorstDifference(report.curve, fe_de.curve, scaled);
  std::cout << "  scaled tyre at 1,440 N: fe-ann " << seconds << " s (fe-de " << fe_de_seconds
            << " s), " << report.fallbacks << " fallbacks; worst: D "
            << 100 * worst.drawbar_pull_over_w << " % of W, T " << 100 * worst.torque_over_rw
            << " % of rW, z " << 100 * worst.sinkage_over_r << " % of r\n";
  EXPECT_LE(report.fallbacks, report.elements / 16) << "more than a few points left the envelope";
  EXPECT_LT(worst.drawbar_pull_over_w, 0.05);
  EXPECT_LT(worst.torque_over_rw, 0.05);
  EXPECT_LT(worst.sinkage_over_r, 0.05);
}

// Seed 000's step 2: the paths the points of an fe-de rig run take, recorded without changing
// the run: the recorded run's curve is the fe-de curve bit for bit, and every point of the bin has
// a path of every FE step, starting at its geostatic stress.
TEST_F(FeAnnTierTest, RecordsTheRigRunsPointPathsWithoutChangingItsCurve) {
  const RecordedRigRun& recorded = RecordedFeDeRun();
  EXPECT_TRUE(SameBits(recorded.run.curve, fe_de_->curve));
  ASSERT_EQ(recorded.paths.size(), static_cast<std::size_t>(recorded.run.elements));
  double deepest_start_pa = 0, largest_stress_pa = 0;
  for (const ann::StrainHistory& path : recorded.paths) {
    EXPECT_GE(path.steps(), static_cast<std::size_t>(recorded.run.fe_steps));
    ASSERT_EQ(path.stresses_pa.size(), path.steps());
    deepest_start_pa = std::max(deepest_start_pa, -path.initial_stress_pa.trace() / 3);
    for (const ann::Vector6& stress : path.stresses_pa) {
      ASSERT_TRUE(stress.allFinite());
      largest_stress_pa = std::max(largest_stress_pa, stress.cwiseAbs().maxCoeff());
    }
  }
  std::cout << "  " << recorded.paths.size() << " paths of " << recorded.paths.front().steps()
            << " steps; geostatic mean stress up to " << deepest_start_pa / 1e3
            << " kPa, stresses up to " << largest_stress_pa / 1e3 << " kPa\n";
  EXPECT_GE(deepest_start_pa, 2e3);  // the bin's floor, at least
  EXPECT_GT(largest_stress_pa, 2 * deepest_start_pa) << "the wheel loads the points it passes";
  const std::vector<ann::StrainHistory> spread = EvenlySpread(recorded.paths, 4, 1);
  ASSERT_EQ(spread.size(), 4u);
  EXPECT_EQ(spread[1].stresses_pa.back(), recorded.paths[1 + 32].stresses_pa.back());
}

// A rig point's path replayed (ReplayedOnRve) on the packing it was recorded on is that path, to
// within the settling: the template is settled at the recorded initial mean stress, which the bin's
// servo reached to 1 %, not at the depth's own (measured: 0.06-0.4 % off). On packing 2 it is
// further off (1.6-8.9 %): the floor under a held-out rig path. A path the RVE cannot start is
// refused by name.
TEST_F(FeAnnTierTest, ARigPathReplayedOnItsOwnPackingIsThePathAndOnAnotherItsFloor) {
  const std::vector<ann::StrainHistory> paths = EvenlySpread(RecordedFeDeRun().paths, 3, 1);
  const SoilParameters soil =
      BuiltinSoilCatalogue().Find(kSoil, dem::rve::kRveSoilModel)->parameters;
  const auto rve_of = [&](unsigned packing_seed) {
    FeDeOptions options = TinyFeDeOptions();
    if (packing_seed > 0) options.numerics.seed = packing_seed;
    return dem::rve::SharedRveMaterial(
        dem::rve::RveMaterialParamsFromSoil(soil, options.numerics, "soil"));
  };
  const auto own = rve_of(0);
  const auto other = rve_of(2);
  const ann::InternalVariables coordination = RveVariables({"coordination_number"}, "carried");
  for (const ann::StrainHistory& path : paths) {
    const ann::StrainHistory again = ReplayedOnRve(own, path, coordination);
    ASSERT_EQ(again.steps(), path.steps()) << again.stopped_reason;
    EXPECT_EQ(again.increments, path.increments);
    EXPECT_EQ(again.internal_variable_names, coordination.names);
    ASSERT_EQ(again.internal_variables.size(), path.steps());
    const double initial_mean_pa = -path.initial_stress_pa.trace() / 3;
    EXPECT_NEAR(-again.initial_stress_pa.trace() / 3, initial_mean_pa, 0.02 * initial_mean_pa);
    const double own_difference = ann::HistoryDifference(again, path);
    const double other_difference = ann::HistoryDifference(ReplayedOnRve(other, path), path);
    std::cout << "  path from " << initial_mean_pa / 1e3 << " kPa: replayed on its own packing "
              << 100 * own_difference << " %, on packing 2 " << 100 * other_difference << " %\n";
    EXPECT_LT(own_difference, 0.01);
    EXPECT_GT(other_difference, own_difference);
  }
  ann::StrainHistory tensile = paths.front();
  tensile.initial_stress_pa = -tensile.initial_stress_pa;
  ann::StrainHistory empty = paths.front();
  empty.increments.clear();
  empty.stresses_pa.clear();
  for (const ann::StrainHistory& refused : {tensile, empty}) {
    try {
      ReplayedOnRve(own, refused);
      ADD_FAILURE() << "a path the RVE cannot start was replayed";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "path") << e.what();
    }
  }
}

// A rig point's path answered as the tier answers its point (ReplayGuarded). With every increment
// flagged the point falls back at its first and its RVE answers the whole path, as ReplayedOnRve
// replays it, bit for bit. With none flagged the network answers every step, as the open-loop
// replay does, but from the settled RVE's stress and coordination number rather than the path's
// recorded ones: measured, the two errors differ by far less than either.
TEST_F(FeAnnTierTest, ARigPathAnsweredAsTheTierAnswersItsPointIsTheRvesWhereFlagged) {
  const SoilParameters soil =
      BuiltinSoilCatalogue().Find(kSoil, dem::rve::kRveSoilModel)->parameters;
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(soil, TinyFeDeOptions().numerics, "soil"));
  // The rig's path with the coordination number the model carries (its replay on its own packing).
  const ann::StrainHistory path = ReplayedOnRve(rve, EvenlySpread(RecordedFeDeRun().paths, 3, 1)[1],
                                                RveVariables({"coordination_number"}, "carried"));
  const ann::SurrogateEnsemble model = ann::SurrogateEnsemble::Load(*directory_ + "/model");

  ann::SurrogateEnsemble flag_all = ann::SurrogateEnsemble::Load(*directory_ + "/model");
  flag_all.SetThresholds(1e-12, 1e-12);
  const GuardedReplay on_rve = ReplayGuarded(flag_all, rve, path);
  EXPECT_EQ(on_rve.first_fallback_step, 0);
  EXPECT_EQ(on_rve.fallbacks, 1);
  EXPECT_TRUE(on_rve.stopped_reason.empty()) << on_rve.stopped_reason;
  const ann::StrainHistory replayed = ReplayedOnRve(rve, path);
  ASSERT_EQ(on_rve.stresses_pa.size(), replayed.steps());
  for (std::size_t k = 0; k < replayed.steps(); ++k) {
    ASSERT_EQ(on_rve.stresses_pa[k], replayed.stresses_pa[k]) << "step " << k;
  }
  EXPECT_EQ(on_rve.error, ann::HistoryDifference(replayed, path));

  ann::SurrogateEnsemble flag_none = ann::SurrogateEnsemble::Load(*directory_ + "/model");
  flag_none.SetThresholds(1e30, 1e30);
  const GuardedReplay on_network = ReplayGuarded(flag_none, rve, path);
  EXPECT_EQ(on_network.fallbacks, 0);
  EXPECT_EQ(on_network.first_fallback_step, -1);
  ASSERT_EQ(on_network.stresses_pa.size(), path.steps());
  const double open_loop = ann::ReplayError(model, path);
  std::cout << "  rig path of " << path.steps() << " steps: open-loop " << 100 * open_loop
            << " %, the network from the settled RVE " << 100 * on_network.error << " %, the RVE "
            << 100 * on_rve.error << " %\n";
  EXPECT_NEAR(on_network.error, open_loop, 0.2 * open_loop);
  EXPECT_GT(std::abs(on_network.error - on_rve.error), 0.0) << "two answers, not one";

  // A pressure floor above the path's stresses flags its first increment: the RVE answers the
  // whole path, as with every threshold at nothing.
  ann::SurrogateEnsemble floored = ann::SurrogateEnsemble::Load(*directory_ + "/model");
  floored.SetPressureFloor(1e9);
  const GuardedReplay under_floor = ReplayGuarded(floored, rve, path);
  EXPECT_EQ(under_floor.first_fallback_step, 0);
  EXPECT_EQ(under_floor.fallbacks, 1);
  EXPECT_TRUE(under_floor.stresses_pa == on_rve.stresses_pa);

  // At the model's own thresholds, what the tier's point gets: printed for the README.
  const GuardedReplay guarded = ReplayGuarded(model, rve, path);
  std::cout << "  at the model's thresholds: " << 100 * guarded.error << " %, " << guarded.fallbacks
            << " fallbacks, the first after " << guarded.first_fallback_step << " increments\n";
  EXPECT_EQ(guarded.stresses_pa.size(), path.steps()) << guarded.stopped_reason;
}

}  // namespace
}  // namespace gonogo::tiers
