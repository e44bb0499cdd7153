// The contract of solvers/material/constitutive.h and point_store.h, checked on every model of
// ContractRegistry() (contract_registry.h: RegisterBuiltinMaterials plus the DE RVE of
// solvers/dem/rve in a cheap configuration), built from its example parameters, with the
// tolerances of TolerancesFor. Each check runs from four states reached by a fixed sequence of
// increments: fresh; compressed and sheared (elastic for the example parameters); on the
// Drucker-Prager cone after isochoric axial compression; at the Drucker-Prager apex after
// isotropic extension (for linear-elastic the last two are elastic states too; the RVE reaches
// "cone" with sliding contacts and "apex" by unloading to about 55 kPa).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/material/constitutive.h"
#include "solvers/material/kinematics.h"
#include "solvers/material/linear_elastic.h"
#include "solvers/material/point_store.h"
#include "solvers/material/registry.h"
#include "tests/solvers/material/contract_registry.h"

namespace gonogo::material {
namespace {

// How closely a model must meet each check. A new model starts from the defaults; a row that
// loosens one says why (an RVE's tangent is an estimate, a network's rotation is learnt ...).
struct ContractTolerances {
  double tangent_relative = 1e-5;       // (a) tangent vs central differences, Frobenius
  double difference_step = 1e-7;        // (a) strain step of the central differences
  bool tangent_is_upper_bound = false;  // (a) also: each difference diagonal term <= tangent's
  std::vector<std::string> bound_only_states;  // (a) path states where only the bound is checked
  double zero_increment_relative = 1e-12;      // (b) stress change under a zero increment
  double rotation_deg = 30;                    // (c) angle of the rigid rotation increment
  double rotation_relative = 1e-10;            // (c) Q sigma Q^T under a rigid rotation
  std::string rotation_skip_reason;            // (c) non-empty: why the model does not meet it
  double moduli_relative = 1e-12;              // (g) K and G of a fresh point
  int batch_points = 64;                       // (f) points in the batch
};

ContractTolerances TolerancesFor(const std::string& model_name) {
  // The periodic DE RVE (solvers/dem/rve) in the cheap configuration of contract_registry.cc.
  // The exact checks (d, e, f, h, i) hold as for any model: the DE run is deterministic and
  // serial inside one RVE. The others compare a dynamic, discrete packing with continuum ideals.
  ContractTolerances rve;
  // (a) TangentPa() is the affine contact stiffness, which ignores how the grains relax. The
  // affine field is kinematically admissible, so by minimum potential energy it bounds the
  // relaxed stiffness from above (the Voigt bound, Hill 1952, Proc. Phys. Soc. A 65, 349):
  // central differences (each a DE run of min_steps + relax_steps) must stay below it on the
  // diagonal. Where the packing responds elastically (fresh, prestressed, and the "apex" state,
  // which for the RVE is only unloading to about 55 kPa) they differ from it by 10-16 %
  // (Frobenius, measured): 0.25 leaves room for round-off yet catches a tangent with the shear
  // block doubled (tensor instead of engineering shears: 0.4, tried). On the "cone" path,
  // where contacts slide, the relaxed response is 40-70 % of the affine estimate on the
  // diagonal: only the bound is asserted there. Steps of 1e-6: far above the DE round-off, small
  // enough that no contact opens or starts sliding.
  rve.tangent_relative = 0.25;
  rve.difference_step = 1e-6;
  rve.tangent_is_upper_bound = true;
  rve.bound_only_states = {"cone"};
  // (b) a zero increment still runs min_steps + relax_steps DE steps, and the packing keeps
  // settling (its unbalanced force is not zero): measured 0.9-1.3e-4 of the stress.
  rve.zero_increment_relative = 1e-3;
  // (c) the default 30 deg rotation about an oblique axis. The RVE maps its cell by
  // (I + dH)^(1/n) each step and spins grains and contact springs with the rotation
  // (solvers/dem/rve/README.md, "Increments"), so Q sigma Q^T holds up to what the packing does
  // anyway in the 20 + 30 DE steps: measured 1e-5 (fresh, prestressed) to 9e-5 (cone, apex) of
  // the stress norm, the size of the settling under a zero increment (b). It was 1.5-7 % at
  // 0.5 deg before the fix. The bound is (b)'s: the reference is the committed stress, and the
  // packing keeps settling while it turns.
  rve.rotation_relative = 1e-3;
  // (f) each point is a DE run; 16 keep the batch on two threads cheap.
  rve.batch_points = 16;
  static const std::map<std::string, ContractTolerances> kByModel = {
      // Both integrate Hughes-Winget exactly and have closed-form tangents: the defaults.
      {"linear-elastic", ContractTolerances{}},
      {"drucker-prager", ContractTolerances{}},
      {"dem-rve", rve},
  };
  const auto found = kByModel.find(model_name);
  return found == kByModel.end() ? ContractTolerances{} : found->second;
}

std::vector<std::string> ContractNames() { return ContractRegistry().Names(); }

Matrix3 StrainFromVoigt(double xx, double yy, double zz, double yz, double xz, double xy) {
  Vector6 voigt;
  voigt << xx, yy, zz, yz, xz, xy;
  return VoigtToStrain(voigt);
}

bool SameBits(const Eigen::Ref<const Eigen::MatrixXd>& a,
              const Eigen::Ref<const Eigen::MatrixXd>& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// A committed state, its stress, and the strain increment (Hughes-Winget d_eps) that continues
// the path that reached it.
struct PathPoint {
  std::string label;
  std::unique_ptr<MaterialState> state;
  Matrix3 stress_pa;
  Matrix3 next_strain;
};

class MaterialContractTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    registry_ = ContractRegistry();
    const ModelEntry& entry = registry_.Get(GetParam());
    model_ = entry.make(entry.example_parameters);
    tolerances_ = TolerancesFor(GetParam());
    // Young's modulus of a fresh point, E = 9 K G / (3 K + G): the stress and stiffness scale of
    // the checks, also for a model (the RVE) without elastic constants among its parameters.
    const ElasticModuli moduli = model_->InitialElasticModuli();
    young_pa_ = 9 * moduli.bulk_pa * moduli.shear_pa / (3 * moduli.bulk_pa + moduli.shear_pa);
    BuildPath();
  }

