// The DE RVE material built from a soil description (solvers/dem/rve/rve_soil.h): the mapping of
// a dem-hertz-mindlin set onto RveMaterialParams, the shared template cache, the "dem-rve"
// registration, and the one-element check: one hexahedron of the RVE material driven through a
// homogeneous strain path by the explicit FE solver answers exactly what the same RveMaterial
// answers when driven directly with the same increments (solvers/dem/rve/README.md, "From a soil
// description").
#include "solvers/dem/rve/rve_soil.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/fe/explicit_solver.h"
#include "solvers/fe/mesh.h"

namespace gonogo::dem::rve {
namespace {

// Every field of RveMaterialParams, so that a mapped set can be compared with an expected one
// field by field.
std::vector<double> AllFields(const RveMaterialParams& p) {
  const MaterialParams& m = p.rve.material;
  return {m.youngs_modulus_pa,
          m.poisson_ratio,
          m.density_kg_m3,
          m.friction,
          m.rolling_stiffness,
          m.rolling_limit,
          m.restitution,
          static_cast<double>(p.rve.grain_count),
          p.rve.mean_radius_m,
          p.rve.radius_spread,
          static_cast<double>(p.rve.seed),
          p.rve.initial_solid_fraction,
          p.rve.consolidation_pressure_pa,
          p.rve.consolidation_friction,
          p.rve.time_step_safety,
          p.rve.max_inertial_number,
          static_cast<double>(p.rve.threads),
          static_cast<double>(p.min_steps_per_increment),
          static_cast<double>(p.relax_steps),
          p.max_strain_increment,
          static_cast<double>(p.batch_threads)};
}

SoilParameters Soil(std::map<std::string, double> values = {}) {
  return SoilParameters{kRveSoilModel, std::move(values)};
}

// The cheap packing every RVE of this file shares: 100 grains of seed 000's law at 100 kPa.
RveMaterialParams CheapParams() {
  RveNumerics numerics;
  numerics.min_steps_per_increment = 5;
  numerics.relax_steps = 10;
  return RveMaterialParamsFromSoil(Soil({{"grains_per_rve", 100}}), numerics);
}

// Runs `call` and returns the field of the InputError it throws ("" when it throws none).
std::string FieldOfInputError(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& error) {
    return error.field();
  }
  return "";
}

TEST(RveSoilMapping, DefaultsAreSeedZeroZeroZerosRve) {
  // dem-hertz-mindlin's defaults are seed 000's, and so are RveParams'.
  EXPECT_EQ(AllFields(RveMaterialParamsFromSoil(Soil(), RveNumerics{})),
            AllFields(RveMaterialParams{}));
}

TEST(RveSoilMapping, EverySoilParameterLandsInItsField) {
  struct Row {
    std::string name;
    double value;  // differs from the default
    std::function<void(RveMaterialParams&, double)> set;
  };
  const std::vector<Row> rows = {
      {"young_pa", 2.5e9, [](auto& p, double v) { p.rve.material.youngs_modulus_pa = v; }},
      {"poisson", 0.21, [](auto& p, double v) { p.rve.material.poisson_ratio = v; }},
      {"friction", 0.31, [](auto& p, double v) { p.rve.material.friction = v; }},
      {"rolling_stiffness", 1.7, [](auto& p, double v) { p.rve.material.rolling_stiffness = v; }},
      {"rolling_limit", 0.45, [](auto& p, double v) { p.rve.material.rolling_limit = v; }},
      {"particle_radius_m", 1.3e-3, [](auto& p, double v) { p.rve.mean_radius_m = v; }},
      {"density_kg_m3", 2480, [](auto& p, double v) { p.rve.material.density_kg_m3 = v; }},
      {"grains_per_rve", 321, [](auto& p, double v) { p.rve.grain_count = static_cast<int>(v); }},
      {"consolidation_pressure_pa", 55e3,
       [](auto& p, double v) { p.rve.consolidation_pressure_pa = v; }},
      {"initial_solid_fraction", 0.33, [](auto& p, double v) { p.rve.initial_solid_fraction = v; }},
  };
  // Every declared parameter has a row.
  EXPECT_EQ(rows.size(), SoilModels().Get(kRveSoilModel, "model").parameters.size());
  const RveMaterialParams defaults = RveMaterialParamsFromSoil(Soil(), RveNumerics{});
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    RveMaterialParams expected = defaults;
    row.set(expected, row.value);
    ASSERT_NE(AllFields(expected), AllFields(defaults)) << "the test value is the default";
    EXPECT_EQ(AllFields(RveMaterialParamsFromSoil(Soil({{row.name, row.value}}), RveNumerics{})),
              AllFields(expected));
  }
}

