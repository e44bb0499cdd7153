// The surrogate ensemble (solvers/ann/surrogate_ensemble.h): its members' mean, the Mahalanobis
// envelope and the spread flagging what lies outside the training (Drucker-Prager lab paths at
// 10-80 kPa) and not what lies inside, settable thresholds, and saving and loading.
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>

#include <unistd.h>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/surrogate_ensemble.h"
#include "solvers/common/errors.h"
#include "solvers/material/drucker_prager.h"

namespace gonogo::ann {
namespace {

const material::DruckerPrager& Soil() {
  static const material::DruckerPrager* soil = [] {
    material::DruckerPragerParams params;
    params.young_pa = 20e6;
    params.poisson = 0.3;
    params.cohesion_pa = 1e3;
    params.friction_angle_deg = 35;
    params.dilation_angle_deg = 5;
    return new material::DruckerPrager(params);
  }();
  return *soil;
}

StrainHistory Path(LabPath path, double pressure_pa, double max_strain, std::uint64_t seed = 1) {
  LabPathSpec spec;
  spec.path = path;
  spec.pressure_pa = pressure_pa;
  spec.max_strain = max_strain;
  spec.steps = 60;
  spec.seed = seed;
  spec.walk_step_strain = 5e-4;
  return RunLabPath(Soil(), spec);
}

std::vector<StrainHistory> TrainingPaths() {
  std::vector<StrainHistory> paths;
  for (double p : {10e3, 20e3, 40e3, 80e3}) paths.push_back(Path(LabPath::kTriaxial, p, 0.02));
  for (double p : {10e3, 40e3, 80e3}) paths.push_back(Path(LabPath::kSimpleShear, p, 0.04));
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    paths.push_back(Path(LabPath::kRandomWalk, 10e3 * (1 + seed % 8), 0.004, seed));
  }
  return paths;
}

const SurrogateEnsemble& Trained() {
  static const SurrogateEnsemble* ensemble = [] {
    TrainingOptions options;
    options.epochs = 150;
    options.batch_size = 64;
    return new SurrogateEnsemble(
        SurrogateEnsemble::Train(TrainingPaths(), MlpArchitecture{}, options));
  }();
  return *ensemble;
}

double FlaggedFraction(const std::vector<EnsembleAnswer>& answers) {
  double flagged = 0;
  for (const EnsembleAnswer& answer : answers) flagged += answer.out_of_distribution ? 1 : 0;
  return flagged / static_cast<double>(answers.size());
}

double MeanSpread(const std::vector<EnsembleAnswer>& answers) {
  double sum = 0;
  for (const EnsembleAnswer& answer : answers) sum += answer.relative_spread;
  return sum / static_cast<double>(answers.size());
}

TEST(SurrogateEnsemble, AnswersWithItsMembersMeanAndTangent) {
  const SurrogateEnsemble& ensemble = Trained();
  ASSERT_EQ(ensemble.size(), 3u);
  std::vector<SurrogateInput> inputs = InputsOf(Path(LabPath::kTriaxial, 30e3, 0.02));
  inputs.resize(10);
  const std::vector<EnsembleAnswer> answers = ensemble.Answer(inputs, true);
  Vector6 sum = Vector6::Zero();
  Voigt6x6 tangent_sum = Voigt6x6::Zero();
  for (std::size_t k = 0; k < 3; ++k) {
    std::vector<Voigt6x6> tangents;
    sum += ensemble.member(k).StressIncrements(inputs, &tangents)[7];
    tangent_sum += tangents[7];
  }
  EXPECT_LT((answers[7].stress_increment_pa - sum / 3).norm(), 1e-9 * sum.norm());
  EXPECT_LT((answers[7].tangent_pa - tangent_sum / 3).norm(), 1e-9 * tangent_sum.norm());
  EXPECT_NE(ensemble.member(0).StressIncrements(inputs)[7],
            ensemble.member(1).StressIncrements(inputs)[7]) << "members differ by their seeds";
}

TEST(SurrogateEnsemble, FlagsWhatLiesOutsideItsTrainingAndNotWhatLiesInside) {
  const SurrogateEnsemble& ensemble = Trained();
  std::vector<SurrogateInput> training;
  for (const StrainHistory& history : TrainingPaths()) {
    const std::vector<SurrogateInput> steps = InputsOf(history);
    training.insert(training.end(), steps.begin(), steps.end());
  }
  const std::vector<EnsembleAnswer> inside = ensemble.Answer(training, false);
  EXPECT_EQ(FlaggedFraction(inside), 0.0);
  const std::vector<EnsembleAnswer> held_out =
      ensemble.Answer(InputsOf(Path(LabPath::kTriaxial, 30e3, 0.02)), false);
  // Ten times the largest training pressure, and a strain increment 30 times the training's.
  const std::vector<EnsembleAnswer> deep =
      ensemble.Answer(InputsOf(Path(LabPath::kTriaxial, 800e3, 0.02)), false);
  SurrogateInput jump = training[100];
  jump.strain_increment *= 30;
  const EnsembleAnswer jumped = ensemble.Answer({jump}, false)[0];
  std::cout << "  thresholds: distance " << ensemble.distance_threshold() << ", spread "
            << ensemble.spread_threshold() << "\n  flagged: training " << FlaggedFraction(inside)
            << ", held-out triaxial at 30 kPa " << FlaggedFraction(held_out)
            << ", triaxial at 800 kPa " << FlaggedFraction(deep) << "; 30x increment: distance "
            << jumped.distance << "\n  mean relative spread: training " << MeanSpread(inside)
            << ", held-out " << MeanSpread(held_out) << ", 800 kPa " << MeanSpread(deep) << "\n";
  EXPECT_LT(FlaggedFraction(held_out), 0.1);
  EXPECT_GT(FlaggedFraction(deep), 0.9);
  EXPECT_TRUE(jumped.out_of_distribution);
  EXPECT_GT(MeanSpread(deep), MeanSpread(held_out));
}

TEST(SurrogateEnsemble, ThresholdsCanBeSetAndTheEnsembleSavedAndLoaded) {
  SurrogateEnsemble ensemble = SurrogateEnsemble::Load([] {
    const std::filesystem::path directory = std::filesystem::temp_directory_path() /
                                            ("gonogo_ensemble_" + std::to_string(getpid()));
    Trained().Save(directory.string());
    return directory.string();
  }());
  EXPECT_EQ(ensemble.distance_threshold(), Trained().distance_threshold());
  EXPECT_EQ(ensemble.spread_threshold(), Trained().spread_threshold());
  const std::vector<SurrogateInput> deep = InputsOf(Path(LabPath::kTriaxial, 800e3, 0.02));
  const std::vector<EnsembleAnswer> a = Trained().Answer(deep, false);
  const std::vector<EnsembleAnswer> b = ensemble.Answer(deep, false);
  for (std::size_t n = 0; n < deep.size(); ++n) {
    EXPECT_EQ(a[n].stress_increment_pa, b[n].stress_increment_pa);
    EXPECT_EQ(a[n].distance, b[n].distance);
  }
  ensemble.SetThresholds(1e12, 1e12);
  EXPECT_EQ(FlaggedFraction(ensemble.Answer(deep, false)), 0.0);
  EXPECT_THROW(ensemble.SetThresholds(0, 1), InputError);
  EXPECT_THROW(ensemble.SetThresholds(1, -1), InputError);
  std::filesystem::remove_all(std::filesystem::temp_directory_path() /
                              ("gonogo_ensemble_" + std::to_string(getpid())));
  try {
    SurrogateEnsemble::Load("/nonexistent/ensemble");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "model");
  }
  EXPECT_THROW(SurrogateEnsemble::Train(TrainingPaths(), MlpArchitecture{}, TrainingOptions{}, 2),
               InputError);
}

}  // namespace
}  // namespace gonogo::ann
