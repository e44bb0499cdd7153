// Laboratory paths on one material point (solvers/ann/lab_paths.h) against closed forms of linear
// elasticity and of Drucker-Prager in drained triaxial compression, their histories' storage and
// export (read back by NumPy), and a short drained triaxial on a DE RVE.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "solvers/ann/lab_paths.h"
#include "solvers/ann/path_recorder.h"
#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/common/soil_model.h"
#include "solvers/dem/rve/rve_material.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/material/linear_elastic.h"
#include "tests/solvers/ann/drucker_prager_paths.h"

namespace gonogo::ann {
namespace {

material::LinearElasticParams Elastic() {
  material::LinearElasticParams params;
  params.young_pa = 20e6;
  params.poisson = 0.3;
  return params;
}

// The Hughes-Winget strain of an increment (what the model integrated).
Matrix3 StrainOf(const Matrix3& increment) {
  return material::HughesWinget(increment).strain_increment;
}

TEST(LabPaths, AnElasticPointSettlesThenFollowsTheIsotropicPathInClosedForm) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kIsotropic;
  spec.pressure_pa = 20e3;
  spec.max_strain = 0.003;
  spec.steps = 30;
  const StrainHistory history = RunLabPath(model, spec);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  ASSERT_EQ(history.steps(), 5u + 30u + 15u);
  const Vector6 settled = history.stresses_pa[4];
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(settled[c], -20e3, 2.0);
  // Loading by volumetric strain 0.003: p rises by K x 0.003; unloading by half of it.
  const double bulk = Elastic().bulk_pa();
  const Vector6 loaded = history.stresses_pa[34];
  const Vector6 unloaded = history.stresses_pa.back();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(loaded[c], -20e3 - bulk * 0.003, 1e-6 * bulk * 0.003) << c;
    EXPECT_NEAR(unloaded[c], -20e3 - bulk * 0.0015, 1e-6 * bulk * 0.003) << c;
  }
  for (int c = 3; c < 6; ++c) EXPECT_NEAR(loaded[c], 0.0, 1e-6);
}

TEST(LabPaths, AnElasticDrainedTriaxialHoldsItsLateralStressAndLoadsAxiallyWithYoungsModulus) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kTriaxial;
  spec.pressure_pa = 10e3;
  spec.max_strain = 0.002;
  spec.steps = 20;
  const StrainHistory history = RunLabPath(model, spec);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  Matrix3 strain = Matrix3::Zero();
  for (std::size_t s = 5; s < history.steps(); ++s) {
    strain += StrainOf(history.increments[s]);
    EXPECT_NEAR(history.stresses_pa[s][0], -10e3, 1.0) << s;
    EXPECT_NEAR(history.stresses_pa[s][1], -10e3, 1.0) << s;
  }
  EXPECT_NEAR(strain(2, 2), -0.002, 1e-12);
  EXPECT_NEAR(history.stresses_pa.back()[2], -10e3 - 20e6 * 0.002, 2.0);
  EXPECT_NEAR(strain(0, 0), 0.3 * 0.002, 1e-7);  // lateral strain -nu eps_a
}