TEST(RveSoilMapping, NumericsLandInTheirFields) {
  RveNumerics numerics;
  numerics.min_steps_per_increment = 7;
  numerics.relax_steps = 11;
  numerics.max_strain_increment = 0.004;
  numerics.max_inertial_number = 2e-3;
  numerics.seed = 42;
  RveMaterialParams expected = RveMaterialParamsFromSoil(Soil(), RveNumerics{});
  expected.min_steps_per_increment = 7;
  expected.relax_steps = 11;
  expected.max_strain_increment = 0.004;
  expected.rve.max_inertial_number = 2e-3;
  expected.rve.seed = 42;
  EXPECT_EQ(AllFields(RveMaterialParamsFromSoil(Soil(), numerics)), AllFields(expected));
}

TEST(RveSoilMapping, BadInputNamesTheField) {
  const RveNumerics numerics;
  auto mapping = [](const SoilParameters& soil, const RveNumerics& n) {
    return [soil, n] { RveMaterialParamsFromSoil(soil, n); };
  };
  EXPECT_EQ(FieldOfInputError(mapping(SoilParameters{"dem-eepa", {}}, numerics)), "soil.model");
  EXPECT_EQ(FieldOfInputError(mapping(Soil({{"grains_per_rve", 100.5}}), numerics)),
            "soil.grains_per_rve");
  EXPECT_EQ(FieldOfInputError(mapping(Soil({{"friction", -0.1}}), numerics)), "soil.friction");
  EXPECT_EQ(FieldOfInputError(mapping(Soil({{"grain_count", 100}}), numerics)), "soil.grain_count");
  RveNumerics bad = numerics;
  bad.relax_steps = -1;
  EXPECT_EQ(FieldOfInputError(mapping(Soil(), bad)), "soil.relax_steps");
  bad = numerics;
  bad.max_strain_increment = 0.5;
  EXPECT_EQ(FieldOfInputError(mapping(Soil(), bad)), "soil.max_strain_increment");
  bad = numerics;
  bad.max_inertial_number = 0;
  EXPECT_EQ(FieldOfInputError([&] { bad.Validate("numerics."); }), "numerics.max_inertial_number");
  bad = numerics;
  bad.min_steps_per_increment = 0;
  EXPECT_EQ(FieldOfInputError([&] { bad.Validate("numerics."); }),
            "numerics.min_steps_per_increment");
}

TEST(RveSoilCache, EqualParametersShareOneTemplateAndOthersDoNot) {
  const RveMaterialParams params = CheapParams();
  const std::shared_ptr<const Rve> first = SharedRveTemplate(params.rve);
  EXPECT_EQ(SharedRveTemplate(params.rve).get(), first.get());
  // Numerics of the FE-DE bridge alone do not change the template.
  RveMaterialParams other_numerics = params;
  other_numerics.relax_steps = 3;
  other_numerics.batch_threads = 2;
  EXPECT_EQ(SharedRveTemplate(other_numerics.rve).get(), first.get());
  // A material starts from a copy of the template.
  const std::shared_ptr<const RveMaterial> material = SharedRveMaterial(other_numerics);
  EXPECT_NE(&material->initial(), first.get());
  EXPECT_EQ(material->initial().Save(), first->Save());
  EXPECT_EQ(material->params().relax_steps, 3);

  // Another packing: another template, generated once however many threads ask at once.
  RveMaterialParams other_packing = params;
  other_packing.rve.seed = 2;
  std::vector<std::shared_ptr<const Rve>> answers(3);
  std::vector<std::thread> callers;
  for (auto& answer : answers) {
    callers.emplace_back(
        [&answer, &other_packing] { answer = SharedRveTemplate(other_packing.rve); });
  }
  for (std::thread& caller : callers) caller.join();
  for (const auto& answer : answers) EXPECT_EQ(answer.get(), answers[0].get());
  EXPECT_NE(answers[0].get(), first.get());
  EXPECT_NE(answers[0]->Save(), first->Save());
  // A value that differs in the last bit is another parameter set.
  RveMaterialParams nudged = params;
  nudged.rve.consolidation_pressure_pa = std::nextafter(100e3, 1e6);
  EXPECT_EQ(FieldOfInputError([&] { SharedRveTemplate(nudged.rve); }), "");
  EXPECT_NE(SharedRveTemplate(nudged.rve).get(), first.get());
}

TEST(RveSoilCache, BulkDensityIsGrainDensityTimesSolidFraction) {
  const std::shared_ptr<const RveMaterial> material = SharedRveMaterial(CheapParams());
  const double solid_fraction = material->initial().Snapshot().solid_fraction;
  // A consolidated frictionless packing lies between random loose and random close packing.
  EXPECT_GT(solid_fraction, 0.55);
  EXPECT_LT(solid_fraction, 0.66);
  EXPECT_DOUBLE_EQ(ConsolidatedBulkDensityKgM3(*material), 2650.0 * solid_fraction);
}