  PointResponse Apply(const MaterialState& committed, const Matrix3& displacement_gradient,
                      bool want_tangent) const {
    std::vector<PointIncrement> one(1);
    one[0].displacement_gradient_increment = displacement_gradient;
    one[0].committed = &committed;
    std::vector<PointResponse> responses = model_->Update(one, want_tangent);
    EXPECT_EQ(responses.size(), 1u);
    return std::move(responses[0]);
  }

  // Applies strain increments in turn (no rotation) and records the state reached.
  PathPoint Walk(const std::string& label, const MaterialState& start,
                 const std::vector<Matrix3>& strains, const Matrix3& next_strain) const {
    PathPoint point{label, start.Clone(), Matrix3::Zero(), next_strain};
    PointResponse response = Apply(*point.state, Matrix3::Zero(), false);  // the start's stress
    point.stress_pa = response.stress_pa;
    for (const Matrix3& strain : strains) {
      response = Apply(*point.state, DisplacementGradientForStrain(strain), false);
      EXPECT_EQ(response.status, UpdateStatus::kOk) << response.reason;
      point.state = std::move(response.state);
      point.stress_pa = response.stress_pa;
    }
    return point;
  }

  void BuildPath() {
    const std::unique_ptr<MaterialState> fresh = model_->InitialState();
    path_.push_back(
        Walk("fresh", *fresh, {}, StrainFromVoigt(-2e-4, 1e-4, -1e-4, 5e-5, -3e-5, 4e-5)));
    // Isotropic compression to p ~ -50 kPa and a small shear (elastic).
    const Matrix3 compress = StrainFromVoigt(-5e-4, -5e-4, -5e-4, 2e-5, 0, 1e-4);
    path_.push_back(Walk("prestressed", *fresh, {compress, compress},
                         StrainFromVoigt(-2e-4, 1e-4, -1e-4, 5e-5, -3e-5, 4e-5)));
    // Isochoric axial compression from there: on the cone after about four steps.
    const Matrix3 axial = StrainFromVoigt(5e-4, 5e-4, -1e-3, 0, 0, 0);
    path_.push_back(Walk("cone", *path_[1].state, std::vector<Matrix3>(6, axial),
                         StrainFromVoigt(5e-4, 4e-4, -1e-3, 2e-5, -1e-5, 3e-5)));
    // Isotropic extension: p_trial = 50 kPa beyond the apex p = xi c / eta ~ 17 kPa.
    path_.push_back(Walk("apex", *fresh, {StrainFromVoigt(1e-3, 1e-3, 1e-3, 0, 0, 0)},
                         StrainFromVoigt(1e-4, 1e-4, 1e-4, 1e-5, 0, 0)));
  }