TEST(LabPaths, ADruckerPragerTriaxialPeaksAtTheMohrCoulombLimitAndDilatesAtPsi) {
  material::DruckerPragerParams params;
  params.young_pa = 20e6;
  params.poisson = 0.25;
  params.cohesion_pa = 2e3;
  params.friction_angle_deg = 35;
  params.dilation_angle_deg = 10;
  const material::DruckerPrager model(params);
  LabPathSpec spec;
  spec.path = LabPath::kTriaxial;
  spec.pressure_pa = 30e3;
  spec.max_strain = 0.02;
  spec.steps = 100;
  const StrainHistory history = RunLabPath(model, spec);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  const double sin_phi = std::sin(units::DegreesToRadians(35.0));
  const double sin_psi = std::sin(units::DegreesToRadians(10.0));
  const double n = (1 + sin_phi) / (1 - sin_phi);
  const double peak_q = (n - 1) * 30e3 + 2 * 2e3 * std::sqrt(n);
  const Vector6 last = history.stresses_pa.back();
  EXPECT_NEAR(last[0] - last[2], peak_q, 1e-3 * peak_q);  // q = sigma_3 - sigma_1, tension +
  // Past the yield (reached at eps_a = q / E, 0.5 %), d eps_v / d eps_a = -2 sin psi / (1 - sin psi)
  // (compression positive), over the last half of the test.
  double axial = 0, volumetric = 0;
  for (std::size_t s = history.steps() - 50; s < history.steps(); ++s) {
    const Matrix3 strain = StrainOf(history.increments[s]);
    axial -= strain(2, 2);
    volumetric -= strain.trace();
  }
  EXPECT_NEAR(volumetric / axial, -2 * sin_psi / (1 - sin_psi), 1e-3);
}

TEST(LabPaths, AnElasticSimpleShearHoldsTheNormalStressAndShearsWithG) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kSimpleShear;
  spec.pressure_pa = 10e3;
  spec.max_strain = 1e-3;
  spec.steps = 10;
  const StrainHistory history = RunLabPath(model, spec);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  const Vector6 last = history.stresses_pa.back();
  EXPECT_NEAR(last[2], -10e3, 1.0);
  // tau = G gamma to first order; the rotation of the stress adds O(gamma^2 sigma).
  EXPECT_NEAR(last[4], Elastic().shear_pa() * 1e-3, 1e-3 * Elastic().shear_pa() * 1e-3 + 20);
  // u_x = gamma z: dH_xz = gamma per step, dH_zx = 0 (strain plus spin).
  EXPECT_NEAR(history.increments.back()(0, 2), 1e-4, 1e-9);
  EXPECT_NEAR(history.increments.back()(2, 0), 0.0, 1e-9);
}

TEST(LabPaths, UnloadReloadUnloadsThenReloadsPastItsFirstLoad) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kUnloadReload;
  spec.pressure_pa = 10e3;
  spec.max_strain = 0.002;
  spec.steps = 60;
  const StrainHistory history = RunLabPath(model, spec);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  ASSERT_EQ(history.steps(), 5u + 20u + 10u + 30u);
  const double loaded = history.stresses_pa[24][2], unloaded = history.stresses_pa[34][2];
  const double reloaded = history.stresses_pa.back()[2];
  EXPECT_NEAR(loaded, -10e3 - 20e6 * 0.001, 2.0);
  EXPECT_NEAR(unloaded, -10e3 - 20e6 * 0.0005, 2.0);
  EXPECT_NEAR(reloaded, -10e3 - 20e6 * 0.002, 2.0);
}

TEST(LabPaths, ARandomWalkIsSeededAndStaysInItsEnvelope) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kRandomWalk;
  spec.pressure_pa = 10e3;
  spec.max_strain = 0.004;
  spec.walk_step_strain = 1e-3;
  spec.steps = 200;
  spec.seed = 7;
  const StrainHistory a = RunLabPath(model, spec), b = RunLabPath(model, spec);
  ASSERT_TRUE(a.stopped_reason.empty()) << a.stopped_reason;
  EXPECT_EQ(SerializeHistory(a), SerializeHistory(b));
  spec.seed = 8;
  EXPECT_NE(SerializeHistory(RunLabPath(model, spec)), SerializeHistory(a));
  Vector6 walked = Vector6::Zero(), largest = Vector6::Zero();
  for (std::size_t s = 5; s < a.steps(); ++s) {
    walked += material::StrainToVoigt(StrainOf(a.increments[s]));
    largest = largest.cwiseMax(walked.cwiseAbs());
  }
  for (int c = 0; c < 6; ++c) {
    EXPECT_LE(largest[c], 0.004 * (1 + 1e-3)) << c;
    EXPECT_GT(largest[c], 0.002) << c << ": the walk reaches out";
  }
}