TEST(RveSoilRegistry, MapKeysAreSoilParametersAndNumerics) {
  material::MaterialRegistry registry;
  RegisterRveMaterial(registry);
  const material::ModelEntry& entry = registry.Get("dem-rve");
  EXPECT_LE(entry.example_parameters.at("grains_per_rve"), 100);

  // Missing keys take the soil model's and the numerics' defaults.
  const material::ParameterMap cheap = {
      {"grains_per_rve", 100}, {"min_steps_per_increment", 5}, {"relax_steps", 10}};
  const std::unique_ptr<material::ConstitutiveModel> model = registry.Make("dem-rve", cheap);
  const auto* rve = dynamic_cast<const RveMaterial*>(model.get());
  ASSERT_NE(rve, nullptr);
  EXPECT_EQ(rve->Name(), "dem-rve");
  EXPECT_EQ(AllFields(rve->params()), AllFields(CheapParams()));
  EXPECT_EQ(rve->initial().Save(), SharedRveTemplate(CheapParams().rve)->Save());

  auto field_of = [&](const material::ParameterMap& parameters) {
    return FieldOfInputError([&] { registry.Make("dem-rve", parameters); });
  };
  EXPECT_EQ(field_of({{"grain_count", 100}}), "material.grain_count");  // RveParams' name
  EXPECT_EQ(field_of({{"friction", 11}}), "material.friction");
  EXPECT_EQ(field_of({{"grains_per_rve", 99.5}}), "material.grains_per_rve");
  EXPECT_EQ(field_of({{"relax_steps", 2.5}}), "material.relax_steps");
  EXPECT_EQ(field_of({{"seed", -1}}), "material.seed");
  EXPECT_EQ(field_of({{"batch_threads", 0}}), "material.batch_threads");
  EXPECT_EQ(field_of({{"max_strain_increment", 0}}), "material.max_strain_increment");
  EXPECT_EQ(field_of({{"max_inertial_number", 1}}), "material.max_inertial_number");
}

// --- One element -----------------------------------------------------------------------------

// The relative difference |a - b| / |b| (Frobenius).
double RelativeDifference(const Matrix3& a, const Matrix3& b) { return (a - b).norm() / b.norm(); }

// One point of `material` driven directly through Update, one increment at a time.
class StandalonePoint {
 public:
  explicit StandalonePoint(const RveMaterial& material)
      : material_(material), state_(material.InitialState()) {}
  // The stress after `increment` from the committed state; commits only when `commit`.
  Matrix3 Apply(const Matrix3& increment, bool commit = true) {
    std::vector<material::PointIncrement> batch(1);
    batch[0].displacement_gradient_increment = increment;
    batch[0].committed = state_.get();
    std::vector<material::PointResponse> responses = material_.Update(batch, false);
    EXPECT_EQ(responses[0].status, material::UpdateStatus::kOk) << responses[0].reason;
    if (responses[0].status != material::UpdateStatus::kOk) return Matrix3::Constant(NAN);
    if (commit) state_ = std::move(responses[0].state);
    return responses[0].stress_pa;
  }

 private:
  const RveMaterial& material_;
  std::unique_ptr<material::MaterialState> state_;
};

