// The surrogate ensemble (solvers/ann/surrogate_ensemble.h): its members' mean, the Mahalanobis
// envelope and the spread flagging what lies outside the training (Drucker-Prager lab paths at
// 10-80 kPa) and not what lies inside, settable thresholds, and saving and loading; and the ANN
// material (ann_material.h) on the same ensemble, falling back to the Drucker-Prager model itself.
#include "solvers/ann/surrogate_ensemble.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>

#include "solvers/ann/ann_material.h"
#include "solvers/ann/lab_paths.h"
#include "solvers/common/errors.h"
#include "solvers/material/drucker_prager.h"
#include "tests/solvers/ann/drucker_prager_paths.h"

namespace gonogo::ann {
namespace {

using testing::Path;
using testing::Soil;
using testing::TrainingPaths;

const SurrogateEnsemble& Trained() {
  static const SurrogateEnsemble* ensemble = [] {
    TrainingOptions options;
    options.epochs = 300;
    options.batch_size = 64;
    // Unanchored: the material's seam and fallback are what this file tests, on the network its
    // figures were first measured with. The anchored network (the default) drives the servo
    // triaxial through the seam 13.5 % off the soil (unanchored 2.5 %), though it replays
    // strain-driven paths closer (stress_surrogate_test); solvers/ann/README.md.
    MlpArchitecture architecture;
    architecture.anchored = false;
    return new SurrogateEnsemble(
        SurrogateEnsemble::Train(TrainingPaths(), architecture, options));
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
  EXPECT_TRUE(jumped.beyond_distance);
  EXPECT_GT(MeanSpread(deep), MeanSpread(held_out));
  // Each answer says which test flagged it: the distance and the spread against their thresholds,
  // each alone, and flagged when either is (no floor is set).
  int by_distance = 0;
  int by_spread = 0;
  for (const std::vector<EnsembleAnswer>* answers : {&inside, &held_out, &deep}) {
    for (const EnsembleAnswer& answer : *answers) {
      EXPECT_EQ(answer.beyond_distance, answer.distance > ensemble.distance_threshold());
      EXPECT_EQ(answer.beyond_spread, answer.relative_spread > ensemble.spread_threshold());
      EXPECT_FALSE(answer.below_pressure_floor);
      EXPECT_EQ(answer.out_of_distribution, answer.beyond_distance || answer.beyond_spread);
      by_distance += answer.beyond_distance;
      by_spread += answer.beyond_spread;
    }
  }
  std::cout << "  flagged by distance " << by_distance << ", by spread " << by_spread << "\n";
  EXPECT_GT(by_distance, 0);
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
  // A pressure floor flags every input whose mean compression lies below it, whatever the members
  // say: here one floor between the path's least and most.
  double least_pa = std::numeric_limits<double>::infinity();
  double most_pa = 0;
  for (const SurrogateInput& input : deep) {
    least_pa = std::min(least_pa, -input.stress_pa.head<3>().mean());
    most_pa = std::max(most_pa, -input.stress_pa.head<3>().mean());
  }
  ASSERT_GT(most_pa, least_pa);
  ensemble.SetPressureFloor(0.5 * (least_pa + most_pa));
  EXPECT_EQ(ensemble.pressure_floor_pa(), 0.5 * (least_pa + most_pa));
  int below = 0;
  for (const EnsembleAnswer& answer : ensemble.Answer(deep, false)) {
    EXPECT_EQ(answer.out_of_distribution, answer.mean_pressure_pa < ensemble.pressure_floor_pa());
    EXPECT_EQ(answer.below_pressure_floor, answer.out_of_distribution);
    EXPECT_FALSE(answer.beyond_distance || answer.beyond_spread);  // thresholds no input meets
    below += answer.out_of_distribution;
  }
  EXPECT_GT(below, 0);
  EXPECT_LT(below, static_cast<int>(deep.size()));
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      ensemble.SetPressureFloor(bad);
      ADD_FAILURE() << bad << " Pa accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "pressure_floor_pa");
    }
  }
  ensemble.SetPressureFloor(0);
  EXPECT_EQ(FlaggedFraction(ensemble.Answer(deep, false)), 0.0);
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

// Principal compressions of `stress` (tension positive) measured from the apex `limit`, sorted.
Eigen::Vector3d CompressionsFrom(double limit, const Matrix3& stress) {
  Eigen::Vector3d compression =
      limit - Eigen::SelfAdjointEigenSolver<Matrix3>(stress).eigenvalues().array();
  std::sort(compression.data(), compression.data() + 3);
  return compression;
}

// The cap on principal stresses is the training data's most tensile principal stress (at least
// zero), and the cone the least ratio of least to most principal compression (from that apex) of
// the training stresses above the stress floor. A stress beyond the cap is capped and then, like
// a compressive stress outside the cone, returned onto it at its mean compression, keeping its
// principal directions; a stress inside both is left alone. Both are saved; an envelope saved
// before the cone (GNGENV02) loads with the cap only, one before the cap (GNGENV01) with neither.
TEST(SurrogateEnsemble, CapsTensionAndReturnsStressesOntoTheTrainingDataCone) {
  const SurrogateEnsemble& ensemble = Trained();
  double most_tensile = 0;
  for (const StrainHistory& history : TrainingPaths()) {
    for (const Vector6& stress : history.stresses_pa) {
      const Eigen::SelfAdjointEigenSolver<Matrix3> principal(material::VoigtToStress(stress));
      most_tensile = std::max(most_tensile, principal.eigenvalues().maxCoeff());
    }
  }
  const double limit = ensemble.envelope().tensile_limit_pa;
  EXPECT_EQ(limit, most_tensile);
  double least_ratio = 1;
  for (const StrainHistory& history : TrainingPaths()) {
    for (const Vector6& voigt : history.stresses_pa) {
      const Matrix3 stress = material::VoigtToStress(voigt);
      if (stress.norm() < ensemble.envelope().stress_floor_pa) continue;
      const Eigen::Vector3d c = CompressionsFrom(limit, stress);
      least_ratio = std::min(least_ratio, std::max(0.0, c[0]) / c[2]);
    }
  }
  const double k = ensemble.envelope().least_principal_ratio;
  std::cout << "  tensile limit " << limit << " Pa, cone ratio " << k << " (friction angle "
            << std::asin((1 - k) / (1 + k)) * 180 / M_PI
            << " deg; Drucker-Prager data, c 1 kPa, phi 35 deg)\n";
  EXPECT_NEAR(k, least_ratio, 1e-12);
  // Wider than the soil's 35 deg (0.27): the ratios are measured from the tensile limit (1.2 kPa),
  // not from the Drucker-Prager cone's apex (c cot phi = 1.4 kPa), and stresses near it have
  // small ones. Still a cone, which the returns below tell from the cap alone.
  ASSERT_GT(k, 0.01);

  const Matrix3 rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const auto rotated = [&](const Eigen::Vector3d& values) -> Matrix3 {
    return rotation * values.asDiagonal() * rotation.transpose();
  };
  const auto expect_on_cone = [&](const Matrix3& admissible, const Eigen::Vector3d& mean_of) {
    const Matrix3 principal_frame = rotation.transpose() * admissible * rotation;
    EXPECT_LT((principal_frame - Matrix3(principal_frame.diagonal().asDiagonal())).norm(), 1e-6)
        << "principal directions changed:\n" << principal_frame;
    const Eigen::Vector3d c = CompressionsFrom(limit, admissible);
    EXPECT_NEAR(c[0] / c[2], k, 1e-9);
    EXPECT_NEAR(c.mean(), mean_of.mean(), 1e-6);
  };
  bool capped = false;
  // Tension: capped at the limit (compressions 20 kPa + t, 10 kPa + t, 0), then on the cone.
  const Matrix3 tensile = rotated({-20e3, -10e3, limit + 5e3});
  const Matrix3 admissible = ensemble.Admissible(tensile, &capped);
  EXPECT_TRUE(capped);
  expect_on_cone(admissible, Eigen::Vector3d(20e3 + limit, 10e3 + limit, 0));
  // Compressive but more deviatoric than any training stress.
  const Matrix3 sheared = rotated({limit - 20e3, limit - 10e3, limit - 0.5 * k * 20e3});
  EXPECT_LT(CompressionsFrom(limit, sheared)[0] / CompressionsFrom(limit, sheared)[2], k);
  expect_on_cone(ensemble.Admissible(sheared, &capped), CompressionsFrom(limit, sheared));
  EXPECT_TRUE(capped);
  const Matrix3 inside = rotated({-20e3, -15e3, -12e3});
  EXPECT_EQ(ensemble.Admissible(inside, &capped), inside);
  EXPECT_FALSE(capped);

  const std::filesystem::path directory = std::filesystem::temp_directory_path() /
                                          ("gonogo_ensemble_cap_" + std::to_string(getpid()));
  ensemble.Save(directory.string());
  EXPECT_EQ(SurrogateEnsemble::Load(directory.string()).envelope().tensile_limit_pa, limit);
  EXPECT_EQ(SurrogateEnsemble::Load(directory.string()).envelope().least_principal_ratio, k);
  // The same file as the formats before wrote it: older tag, and the cone (then the cap too)
  // gone from the last doubles (cap, cone, distance threshold, spread threshold).
  const std::filesystem::path envelope = directory / "envelope.bin";
  std::string bytes;
  {
    std::ifstream in(envelope, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_EQ(bytes.compare(0, 8, "GNGENV03"), 0);
  const auto older_format = [&](const char* tag, std::size_t dropped_doubles) {
    std::string older = bytes;
    older.replace(0, 8, tag);
    older.erase(older.size() - 16 - 8 * dropped_doubles, 8 * dropped_doubles);
    std::ofstream(envelope, std::ios::binary | std::ios::trunc) << older;
    SurrogateEnsemble loaded = SurrogateEnsemble::Load(directory.string());
    EXPECT_EQ(loaded.distance_threshold(), ensemble.distance_threshold()) << tag;
    EXPECT_EQ(loaded.spread_threshold(), ensemble.spread_threshold()) << tag;
    return loaded;
  };
  const SurrogateEnsemble without_cone = older_format("GNGENV02", 1);
  EXPECT_EQ(without_cone.envelope().tensile_limit_pa, limit);
  EXPECT_EQ(without_cone.envelope().least_principal_ratio, 0);
  EXPECT_LT((without_cone.Admissible(tensile) - rotated({-20e3, -10e3, limit})).norm(), 1e-8);
  EXPECT_EQ(without_cone.Admissible(sheared), sheared);
  const SurrogateEnsemble without_cap = older_format("GNGENV01", 2);
  EXPECT_TRUE(std::isinf(without_cap.envelope().tensile_limit_pa));
  EXPECT_EQ(without_cap.Admissible(tensile), tensile);
  std::filesystem::remove_all(directory);
}

std::shared_ptr<const material::DruckerPrager> SharedSoil() {
  return std::shared_ptr<const material::DruckerPrager>(&Soil(), [](const auto*) {});
}

std::shared_ptr<const SurrogateEnsemble> SharedEnsemble() {
  return std::shared_ptr<const SurrogateEnsemble>(&Trained(), [](const auto*) {});
}

// Stress error of a path relative to the reference path's stress (ReplayError's measure).
double PathError(const StrainHistory& got, const StrainHistory& reference) {
  double error = 0, size = 0;
  for (std::size_t s = 0; s < std::min(got.steps(), reference.steps()); ++s) {
    error += (material::VoigtToStress(got.stresses_pa[s]) -
              material::VoigtToStress(reference.stresses_pa[s])).norm();
    size += material::VoigtToStress(reference.stresses_pa[s]).norm();
  }
  return error / size;
}

LabPathSpec Triaxial(double pressure_pa) {
  LabPathSpec spec;
  spec.path = LabPath::kTriaxial;
  spec.pressure_pa = pressure_pa;
  spec.max_strain = 0.02;
  spec.steps = 60;
  return spec;
}

// Reads, from an ANN point's committed state, the step it fell back at (-1: on the network).
InternalVariables FellBackAt() {
  InternalVariables internal;
  internal.names = {"fell_back_at_step"};
  internal.read = [](const material::MaterialState& state) {
    return std::vector<double>{
        static_cast<double>(static_cast<const AnnState&>(state).fell_back_at_step)};
  };
  return internal;
}

TEST(AnnMaterial, FollowsTheSoilInsideItsTrainingWithoutFallingBack) {
  const AnnMaterial ann(SharedEnsemble(), SharedSoil());
  // The same servo-controlled test on both: the driver holds the lateral stress with the
  // network's autograd tangent.
  const StrainHistory on_network = RunLabPath(ann, Triaxial(30e3), {}, FellBackAt());
  const StrainHistory on_soil = RunLabPath(Soil(), Triaxial(30e3));
  ASSERT_TRUE(on_network.stopped_reason.empty()) << on_network.stopped_reason;
  const double error = PathError(on_network, on_soil);
  std::cout << "  triaxial at 30 kPa through the seam: " << 100 * error << " % off the soil's\n";
  EXPECT_LT(error, 0.05);
  EXPECT_EQ(on_network.internal_variables.back()[0], -1.0) << "still on the network";
  EXPECT_TRUE(ann.log().fallbacks().empty()) << "not even in a trial";
}

TEST(AnnMaterial, APointDrivenOutOfItsEnvelopeFallsBackToTheRealModel) {
  const AnnMaterial ann(SharedEnsemble(), SharedSoil());
  const StrainHistory history = RunLabPath(ann, Triaxial(800e3), {}, FellBackAt());
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  const double fell_back_at = history.internal_variables.back()[0];
  // The log has every fallback the material made, the driver's discarded trials included.
  const std::vector<FallbackLog::Event> events = ann.log().fallbacks();
  ASSERT_FALSE(events.empty());
  std::cout << "  fell back at its step " << fell_back_at << " of " << history.steps()
            << "; first logged at distance " << events[0].distance << " (threshold "
            << Trained().distance_threshold() << "), " << events.size() << " logged in all\n";
  EXPECT_GE(fell_back_at, 0.0);
  EXPECT_GT(events[0].distance, Trained().distance_threshold());
  // From the fallback on, the point is the soil along the increments it took: the same stress,
  // bit for bit, as the soil driven through those increments from its start.
  std::unique_ptr<material::MaterialState> soil = Soil().InitialState();
  Matrix3 stress = Matrix3::Zero();
  for (const Matrix3& increment : history.increments) {
    std::vector<material::PointResponse> step = Soil().Update({{increment, soil.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk);
    soil = std::move(step[0].state);
    stress = step[0].stress_pa;
  }
  EXPECT_EQ(material::StressToVoigt(stress), history.stresses_pa.back());
  // With the fallback off, the network answers every flagged step and counts it.
  AnnMaterialOptions no_fallback;
  no_fallback.fallback_enabled = false;
  const AnnMaterial alone(SharedEnsemble(), nullptr, no_fallback);
  const StrainHistory unguarded = RunLabPath(alone, Triaxial(800e3));
  std::cout << "  without the fallback: " << unguarded.steps() << " steps, "
            << alone.log().unanswered_flags() << " flags answered by the network; "
            << (unguarded.stopped_reason.empty() ? "ran to the end" : unguarded.stopped_reason)
            << "\n";
  EXPECT_TRUE(alone.log().fallbacks().empty());
  EXPECT_GT(alone.log().unanswered_flags(), 0);
  EXPECT_THROW(AnnMaterial(SharedEnsemble(), nullptr), InputError);
}

TEST(AnnMaterial, StatesSaveAndRestoreOnAndOffTheNetwork) {
  const AnnMaterial ann(SharedEnsemble(), SharedSoil());
  std::unique_ptr<material::MaterialState> state = ann.InitialState();
  Matrix3 increment = Matrix3::Zero();
  increment(2, 2) = -1e-4;
  increment(0, 2) = 2e-4;
  for (int s = 0; s < 5; ++s) {
    std::vector<material::PointResponse> step = ann.Update({{increment, state.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk) << step[0].reason;
    state = std::move(step[0].state);
  }
  const std::string on_network = state->Serialize();
  EXPECT_EQ(ann.RestoreState(on_network)->Serialize(), on_network);
  EXPECT_EQ(static_cast<const AnnState&>(*ann.RestoreState(on_network)).steps(), 5);
  // A huge jump leaves the envelope: the point falls back and keeps its fallback state.
  std::vector<material::PointResponse> jump = ann.Update({{increment * 40, state.get()}}, true);
  ASSERT_EQ(jump[0].status, material::UpdateStatus::kOk) << jump[0].reason;
  EXPECT_TRUE(jump[0].has_tangent);
  const auto& fallen = static_cast<const AnnState&>(*jump[0].state);
  ASSERT_NE(fallen.fallback, nullptr);
  EXPECT_EQ(fallen.fell_back_at_step, 5);
  const std::string off_network = fallen.Serialize();
  EXPECT_EQ(ann.RestoreState(off_network)->Serialize(), off_network);
  EXPECT_THROW(ann.RestoreState(off_network.substr(0, off_network.size() - 3)), InputError);
  EXPECT_THROW(ann.RestoreState("not a state"), InputError);
}

// A compression with shear inside the envelope, along which a point stays on the network.
Matrix3 SmallShear() {
  Matrix3 increment = Matrix3::Zero();
  increment(2, 2) = -1e-4;
  increment(0, 2) = 2e-4;
  return increment;
}

// Five small shears, a jump 40 times larger that leaves the envelope, six half shears.
std::vector<Matrix3> OutOfTheEnvelopeAndBack() {
  std::vector<Matrix3> increments(5, SmallShear());
  increments.push_back(SmallShear() * 40);
  for (int s = 0; s < 6; ++s) increments.push_back(SmallShear() * 0.5);
  return increments;
}

// With the return on, a point that fell back goes back to the network once the ensemble would not
// have flagged its increments `return_after_steps` times in a row: until then the soil answers
// (its stress bit for bit the soil's along the same increments), from then the network, starting
// from the soil's stress. With the return off the point stays on the soil. A state half-way to
// its return saves and restores with its count; a state of the format before the count reads.
TEST(AnnMaterial, AFallenBackPointReturnsToTheNetworkOnceBackInside) {
  const std::vector<Matrix3> increments = OutOfTheEnvelopeAndBack();
  struct Walked {
    std::vector<std::unique_ptr<material::MaterialState>> states;  // after each increment
    std::vector<Matrix3> stresses;
  };
  const auto walk = [&](const material::ConstitutiveModel& model) {
    Walked walked;
    std::unique_ptr<material::MaterialState> state = model.InitialState();
    for (const Matrix3& step : increments) {
      std::vector<material::PointResponse> answer = model.Update({{step, state.get()}}, false);
      EXPECT_EQ(answer[0].status, material::UpdateStatus::kOk) << answer[0].reason;
      if (answer[0].status != material::UpdateStatus::kOk) break;
      state = std::move(answer[0].state);
      walked.stresses.push_back(answer[0].stress_pa);
      walked.states.push_back(state->Clone());
    }
    return walked;
  };
  const Walked soil = walk(Soil());
  AnnMaterialOptions returning;
  returning.return_after_steps = 3;
  const AnnMaterial ann(SharedEnsemble(), SharedSoil(), returning);
  const Walked on_ann = walk(ann);
  ASSERT_EQ(on_ann.states.size(), increments.size());
  const auto ann_state = [&](std::size_t s) -> const AnnState& {
    return static_cast<const AnnState&>(*on_ann.states[s]);
  };
  ASSERT_EQ(ann_state(4).fallback, nullptr) << "on the network before the jump";
  ASSERT_NE(ann_state(5).fallback, nullptr) << "the jump falls back";
  EXPECT_EQ(ann_state(5).fell_back_at_step, 5);
  // Three steps back inside: the soil answers them, and after the third the point is back.
  for (std::size_t s = 5; s <= 8; ++s) {
    EXPECT_EQ(on_ann.stresses[s], soil.stresses[s]) << "step " << s + 1 << " is the soil's";
  }
  EXPECT_NE(ann_state(6).fallback, nullptr);
  EXPECT_EQ(ann_state(6).unflagged_on_fallback, 1);
  EXPECT_NE(ann_state(7).fallback, nullptr);
  EXPECT_EQ(ann_state(7).unflagged_on_fallback, 2);
  EXPECT_EQ(ann_state(8).fallback, nullptr) << "back on the network after three unflagged steps";
  EXPECT_EQ(ann.log().returns(), 1);
  EXPECT_EQ(ann.log().fallbacks().size(), 1u);
  // The network answers the next steps from the soil's stress: close to the soil, not equal.
  EXPECT_NE(on_ann.stresses[9], soil.stresses[9]);
  EXPECT_LT((on_ann.stresses[9] - soil.stresses[9]).norm(), 0.1 * soil.stresses[9].norm());
  std::cout << "  back on the network at step 9; step 10 " << 100 * (on_ann.stresses[9] - soil.stresses[9]).norm() / soil.stresses[9].norm()
            << " % off the soil's\n";
  // Half-way to its return, a state saves and restores with its count.
  const std::string halfway = ann_state(7).Serialize();
  EXPECT_EQ(halfway.substr(0, 8), "GNGANN04");
  const auto restored = ann.RestoreState(halfway);
  EXPECT_EQ(static_cast<const AnnState&>(*restored).unflagged_on_fallback, 2);
  EXPECT_EQ(restored->Serialize(), halfway);
  // The format before the count (GNGANN03): the same bytes less the count, read as 0.
  const std::size_t count_at = 8 + 9 * 8 + 6 * 8 + 8 + 8 + 8;  // tag, stress, strain, V = 0, flags, step
  std::string older = halfway;
  older.replace(0, 8, "GNGANN03");
  older.erase(count_at, 8);
  const auto read = ann.RestoreState(older);
  EXPECT_EQ(static_cast<const AnnState&>(*read).unflagged_on_fallback, 0);
  EXPECT_NE(static_cast<const AnnState&>(*read).fallback, nullptr);
  // With the return off, the point stays on the soil to the end.
  const AnnMaterial staying(SharedEnsemble(), SharedSoil());
  const Walked on_staying = walk(staying);
  ASSERT_EQ(on_staying.states.size(), increments.size());
  EXPECT_NE(static_cast<const AnnState&>(*on_staying.states.back()).fallback, nullptr);
  EXPECT_EQ(on_staying.stresses.back(), soil.stresses.back());
  EXPECT_EQ(staying.log().returns(), 0);
}

// Recording: each fallen-back point's path on the real model is kept, from the point's start
// through the replay to its last step there, bit for bit the soil's along the same increments;
// the answers are those of the material that does not record; a point on the network leaves no
// path; a point that returns and falls back again leaves one path (the longer); a fallen-back
// state restored from its bytes is answered and not recorded.
TEST(AnnMaterial, RecordsEachFallenBackPointsPathOnTheRealModel) {
  const Matrix3 increment = SmallShear();
  std::vector<Matrix3> leaving = OutOfTheEnvelopeAndBack();
  // Both points in each batch, as the FE asks (the second takes `increment` at every step); the
  // stresses after each step, by point.
  const auto walk = [&](const material::ConstitutiveModel& model,
                        std::vector<std::unique_ptr<material::MaterialState>> states,
                        std::size_t first_step) {
    std::vector<std::vector<Matrix3>> stresses(2);
    for (std::size_t s = first_step; s < leaving.size(); ++s) {
      std::vector<material::PointResponse> answers =
          model.Update({{leaving[s], states[0].get()}, {increment, states[1].get()}}, false);
      for (int p = 0; p < 2; ++p) {
        EXPECT_EQ(answers[p].status, material::UpdateStatus::kOk) << answers[p].reason;
        if (answers[p].status != material::UpdateStatus::kOk) return stresses;
        states[p] = std::move(answers[p].state);
        stresses[p].push_back(answers[p].stress_pa);
      }
    }
    return stresses;
  };
  const auto fresh = [](const material::ConstitutiveModel& model) {
    std::vector<std::unique_ptr<material::MaterialState>> states;
    states.push_back(model.InitialState());
    states.push_back(model.InitialState());
    return states;
  };
  AnnMaterialOptions recording;
  recording.record_fallback_paths = true;
  const AnnMaterial recorded(SharedEnsemble(), SharedSoil(), recording);
  const AnnMaterial plain(SharedEnsemble(), SharedSoil());
  const auto recorded_stresses = walk(recorded, fresh(recorded), 0);
  EXPECT_EQ(recorded_stresses, walk(plain, fresh(plain), 0)) << "recording changes no answer";
  EXPECT_TRUE(plain.FallbackPaths().empty());
  const std::vector<StrainHistory> paths = recorded.FallbackPaths();
  ASSERT_EQ(paths.size(), 1u) << "the point that left; the one on the network leaves no path";
  const StrainHistory& path = paths[0];
  ASSERT_EQ(path.increments, leaving);
  EXPECT_EQ(path.initial_stress_pa,
            material::StressOfState(Soil(), *Soil().InitialState(), "soil's start"));
  // The soil's own path along the same increments, bit for bit.
  std::unique_ptr<material::MaterialState> soil = Soil().InitialState();
  for (std::size_t s = 0; s < leaving.size(); ++s) {
    std::vector<material::PointResponse> step = Soil().Update({{leaving[s], soil.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk);
    soil = std::move(step[0].state);
    EXPECT_EQ(path.stresses_pa[s], material::StressToVoigt(step[0].stress_pa)) << "step " << s + 1;
  }
  EXPECT_TRUE(path.internal_variable_names.empty()) << "the ensemble carries none";
  // A point that returns and falls back again leaves one path, its whole history.
  AnnMaterialOptions returning = recording;
  returning.return_after_steps = 3;
  const AnnMaterial twice(SharedEnsemble(), SharedSoil(), returning);
  leaving.push_back(increment * 40);  // leaves again, after its return at step 9
  leaving.push_back(increment * 0.5);
  walk(twice, fresh(twice), 0);
  EXPECT_EQ(twice.log().fallbacks().size(), 2u);
  EXPECT_EQ(twice.log().returns(), 1);
  const std::vector<StrainHistory> twice_paths = twice.FallbackPaths();
  ASSERT_EQ(twice_paths.size(), 1u);
  EXPECT_EQ(twice_paths[0].increments, leaving);
  // Restored from its bytes mid-fallback (a resumed run), a point goes on unrecorded.
  const AnnMaterial resumed(SharedEnsemble(), SharedSoil(), recording);
  std::unique_ptr<material::MaterialState> state = resumed.InitialState();
  for (std::size_t s = 0; s < 7; ++s) {
    std::vector<material::PointResponse> step = resumed.Update({{leaving[s], state.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk) << step[0].reason;
    state = std::move(step[0].state);
  }
  ASSERT_EQ(resumed.FallbackPaths().size(), 1u);
  std::vector<std::unique_ptr<material::MaterialState>> restored;
  restored.push_back(resumed.RestoreState(state->Serialize()));
  restored.push_back(resumed.InitialState());
  ASSERT_NE(static_cast<const AnnState&>(*restored[0]).fallback, nullptr);
  walk(resumed, std::move(restored), 7);
  ASSERT_EQ(resumed.FallbackPaths().size(), 1u);
  EXPECT_EQ(resumed.FallbackPaths()[0].steps(), 7u) << "the path before the restore, no more";
  // Recording needs a model to record.
  AnnMaterialOptions nothing_to_record = recording;
  nothing_to_record.fallback_enabled = false;
  EXPECT_THROW(AnnMaterial(SharedEnsemble(), nullptr, nothing_to_record), InputError);
}

// MlpArchitecture::previous_direction at the seam: the material gives the network each point's
// last increment's direction (zero before the first), so a point driven along a shear answers as
// the ensemble replays the shear with the directions (to rounding), and not as it would with none.
TEST(AnnMaterial, GivesANetworkThatReadsItThePointsPreviousDirection) {
  TrainingOptions options;
  options.epochs = 40;
  options.batch_size = 64;
  MlpArchitecture architecture;
  architecture.hidden_widths = {16, 16};
  architecture.previous_direction = true;
  const auto ensemble = std::make_shared<const SurrogateEnsemble>(
      SurrogateEnsemble::Train(TrainingPaths(), architecture, options));
  AnnMaterialOptions material_options;
  material_options.fallback_enabled = false;  // the network answers every step
  const AnnMaterial ann(ensemble, SharedSoil(), material_options);
  const StrainHistory shear = Path(LabPath::kSimpleShear, 25e3, 0.04);
  std::unique_ptr<material::MaterialState> state = ann.InitialState();
  std::vector<Vector6> on_material;
  for (const Matrix3& increment : shear.increments) {
    std::vector<material::PointResponse> step = ann.Update({{increment, state.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk) << step[0].reason;
    state = std::move(step[0].state);
    on_material.push_back(material::StressToVoigt(static_cast<const AnnState&>(*state).stress_pa));
  }
  const std::vector<Vector6> replayed = Replay(*ensemble, shear);
  const std::vector<Vector6> without = Replay(
      [&](SurrogateInput input) {
        input.previous_direction.setZero();
        const EnsembleAnswer answer = ensemble->Answer({input}, false)[0];
        return SurrogateOutput{answer.stress_increment_pa, answer.internal_variable_increments};
      },
      shear, {}, [&](const Matrix3& stress_pa) { return ensemble->Admissible(stress_pa); });
  double largest = 0, off = 0, off_without = 0;
  for (std::size_t s = 0; s < shear.steps(); ++s) {
    largest = std::max(largest, replayed[s].cwiseAbs().maxCoeff());
    off = std::max(off, (on_material[s] - replayed[s]).cwiseAbs().maxCoeff());
    off_without = std::max(off_without, (on_material[s] - without[s]).cwiseAbs().maxCoeff());
  }
  std::cout << "  a shear at 25 kPa through the seam: " << off << " Pa from the ensemble's replay "
            << "with the directions, " << off_without << " Pa from one without (largest stress "
            << largest << " Pa)\n";
  EXPECT_LT(off, 1e-9 * largest);
  EXPECT_GT(off_without, 1e-3 * largest);
}

// An ensemble that carries an internal variable (Drucker-Prager's equivalent plastic strain):
// its envelope covers the carried input, it saves and loads whole, and the ANN material takes the
// variable from the real model's state a point starts from and carries it step by step, close to
// the soil's along a shear past yield; a state saves and restores with it. Without a reader of the
// real state, or with one that does not read the variable, the material is refused by name.
TEST(AnnMaterial, CarriesTheEnsemblesInternalVariableFromTheRealModelsState) {
  const InternalVariables plastic = testing::PlasticStrain();
  TrainingOptions options;
  options.epochs = 100;
  options.batch_size = 64;
  MlpArchitecture architecture;
  architecture.carried_variables = plastic.names;
  const auto ensemble = std::make_shared<const SurrogateEnsemble>(
      SurrogateEnsemble::Train(TrainingPaths(plastic), architecture, options));
  EXPECT_EQ(ensemble->carried_variables(), plastic.names);
  EXPECT_EQ(ensemble->envelope().offset.size(), 19);

  const std::filesystem::path directory = std::filesystem::temp_directory_path() /
                                          ("gonogo_carrying_" + std::to_string(getpid()));
  ensemble->Save(directory.string());
  const SurrogateEnsemble loaded = SurrogateEnsemble::Load(directory.string());
  std::filesystem::remove_all(directory);
  const StrainHistory shear = Path(LabPath::kSimpleShear, 25e3, 0.04, 1, plastic);
  const std::vector<SurrogateInput> inputs = InputsOf(shear, plastic.names);
  const std::vector<EnsembleAnswer> a = ensemble->Answer(inputs, false);
  const std::vector<EnsembleAnswer> b = loaded.Answer(inputs, false);
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    EXPECT_EQ(a[n].stress_increment_pa, b[n].stress_increment_pa);
    EXPECT_EQ(a[n].internal_variable_increments, b[n].internal_variable_increments);
    EXPECT_EQ(a[n].distance, b[n].distance);
  }
  EXPECT_LT(FlaggedFraction(a), 0.1) << "a path like the training's";
  SurrogateInput unyielded_far = inputs.back();
  unyielded_far.internal_variables[0] = 1.0;  // a plastic strain no path reached
  EXPECT_GT(ensemble->Answer({unyielded_far}, false)[0].distance, ensemble->distance_threshold());

  const auto field_of = [&](const AnnMaterialOptions& material_options) {
    try {
      AnnMaterial(ensemble, SharedSoil(), material_options);
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("(nothing thrown)");
  };
  EXPECT_EQ(field_of({}), "internal_variables");
  AnnMaterialOptions other_reader;
  other_reader.internal_variables = FellBackAt();
  EXPECT_EQ(field_of(other_reader), "internal_variables");

  AnnMaterialOptions material_options;
  material_options.internal_variables = plastic;
  // The network answers every step (a flagged one too, counted): what is checked is its carrying.
  material_options.fallback_enabled = false;
  const AnnMaterial ann(ensemble, SharedSoil(), material_options);
  std::unique_ptr<material::MaterialState> state = ann.InitialState();
  ASSERT_EQ(static_cast<const AnnState&>(*state).internal_variables.size(), 1);
  EXPECT_EQ(static_cast<const AnnState&>(*state).internal_variables[0], 0.0);
  for (const Matrix3& increment : shear.increments) {
    std::vector<material::PointResponse> step = ann.Update({{increment, state.get()}}, false);
    ASSERT_EQ(step[0].status, material::UpdateStatus::kOk) << step[0].reason;
    state = std::move(step[0].state);
  }
  const auto& end = static_cast<const AnnState&>(*state);
  const double soil = shear.internal_variables.back()[0];
  std::cout << "  plastic strain carried along the shear at 25 kPa: " << end.internal_variables[0]
            << " (the soil's " << soil << "); " << ann.log().unanswered_flags()
            << " steps flagged\n";
  EXPECT_NEAR(end.internal_variables[0], soil, 0.15 * soil);
  const std::string bytes = end.Serialize();
  const std::unique_ptr<material::MaterialState> restored_state = ann.RestoreState(bytes);
  const auto& restored = static_cast<const AnnState&>(*restored_state);
  EXPECT_EQ(restored.internal_variables, end.internal_variables);
  EXPECT_EQ(restored.Serialize(), bytes);
  // A state saved by a material whose ensemble carries nothing is not this material's.
  const AnnMaterial plain(SharedEnsemble(), SharedSoil());
  EXPECT_THROW(ann.RestoreState(plain.InitialState()->Serialize()), InputError);
  EXPECT_THROW(plain.RestoreState(bytes), InputError);
}

}  // namespace
}  // namespace gonogo::ann