// The mean cosine between consecutive strain increments of a walk, after its settling.
double MeanConsecutiveCosine(const StrainHistory& walk, std::size_t settle_steps) {
  double sum = 0;
  int pairs = 0;
  for (std::size_t s = settle_steps + 1; s < walk.steps(); ++s) {
    const Vector6 a = material::StrainToVoigt(StrainOf(walk.increments[s - 1]));
    const Vector6 b = material::StrainToVoigt(StrainOf(walk.increments[s]));
    sum += a.dot(b) / (a.norm() * b.norm());
    ++pairs;
  }
  return sum / pairs;
}

TEST(LabPaths, APersistentWalkLoadsOnBeforeItTurnsAndStaysInItsEnvelope) {
  const material::LinearElastic model(Elastic());
  LabPathSpec spec;
  spec.path = LabPath::kRandomWalk;
  spec.max_strain = 0.05;  // room to walk on: few reflections
  spec.steps = 400;
  spec.seed = 7;
  const StrainHistory fresh = RunLabPath(model, spec);
  spec.walk_persistence = 0.9;
  const StrainHistory persistent = RunLabPath(model, spec);
  ASSERT_TRUE(persistent.stopped_reason.empty()) << persistent.stopped_reason;
  // Uncorrelated directions: only the compressive drift (a twelfth of a step on each normal
  // strain) correlates consecutive steps, by about 3 / 144. rho 0.9: about 0.9.
  EXPECT_LT(std::abs(MeanConsecutiveCosine(fresh, 5)), 0.1);
  EXPECT_GT(MeanConsecutiveCosine(persistent, 5), 0.7);

  spec.max_strain = 0.004;  // reflected at the bounds as an uncorrelated walk is
  const StrainHistory bounded = RunLabPath(model, spec);
  Vector6 walked = Vector6::Zero(), largest = Vector6::Zero();
  for (std::size_t s = 5; s < bounded.steps(); ++s) {
    walked += material::StrainToVoigt(StrainOf(bounded.increments[s]));
    largest = largest.cwiseMax(walked.cwiseAbs());
  }
  for (int c = 0; c < 6; ++c) EXPECT_LE(largest[c], 0.004 * (1 + 1e-3)) << c;
}

TEST(LabPaths, AStepTheDriverCannotHoldEndsTheHistoryWithItsReason) {
  material::DruckerPragerParams params;
  params.young_pa = 20e6;
  params.poisson = 0.25;
  params.friction_angle_deg = 30;
  const material::DruckerPrager model(params);
  LabPathSpec spec;
  spec.path = LabPath::kTriaxial;
  spec.max_strain = 0.02;
  DriverOptions one_try;
  one_try.max_iterations = 1;  // the lateral stress moves once the axial strain does
  const StrainHistory history = RunLabPath(model, spec, one_try);
  EXPECT_NE(history.stopped_reason.find("did not converge"), std::string::npos)
      << history.stopped_reason;
  EXPECT_EQ(history.steps(), history.stresses_pa.size());
  EXPECT_LT(history.steps(), 55u);
}

TEST(LabPaths, BadSpecificationsAreRefusedByName) {
  const material::LinearElastic model(Elastic());
  auto field_of = [&](LabPathSpec spec) {
    try {
      RunLabPath(model, spec);
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("none");
  };
  LabPathSpec spec;
  spec.pressure_pa = -1;
  EXPECT_EQ(field_of(spec), "path.pressure_pa");
  spec = {};
  spec.max_strain = 0.9;
  EXPECT_EQ(field_of(spec), "path.max_strain");
  spec = {};
  spec.steps = 0;
  EXPECT_EQ(field_of(spec), "path.steps");
  spec = {};
  spec.walk_step_strain = 1.0;
  EXPECT_EQ(field_of(spec), "path.walk_step_strain");
  spec = {};
  spec.walk_persistence = 1.0;
  EXPECT_EQ(field_of(spec), "path.walk_persistence");
  EXPECT_EQ(ParseLabPath("simple-shear", "path"), LabPath::kSimpleShear);
  for (LabPath path : AllLabPaths()) EXPECT_EQ(ParseLabPath(LabPathName(path), "p"), path);
  try {
    ParseLabPath("oedometer", "dataset.path");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "dataset.path");
    EXPECT_NE(std::string(e.what()).find("random-walk"), std::string::npos) << e.what();
  }
}