// One 8-node hexahedron of the RVE material, every node's velocity prescribed so that the motion
// is homogeneous, x = F(t) X, with F piecewise linear in t: oedometric compression along z, then
// simple shear in xz. The solver hands the material dH = F_{n+1} F_n^-1 - I per step (its header),
// with F from the nodes' positions; the same RveMaterial driven directly through Update must
// answer the same stress:
// - with the increments computed from the prescribed motion, F(t) in closed form: the nodes'
//   F differs from it by the round-off of x += dt v (2e-16 in dH), which the DE packing carries
//   into the stress at 1e-13 of its norm (measured 5e-14 to 1.1e-13); bound 1e-12;
// - with the increments computed as the solver computes them, from its F read back: the same
//   doubles through the same code, so bit for bit (measured 0); bound 1e-12 as well.
// The check has teeth: a skipped increment, a flipped sign or a transposed dH (the rotation the
// wrong way; measured 5e-4 after one shear step) each moves the stress by more than 1e-6 of its
// norm, a million times the bound (asserted below).
TEST(RveSoilOneElement, HomogeneousPathMatchesTheStandaloneRve) {
  const std::shared_ptr<const RveMaterial> material = SharedRveMaterial(CheapParams());

  fe::ExplicitOptions options;
  options.density_kg_m3 = ConsolidatedBulkDensityKgM3(*material);
  options.gravity_m_s2 = fe::Vec3::Zero();
  fe::ExplicitSolver solver(fe::MeshBox({0, 0.1}, {0, 0.1}, {-0.1, 0}), material, options);

  // dF/dt of the two phases; with x_a = F X_a every node moves at v_a = (dF/dt) X_a. The time step
  // only scales the velocities: all nodes are prescribed, so nothing is dynamic.
  const double dt_s = 1e-3;
  const int compression_steps = 5, shear_steps = 5;
  const double compression_per_step = 4e-4, shear_per_step = 1e-3;  // -dF_zz, dF_xz per step
  Matrix3 compression_rate = Matrix3::Zero(), shear_rate = Matrix3::Zero();
  compression_rate(2, 2) = -compression_per_step / dt_s;
  shear_rate(0, 2) = shear_per_step / dt_s;
  auto prescribe = [&](const Matrix3& deformation_rate_1_s) {
    for (int node = 0; node < solver.mesh().num_nodes(); ++node) {
      const fe::Vec3 velocity = deformation_rate_1_s * solver.mesh().reference_positions_m[node];
      for (int dof = 0; dof < 3; ++dof) solver.PrescribeVelocity(node, dof, velocity[dof]);
    }
  };
  // F(t_n) of the prescribed motion; F(t_-1) = I.
  auto prescribed_f = [&](int n) {
    return Matrix3(Matrix3::Identity() +
                   std::clamp(n, 0, compression_steps) * dt_s * compression_rate +
                   std::max(n - compression_steps, 0) * dt_s * shear_rate);
  };

  StandalonePoint from_motion(*material), from_solver(*material);
  const Matrix3 initial_stress_pa = material->initial().StressPa();
  Matrix3 solver_previous_f = Matrix3::Identity();
  double largest_motion_difference = 0, largest_solver_difference = 0;
  const int steps = compression_steps + shear_steps;
  // Step n updates the material to the nodes' positions x_n (the solver's forces at x_n), then
  // moves them to x_{n+1}: step 0 hands a zero increment, step n the increment from t_{n-1}.
  for (int n = 0; n <= steps; ++n) {
    SCOPED_TRACE("step " + std::to_string(n));
    prescribe(n < compression_steps ? compression_rate : shear_rate);
    const fe::StepStatus status = solver.Step(dt_s);
    ASSERT_TRUE(status.ok) << status.reason;
    const Matrix3& element_stress_pa = solver.element_stress_pa()[0];

    // The prescribed motion's increment, F(t_n) F(t_n-1)^-1 - I.
    const Matrix3 motion_increment =
        prescribed_f(n) * prescribed_f(n - 1).inverse() - Matrix3::Identity();
    const double motion_difference =
        RelativeDifference(element_stress_pa, from_motion.Apply(motion_increment));
    largest_motion_difference = std::max(largest_motion_difference, motion_difference);
    EXPECT_LE(motion_difference, 1e-12);

    // The solver's increment, computed the way it computes it from F read back.
    const Matrix3 f = solver.element_deformation_gradient(0);
    ASSERT_LT((f - prescribed_f(n)).norm(), 1e-13);  // the element follows the motion
    const Matrix3 solver_increment = f * solver_previous_f.inverse() - Matrix3::Identity();
    solver_previous_f = f;
    const double solver_difference =
        RelativeDifference(element_stress_pa, from_solver.Apply(solver_increment));
    largest_solver_difference = std::max(largest_solver_difference, solver_difference);
    EXPECT_LE(solver_difference, 1e-12);

    if (n == compression_steps) {
      // Oedometric compression by 0.2 % raised the vertical stress (tension positive).
      EXPECT_LT(element_stress_pa(2, 2), initial_stress_pa(2, 2) - 10e3);
    }
    if (n == compression_steps + 1) {
      // The first shear increment: the wrong increments the check must tell apart, each applied
      // to the state before it (not committed).
      ASSERT_GT(motion_increment(0, 2), 0.5 * shear_per_step);
      StandalonePoint wrong_path(*material);
      for (int k = 0; k < n; ++k) {
        wrong_path.Apply(prescribed_f(k) * prescribed_f(k - 1).inverse() - Matrix3::Identity());
      }
      for (const Matrix3& wrong : {Matrix3(Matrix3::Zero()), Matrix3(-motion_increment),
                                   Matrix3(motion_increment.transpose())}) {
        EXPECT_GT(RelativeDifference(element_stress_pa, wrong_path.Apply(wrong, false)), 1e-6);
      }
    }
    if (n == steps) {
      // Simple shear to gamma = 0.5 % along +x on planes of constant z: positive shear stress.
      EXPECT_GT(element_stress_pa(0, 2), 5e3);
    }
  }
  char measured[96];
  std::snprintf(measured, sizeof measured, "from the motion %.3g, from the solver's F %.3g",
                largest_motion_difference, largest_solver_difference);
  RecordProperty("largest_relative_stress_difference", measured);
}

}  // namespace
}  // namespace gonogo::dem::rve