  // A stress to measure errors against where the stress itself may be zero.
  double StressScale(const Matrix3& stress) const {
    return std::max(stress.norm(), 1e-3 * young_pa_);
  }

  MaterialRegistry registry_;
  std::unique_ptr<ConstitutiveModel> model_;
  ContractTolerances tolerances_;
  double young_pa_ = 0;
  std::vector<PathPoint> path_;
};

// (a) The tangent is d sigma / d eps (Voigt, engineering shears) of the update it comes with.
TEST_P(MaterialContractTest, TangentMatchesCentralDifferences) {
  const Voigt6x6 elastic = Apply(*path_[0].state, Matrix3::Zero(), true).tangent_pa;  // fresh point
  for (const PathPoint& point : path_) {
    SCOPED_TRACE(point.label);
    const PointResponse base =
        Apply(*point.state, DisplacementGradientForStrain(point.next_strain), true);
    ASSERT_EQ(base.status, UpdateStatus::kOk) << base.reason;
    ASSERT_TRUE(base.has_tangent);
    const Vector6 strain = StrainToVoigt(point.next_strain);
    const double step = tolerances_.difference_step;
    Voigt6x6 differences;
    for (int j = 0; j < 6; ++j) {
      Vector6 plus = strain, minus = strain;
      plus(j) += step;
      minus(j) -= step;
      const PointResponse up =
          Apply(*point.state, DisplacementGradientForStrain(VoigtToStrain(plus)), false);
      const PointResponse down =
          Apply(*point.state, DisplacementGradientForStrain(VoigtToStrain(minus)), false);
      differences.col(j) =
          (StressToVoigt(up.stress_pa) - StressToVoigt(down.stress_pa)) / (2 * step);
    }
    const double scale = std::max(base.tangent_pa.norm(), young_pa_);
    const std::vector<std::string>& skipped = tolerances_.bound_only_states;
    if (std::find(skipped.begin(), skipped.end(), point.label) == skipped.end()) {
      EXPECT_LT((differences - base.tangent_pa).norm(), tolerances_.tangent_relative * scale)
          << "tangent\n"
          << base.tangent_pa << "\ndifferences\n"
          << differences;
    }
    if (tolerances_.tangent_is_upper_bound) {
      // 2 %: the differences are of a dynamic run, not of a packing in exact equilibrium.
      for (int i = 0; i < 6; ++i) {
        EXPECT_LE(differences(i, i), 1.02 * base.tangent_pa(i, i)) << "Voigt diagonal " << i;
      }
    }
    // Drucker-Prager: the path must reach the plastic branches, or (a) would only test C.
    if (GetParam() == "drucker-prager" && (point.label == "cone" || point.label == "apex")) {
      EXPECT_GT((base.tangent_pa - elastic).norm(), 0.1 * elastic.norm());
    }
  }
}

// (b) A zero increment changes nothing, also through the state's bytes.
TEST_P(MaterialContractTest, ZeroIncrementKeepsTheStress) {
  for (const PathPoint& point : path_) {
    SCOPED_TRACE(point.label);
    const PointResponse response = Apply(*point.state, Matrix3::Zero(), false);
    ASSERT_EQ(response.status, UpdateStatus::kOk) << response.reason;
    const double tolerance =
        tolerances_.zero_increment_relative * std::max(point.stress_pa.norm(), 1.0);
    EXPECT_LE((response.stress_pa - point.stress_pa).norm(), tolerance);
    const std::unique_ptr<MaterialState> restored =
        model_->RestoreState(response.state->Serialize());
    const PointResponse again = Apply(*restored, Matrix3::Zero(), false);
    EXPECT_LE((again.stress_pa - point.stress_pa).norm(), tolerance);
  }
}

// (c) Objectivity: a rigid rotation increment I + dH = Q gives Q sigma Q^T.
TEST_P(MaterialContractTest, RigidRotationRotatesTheStress) {
  if (!tolerances_.rotation_skip_reason.empty()) GTEST_SKIP() << tolerances_.rotation_skip_reason;
  const Matrix3 rotation = Eigen::AngleAxisd(units::DegreesToRadians(tolerances_.rotation_deg),
                                             Eigen::Vector3d(1, -2, 3).normalized())
                               .toRotationMatrix();
  for (const PathPoint& point : path_) {
    SCOPED_TRACE(point.label);
    const PointResponse response = Apply(*point.state, rotation - Matrix3::Identity(), false);
    ASSERT_EQ(response.status, UpdateStatus::kOk) << response.reason;
    const Matrix3 expected = rotation * point.stress_pa * rotation.transpose();
    EXPECT_LE((response.stress_pa - expected).norm(),
              tolerances_.rotation_relative * StressScale(expected))
        << response.stress_pa << "\nexpected\n"
        << expected;
  }
}

// (d) A failed update returns a reason and no state, and leaves the committed state alone.
TEST_P(MaterialContractTest, FailureLeavesTheCommittedStateUntouched) {
  Matrix3 not_finite = Matrix3::Zero();
  not_finite(1, 2) = std::numeric_limits<double>::quiet_NaN();
  const Matrix3 inverted = Eigen::Vector3d(-2.0, 0.0, 0.0).asDiagonal();   // det(I + dH) = -1
  const Matrix3 flattened = Eigen::Vector3d(-1.0, 0.0, 0.0).asDiagonal();  // det(I + dH) = 0
  for (const PathPoint& point : path_) {
    SCOPED_TRACE(point.label);
    const std::string before = point.state->Serialize();
    for (const Matrix3& bad : {not_finite, inverted, flattened}) {
      const PointResponse response = Apply(*point.state, bad, true);
      EXPECT_EQ(response.status, UpdateStatus::kFailed);
      EXPECT_FALSE(response.reason.empty());
      EXPECT_EQ(response.state, nullptr);
      EXPECT_EQ(point.state->Serialize(), before);
    }
  }
  std::vector<PointIncrement> orphan(1);  // no committed state
  const std::vector<PointResponse> responses = model_->Update(orphan, false);
  EXPECT_EQ(responses[0].status, UpdateStatus::kFailed);
  EXPECT_FALSE(responses[0].reason.empty());
}

// (e) Serialize / RestoreState reproduce the next update bit for bit; bad bytes are refused.
TEST_P(MaterialContractTest, SerializeRestoreRoundTripIsExact) {
  for (const PathPoint& point : path_) {
    SCOPED_TRACE(point.label);
    const std::string bytes = point.state->Serialize();
    const std::unique_ptr<MaterialState> restored = model_->RestoreState(bytes);
    EXPECT_EQ(restored->Serialize(), bytes);
    const Matrix3 next = DisplacementGradientForStrain(point.next_strain);
    const PointResponse original = Apply(*point.state, next, true);
    const PointResponse replayed = Apply(*restored, next, true);
    ASSERT_EQ(replayed.status, UpdateStatus::kOk);
    EXPECT_TRUE(SameBits(original.stress_pa, replayed.stress_pa));
    EXPECT_TRUE(SameBits(original.tangent_pa, replayed.tangent_pa));
    EXPECT_EQ(original.state->Serialize(), replayed.state->Serialize());
  }
  EXPECT_THROW(model_->RestoreState("not a state"), InputError);
  const std::string bytes = path_[1].state->Serialize();
  EXPECT_THROW(model_->RestoreState(bytes.substr(0, bytes.size() - 1)), InputError);
}

// (f) One batch of points gives the bits of single calls (64 points; fewer for a costly model).
TEST_P(MaterialContractTest, BatchEqualsSingleCalls) {
  const int count = tolerances_.batch_points;
  std::vector<PointIncrement> batch(count);
  for (int i = 0; i < count; ++i) {
    const PathPoint& point = path_[i % path_.size()];
    const Matrix3 spin = 1e-3 * i * (Matrix3() << 0, 1, 0, -1, 0, 2, 0, -2, 0).finished();
    batch[i].displacement_gradient_increment =
        DisplacementGradientForStrain((1.0 + 0.05 * i) * point.next_strain) + spin;
    batch[i].committed = point.state.get();
  }
  const std::vector<PointResponse> together = model_->Update(batch, true);
  ASSERT_EQ(together.size(), static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    SCOPED_TRACE(i);
    const PointResponse alone =
        Apply(*batch[i].committed, batch[i].displacement_gradient_increment, true);
    ASSERT_EQ(together[i].status, alone.status);
    ASSERT_EQ(alone.status, UpdateStatus::kOk) << alone.reason;
    EXPECT_TRUE(SameBits(together[i].stress_pa, alone.stress_pa));
    EXPECT_TRUE(SameBits(together[i].tangent_pa, alone.tangent_pa));
    EXPECT_EQ(together[i].state->Serialize(), alone.state->Serialize());
  }
}

// (g) The moduli of a fresh point are those of its elastic constants. A model without elastic
// constants among its parameters (the RVE: its moduli come from the contact tangent) must give
// positive, finite ones.
TEST_P(MaterialContractTest, InitialElasticModuliMatchTheElasticConstants) {
  const ElasticModuli moduli = model_->InitialElasticModuli();
  EXPECT_TRUE(std::isfinite(moduli.bulk_pa) && std::isfinite(moduli.shear_pa));
  EXPECT_GT(moduli.bulk_pa, 0.0);
  EXPECT_GT(moduli.shear_pa, 0.0);
  const ParameterMap& parameters = registry_.Get(GetParam()).example_parameters;
  if (parameters.count("young_pa") == 0 || parameters.count("poisson") == 0) return;
  const double young_pa = parameters.at("young_pa"), poisson = parameters.at("poisson");
  const double bulk = young_pa / (3 * (1 - 2 * poisson));
  const double shear = young_pa / (2 * (1 + poisson));
  EXPECT_NEAR(moduli.bulk_pa, bulk, tolerances_.moduli_relative * bulk);
  EXPECT_NEAR(moduli.shear_pa, shear, tolerances_.moduli_relative * shear);
}

// (h) The point store's trials: a trial from each path state is the model's own update and leaves
// the committed state alone; discarding and trying again gives the same response bit for bit (as
// does trying twice); commit advances the point; the committed bytes move to another store and
// continue there identically.
TEST_P(MaterialContractTest, TrialsAreCommittedOrDiscardedExplicitly) {
  const std::unique_ptr<MaterialPointStore> store = model_->MakePointStore();
  ASSERT_NE(store, nullptr);
  EXPECT_EQ(store->ModelName(), GetParam());
  const std::vector<PointHandle> handles = store->Create(static_cast<int>(path_.size()));
  ASSERT_EQ(store->size(), static_cast<std::int64_t>(path_.size()));
  std::vector<Matrix3> next, zero(path_.size(), Matrix3::Zero());
  for (size_t i = 0; i < path_.size(); ++i) {
    store->Restore(handles[i], path_[i].state->Serialize());
    next.push_back(DisplacementGradientForStrain(path_[i].next_strain));
  }
  const std::vector<TrialResponse> first = store->TryUpdate(handles, next, true);
  ASSERT_EQ(first.size(), path_.size());
  store->TryUpdate(handles, zero, false);  // a second trial replaces the first ...
  const std::vector<TrialResponse> retried = store->TryUpdate(handles, next, true);
  store->Discard(handles);  // ... and so does a trial after a discard
  const std::vector<TrialResponse> again = store->TryUpdate(handles, next, true);
  for (size_t i = 0; i < path_.size(); ++i) {
    SCOPED_TRACE(path_[i].label);
    const PointResponse direct = Apply(*path_[i].state, next[i], true);
    ASSERT_EQ(first[i].status, UpdateStatus::kOk) << first[i].reason;
    EXPECT_TRUE(SameBits(first[i].stress_pa, direct.stress_pa));
    EXPECT_TRUE(SameBits(first[i].tangent_pa, direct.tangent_pa));
    for (const TrialResponse* other : {&retried[i], &again[i]}) {
      EXPECT_TRUE(SameBits(other->stress_pa, first[i].stress_pa));
      EXPECT_TRUE(SameBits(other->tangent_pa, first[i].tangent_pa));
    }
    EXPECT_EQ(store->Serialize(handles[i]), path_[i].state->Serialize());  // not yet committed
  }
  store->Commit(handles);
  const std::unique_ptr<MaterialPointStore> elsewhere = model_->MakePointStore();
  const std::vector<PointHandle> moved = elsewhere->Create(static_cast<int>(path_.size()));
  for (size_t i = 0; i < path_.size(); ++i) {
    SCOPED_TRACE(path_[i].label);
    const PointResponse direct = Apply(*path_[i].state, next[i], false);
    EXPECT_EQ(store->Serialize(handles[i]), direct.state->Serialize());  // committed: advanced
    elsewhere->Restore(moved[i], store->Serialize(handles[i]));
  }
  const std::vector<TrialResponse> here = store->TryUpdate(handles, next, true);
  const std::vector<TrialResponse> there = elsewhere->TryUpdate(moved, next, true);
  for (size_t i = 0; i < path_.size(); ++i) {
    SCOPED_TRACE(path_[i].label);
    ASSERT_EQ(there[i].status, UpdateStatus::kOk) << there[i].reason;
    EXPECT_TRUE(SameBits(here[i].stress_pa, there[i].stress_pa));
    EXPECT_TRUE(SameBits(here[i].tangent_pa, there[i].tangent_pa));
  }
}

// (i) A failed trial keeps no state: its point cannot be committed, and a refused commit commits
// nothing; the committed state stays for the caller to cut the step. Bad handles, sizes and
// bytes are refused.
TEST_P(MaterialContractTest, FailedTrialsCannotBeCommitted) {
  const std::unique_ptr<MaterialPointStore> store = model_->MakePointStore();
  const std::vector<PointHandle> handles = store->Create(2);
  const std::string fresh = store->Serialize(handles[0]);
  Matrix3 not_finite = Matrix3::Zero();
  not_finite(0, 1) = std::numeric_limits<double>::quiet_NaN();
  const Matrix3 good = DisplacementGradientForStrain(path_[0].next_strain);
  const std::vector<TrialResponse> trials = store->TryUpdate(handles, {not_finite, good}, false);
  EXPECT_EQ(trials[0].status, UpdateStatus::kFailed);
  EXPECT_FALSE(trials[0].reason.empty());
  ASSERT_EQ(trials[1].status, UpdateStatus::kOk) << trials[1].reason;
  EXPECT_THROW(store->Commit(handles), std::logic_error);
  EXPECT_EQ(store->Serialize(handles[0]), fresh);
  EXPECT_EQ(store->Serialize(handles[1]), fresh);  // the refused commit committed nothing
  store->Commit({handles[1]});
  EXPECT_NE(store->Serialize(handles[1]), fresh);
  store->Discard(handles);                                      // nothing pending: fine
  EXPECT_THROW(store->Commit({handles[1]}), std::logic_error);  // a trial commits once

  EXPECT_THROW(store->TryUpdate({handles[0] + 100}, {good}, false), std::out_of_range);
  EXPECT_THROW(store->TryUpdate(handles, {good}, false), std::invalid_argument);
  EXPECT_THROW(store->Restore(handles[0], "not a state"), InputError);
  EXPECT_EQ(store->Serialize(handles[0]), fresh);
}

TEST_P(MaterialContractTest, NameIsTheRegisteredName) { EXPECT_EQ(model_->Name(), GetParam()); }

INSTANTIATE_TEST_SUITE_P(Registered, MaterialContractTest, ::testing::ValuesIn(ContractNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name) c = (c == '-') ? '_' : c;
                           return name;
                         });

}  // namespace
}  // namespace gonogo::material