StrainHistory SmallHistory() {
  StrainHistory history;
  history.initial_stress_pa = Matrix3::Identity() * -1e3;
  history.internal_variable_names = {"solid_fraction", "coordination"};
  for (int s = 0; s < 3; ++s) {
    Matrix3 increment = Matrix3::Zero();
    increment(0, 2) = 1e-4 * (s + 1);
    increment(2, 2) = -2e-4;
    history.increments.push_back(increment);
    Vector6 stress;
    stress << -1e3 - s, -1e3, -2e3 - 10 * s, 0.5, 100.0 * s, 0.25;
    history.stresses_pa.push_back(stress);
    history.internal_variables.push_back({0.6 + 0.01 * s, 5.5});
  }
  return history;
}

TEST(StrainHistories, RoundTripBitForBitAndRefuseDamagedBytes) {
  const StrainHistory history = SmallHistory();
  const std::string bytes = SerializeHistory(history);
  EXPECT_EQ(bytes.size(), 8u + 72u + 8u + 2 * 8u + 14u + 12u + 8u + 8u + 3 * 8u * (9 + 6 + 2));
  const StrainHistory back = ParseHistory(bytes);
  EXPECT_EQ(SerializeHistory(back), bytes);
  EXPECT_EQ(back.internal_variable_names, history.internal_variable_names);
  EXPECT_EQ(back.increments[2], history.increments[2]);
  for (std::size_t cut : {std::size_t{4}, bytes.size() / 2, bytes.size() - 1}) {
    try {
      ParseHistory(bytes.substr(0, cut));
      FAIL() << cut;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "history") << e.what();
    }
  }
  EXPECT_THROW(ParseHistory(bytes + "x"), InputError);
  std::string foreign = bytes;
  foreign[0] = 'X';
  EXPECT_THROW(ParseHistory(foreign), InputError);
  // Without initial internal variables the bytes are the first format's (the data hashes of
  // histories recorded before them stay); with them, the second's, 8 bytes a variable longer.
  EXPECT_EQ(bytes.substr(0, 8), "GNGHIS01");
  StrainHistory with_start = history;
  with_start.initial_internal_variables = {0.55, 5.0};
  const std::string started = SerializeHistory(with_start);
  EXPECT_EQ(started.substr(0, 8), "GNGHIS02");
  EXPECT_EQ(started.size(), bytes.size() + 2 * 8u);
  EXPECT_EQ(ParseHistory(started).initial_internal_variables, with_start.initial_internal_variables);
  EXPECT_EQ(SerializeHistory(ParseHistory(started)), started);
  EXPECT_THROW(ParseHistory(started.substr(0, started.size() - 1)), InputError);
  with_start.initial_internal_variables = {0.55};
  EXPECT_THROW(SerializeHistory(with_start), InputError) << "one per name";
}

// Drives `model` from its initial state through `history`'s increments; the stresses after each.
std::vector<Matrix3> Drive(const material::ConstitutiveModel& model, const StrainHistory& history) {
  std::unique_ptr<material::MaterialState> state = model.InitialState();
  std::vector<Matrix3> stresses;
  for (const Matrix3& increment : history.increments) {
    std::vector<material::PointResponse> response = model.Update({{increment, state.get()}}, false);
    EXPECT_EQ(response[0].status, material::UpdateStatus::kOk);
    stresses.push_back(response[0].stress_pa);
    state = std::move(response[0].state);
  }
  return stresses;
}

// A simple shear of `soil` at 20 kPa to gamma 0.02 in 30 steps: past Drucker-Prager's yield.
StrainHistory SimpleShearPastYield(const material::ConstitutiveModel& soil) {
  LabPathSpec spec;
  spec.path = LabPath::kSimpleShear;
  spec.pressure_pa = 20e3;
  spec.max_strain = 0.02;
  spec.steps = 30;
  return RunLabPath(soil, spec);
}

// A PathRecorder answers with the model it wraps and keeps each point's increments, the stresses
// after them and, when asked, what it reads of the wrapped state after each step: here
// Drucker-Prager's equivalent plastic strain, which a simple shear past yield makes grow.
TEST(PathRecorder, RecordsEachStepWithTheInternalVariablesItIsAskedFor) {
  const material::DruckerPrager& soil = testing::Soil();
  const StrainHistory shear = SimpleShearPastYield(soil);
  ASSERT_TRUE(shear.stopped_reason.empty()) << shear.stopped_reason;
  const std::shared_ptr<const material::ConstitutiveModel> unowned(
      &soil, [](const material::ConstitutiveModel*) {});
  InternalVariables plastic_strain;
  plastic_strain.names = {"equivalent_plastic_strain"};
  plastic_strain.read = [](const material::MaterialState& state) {
    return std::vector<double>{
        static_cast<const material::DruckerPragerState&>(state).equivalent_plastic_strain()};
  };
  const PathRecorder recorder(unowned, plastic_strain);
  const PathRecorder plain(unowned);
  const std::vector<Matrix3> driven = Drive(recorder, shear);
  EXPECT_EQ(driven, Drive(soil, shear)) << "a recorded run is the run";
  Drive(plain, shear);

  const std::vector<StrainHistory> recorded = recorder.Histories();
  ASSERT_EQ(recorded.size(), 1u);
  const StrainHistory& path = recorded[0];
  ASSERT_EQ(path.steps(), shear.steps());
  EXPECT_EQ(path.internal_variable_names, plastic_strain.names);
  ASSERT_EQ(path.internal_variables.size(), path.steps());
  std::unique_ptr<material::MaterialState> state = soil.InitialState();
  for (std::size_t k = 0; k < path.steps(); ++k) {
    EXPECT_EQ(path.increments[k], shear.increments[k]);
    EXPECT_EQ(path.stresses_pa[k], material::StressToVoigt(driven[k]));
    state = std::move(soil.Update({{shear.increments[k], state.get()}}, false)[0].state);
    EXPECT_EQ(path.internal_variables[k],
              std::vector<double>{static_cast<const material::DruckerPragerState&>(*state)
                                      .equivalent_plastic_strain()});
  }
  EXPECT_GT(path.internal_variables.back()[0], 1e-3) << "the shear did not yield";
  EXPECT_EQ(path.initial_internal_variables, std::vector<double>{0.0}) << "read at the start";
  EXPECT_EQ(RunLabPath(soil, LabPathSpec{}, {}, plastic_strain).initial_internal_variables,
            std::vector<double>{0.0});
  EXPECT_TRUE(plain.Histories().at(0).internal_variable_names.empty());
  EXPECT_TRUE(plain.Histories().at(0).internal_variables.empty());
  EXPECT_TRUE(plain.Histories().at(0).initial_internal_variables.empty());
}

// A rotated copy is the same path in a turned frame: a quarter turn about z swaps xx and yy and
// turns xz into yz; an isotropic model (Drucker-Prager) driven along a copy's increments answers
// the copy's stresses, so the copies are data of the same soil; copies are seeded, counted and
// bounded.
TEST(StrainHistories, RotatedCopiesAreThePathsOfTheSameIsotropicSoilInTurnedFrames) {
  const material::DruckerPrager& soil = testing::Soil();
  const StrainHistory shear = SimpleShearPastYield(soil);
  ASSERT_TRUE(shear.stopped_reason.empty()) << shear.stopped_reason;

  Matrix3 quarter_turn;
  quarter_turn << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const StrainHistory turned = Rotated(shear, quarter_turn);
  const Vector6& last = shear.stresses_pa.back();       // xx yy zz yz xz xy
  const Vector6& last_turned = turned.stresses_pa.back();
  EXPECT_DOUBLE_EQ(last_turned[0], last[1]);
  EXPECT_DOUBLE_EQ(last_turned[1], last[0]);
  EXPECT_DOUBLE_EQ(last_turned[2], last[2]);
  EXPECT_DOUBLE_EQ(last_turned[3], last[4]);  // yz' = xz
  EXPECT_NEAR(last_turned[4], 0, 1e-9 * std::abs(last[4]));

  // A fabric recorded as six internal variables turns with the frame; a scalar beside it stays.
  StrainHistory with_fabric = shear;
  with_fabric.internal_variable_names = {"coordination_number", "fabric_xx", "fabric_yy",
                                         "fabric_zz", "fabric_yz", "fabric_xz", "fabric_xy"};
  with_fabric.internal_variables.assign(shear.steps(), {5.5, 0.4, 0.35, 0.25, 0.01, -0.1, 0.02});
  with_fabric.initial_internal_variables = {5.5, 0.4, 0.35, 0.25, 0.01, -0.1, 0.02};
  const StrainHistory fabric_rotated = Rotated(with_fabric, quarter_turn);
  const std::vector<double> expected = {5.5, 0.35, 0.4, 0.25, -0.1, -0.01, -0.02};
  for (const std::vector<double>& fabric_turned :
       {fabric_rotated.internal_variables[3], fabric_rotated.initial_internal_variables}) {
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_NEAR(fabric_turned[k], expected[k], 1e-15) << with_fabric.internal_variable_names[k];
    }
  }

  const std::vector<StrainHistory> copies = WithRotatedCopies({shear}, 2, 7);
  ASSERT_EQ(copies.size(), 3u);
  EXPECT_EQ(SerializeHistory(copies[0]), SerializeHistory(shear));
  EXPECT_EQ(SerializeHistory(WithRotatedCopies({shear}, 2, 7)[2]), SerializeHistory(copies[2]));
  EXPECT_NE(SerializeHistory(WithRotatedCopies({shear}, 2, 8)[2]), SerializeHistory(copies[2]));
  for (const StrainHistory& copy : {copies[1], copies[2]}) {
    const std::vector<Matrix3> driven = Drive(soil, copy);
    ASSERT_EQ(driven.size(), copy.stresses_pa.size());
    double worst = 0;
    for (std::size_t k = 0; k < driven.size(); ++k) {
      worst = std::max(worst, (driven[k] - material::VoigtToStress(copy.stresses_pa[k])).norm());
    }
    EXPECT_LT(worst, 1e-6 * material::VoigtToStress(last).norm())
        << "the soil's answer to the turned path is not the turned answer";
    EXPECT_GT((material::VoigtToStress(copy.stresses_pa.back()) - material::VoigtToStress(last))
                  .norm(),
              0.01 * material::VoigtToStress(last).norm())
        << "the copy was not turned";
  }
  EXPECT_EQ(WithRotatedCopies({shear}, 0, 7).size(), 1u);
  try {
    WithRotatedCopies({shear}, 65, 7);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "rotated_copies");
  }
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(StrainHistories, ExportAsNpyThatNumPyReadsAndAsCsv) {
  const std::filesystem::path directory =
      std::filesystem::temp_directory_path() / ("gonogo_ann_export_" + std::to_string(getpid()));
  std::filesystem::create_directories(directory);
  const std::vector<StrainHistory> histories = {SmallHistory(), SmallHistory()};
  const std::string npy = (directory / "histories.npy").string();
  const std::string csv = (directory / "histories.csv").string();
  WriteHistoriesNpy(npy, histories);
  WriteHistoriesCsv(csv, histories);
  // Debian's Python and NumPy (python3-numpy comes with python3-gdal).
  const std::string script = (directory / "read.py").string();
  std::ofstream(script) << "import numpy, sys\n"
                           "a = numpy.load(sys.argv[1])\n"
                           "names = open(sys.argv[1] + '.columns.txt').read().split()\n"
                           "print(a.dtype, a.shape, len(names), names[2], names[-1])\n"
                           "print(repr(a[4, 0]), repr(a[4, 1]), repr(a[4, 4]), repr(a[5, 15]),"
                           " repr(a[5, 18]))\n";
  const std::string out = (directory / "read.out").string();
  ASSERT_EQ(std::system(("/usr/bin/python3 " + script + " " + npy + " > " + out).c_str()), 0);
  EXPECT_EQ(Slurp(out),
            "float64 (6, 19) 19 dH_xx coordination\n"
            "1.0 1.0 0.0002 200.0 5.5\n");
  const std::string text = Slurp(csv);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "history,step,dH_xx,dH_xy,dH_xz,dH_yx,dH_yy,dH_yz,dH_zx,dH_zy,dH_zz,sigma_xx_pa,"
            "sigma_yy_pa,sigma_zz_pa,sigma_yz_pa,sigma_xz_pa,sigma_xy_pa,solid_fraction,"
            "coordination");
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 7);
  StrainHistory other = SmallHistory();
  other.internal_variable_names = {"void_ratio", "coordination"};
  EXPECT_THROW(WriteHistoriesCsv(csv, {SmallHistory(), other}), InputError);
  std::filesystem::remove_all(directory);
}

// The driver on a DE RVE (100 grains, seed 000's law, the RVE's default numerics): a short
// drained triaxial holds the lateral stress within its tolerance while the axial stress rises,
// and records the packing's solid fraction and coordination number beside the stress.
TEST(LabPaths, ADeRvePointHoldsItsConfiningStressInADrainedTriaxial) {
  const SoilParameters soil{"dem-hertz-mindlin", {{"grains_per_rve", 100}}};
  const auto rve = dem::rve::SharedRveMaterial(
      dem::rve::RveMaterialParamsFromSoil(soil, dem::rve::RveNumerics{}, "soil"));
  InternalVariables internal;
  internal.names = {"solid_fraction", "coordination_number"};
  internal.read = [](const material::MaterialState& state) {
    const dem::rve::RveSnapshot snapshot =
        static_cast<const dem::rve::RveState&>(state).rve().Snapshot();
    return std::vector<double>{snapshot.solid_fraction, snapshot.coordination_number};
  };
  LabPathSpec spec;
  spec.path = LabPath::kTriaxial;
  spec.pressure_pa = 20e3;
  spec.max_strain = 0.01;
  spec.steps = 10;
  DriverOptions options;
  options.relative_tolerance = 0.02;  // a packing's stress is a sum over contacts, not smooth
  const StrainHistory history = RunLabPath(*rve, spec, options, internal);
  ASSERT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  ASSERT_EQ(history.steps(), 15u);
  // From the template's preparation pressure down to 20 kPa in the 5 settling steps.
  EXPECT_LT(history.initial_stress_pa.trace() / 3, -50e3);
  for (std::size_t s = 0; s < history.steps(); ++s) {
    if (s >= 4) {
      EXPECT_NEAR(history.stresses_pa[s][0], -20e3, 0.02 * 20e3 + 1) << s;
      EXPECT_NEAR(history.stresses_pa[s][1], -20e3, 0.02 * 20e3 + 1) << s;
    }
    EXPECT_GT(history.internal_variables[s][0], 0.5) << s;
    EXPECT_GT(history.internal_variables[s][1], 3.0) << s;
  }
  EXPECT_LT(history.stresses_pa.back()[2], -20e3 - 10e3) << "the axial stress rose";
  EXPECT_NEAR(history.stresses_pa[4][2], -20e3, 0.02 * 20e3 + 1) << "settled isotropically";
}

}  // namespace
}  // namespace gonogo::ann
