// The explicit total-Lagrangian solver against closed forms: patch test, P-wave speed, a soil
// column under its own weight, and the bookkeeping (determinism, failure leaves the state intact,
// also when the material refuses an update).
#include "solvers/fe/explicit_solver.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/fe/mesh.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/material/linear_elastic.h"

namespace gonogo::fe {
namespace {

constexpr double kYoung = 10e6, kPoisson = 0.3, kDensity = 2000;

std::shared_ptr<material::LinearElastic> Elastic() {
  return std::make_shared<material::LinearElastic>(material::LinearElasticParams{kYoung, kPoisson});
}

double PWaveModulus() { return kYoung * (1 - kPoisson) / ((1 + kPoisson) * (1 - 2 * kPoisson)); }

ExplicitOptions Options(double damping = 0) {
  ExplicitOptions o;
  o.density_kg_m3 = kDensity;
  o.gravity_m_s2 = Vec3::Zero();
  o.mass_damping_per_s = damping;
  return o;
}

std::vector<double> Lines(int n, double length) {
  std::vector<double> l(n + 1);
  for (int i = 0; i <= n; ++i) l[i] = length * i / n;
  return l;
}

// Patch test (Irons): a homogeneous deformation of a mesh of distorted elements gives every
// element the same strain and the exact stress, and leaves the interior nodes in equilibrium.
TEST(ExplicitSolverTest, PatchTestOnDistortedElements) {
  HexMesh mesh = MeshBox(Lines(2, 1.0), Lines(2, 1.0), Lines(2, 1.0));
  const int centre = mesh.GridNode(1, 1, 1);
  mesh.reference_positions_m[centre] += Vec3(0.13, -0.08, 0.11);  // all 8 elements distorted
  ExplicitSolver solver(mesh, Elastic(), Options());
  // Velocity gradient L, prescribed on every node for one step of dt: dH = L dt exactly.
  Eigen::Matrix3d l;
  l << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, -1e-4, 3e-4, 1.5e-3;
  for (int n = 0; n < solver.mesh().num_nodes(); ++n) {
    const Vec3 v = l * solver.mesh().reference_positions_m[n];
    for (int d = 0; d < 3; ++d) solver.PrescribeVelocity(n, d, v[d]);
  }
  const double dt = 1.0;
  ASSERT_TRUE(solver.Step(dt).ok);  // moves the nodes by L X
  ASSERT_TRUE(solver.Step(dt).ok);  // evaluates the stress of that deformation
  // Expected: the hypoelastic stress of the increment dH = L (Hughes-Winget on the midpoint
  // configuration: d_eps = sym(L (I + L/2)^-1), rotated by the increment's rotation). Every
  // element must agree with element 0 and with that closed form.
  const Eigen::Matrix3d g = l * (Eigen::Matrix3d::Identity() + 0.5 * l).inverse();
  const Eigen::Matrix3d eps = 0.5 * (g + g.transpose());
  const double lambda = kYoung * kPoisson / ((1 + kPoisson) * (1 - 2 * kPoisson));
  const double mu = kYoung / (2 * (1 + kPoisson));
  const Eigen::Matrix3d expected =
      lambda * eps.trace() * Eigen::Matrix3d::Identity() + 2 * mu * eps;
  for (int e = 0; e < solver.mesh().num_elements(); ++e) {
    EXPECT_LT((solver.element_stress_pa()[e] - expected).norm(), 1e-9 * expected.norm()) << e;
  }
  // Interior equilibrium: the centre node's internal force vanishes (to round-off against the
  // size of one element's nodal force).
  const double scale = expected.norm() * 0.25;
  EXPECT_LT(solver.internal_forces_n()[centre].norm(), 1e-9 * scale);
}

// The P-wave in a laterally confined bar runs at c = sqrt((K + 4G/3) / rho).
TEST(ExplicitSolverTest, ConfinedBarWaveSpeed) {
  const double length = 20.0, h = 0.1;
  HexMesh mesh = MeshBox(Lines(200, length), Lines(1, h), Lines(1, h));
  ExplicitOptions options = Options();
  options.hourglass_coefficient = 0;  // a 1-D field excites no hourglass mode
  ExplicitSolver solver(mesh, Elastic(), options);
  const HexMesh& m = solver.mesh();
  const double impact = 1e-3;  // m/s, small: linear
  for (int n = 0; n < m.num_nodes(); ++n) {
    solver.PrescribeVelocity(n, 1);
    solver.PrescribeVelocity(n, 2);
  }
  for (int n : m.NodesOnPlane(0, 0)) solver.PrescribeVelocity(n, 0, impact);
  const double c = std::sqrt(PWaveModulus() / kDensity);
  const double probe_x = 0.5 * length;
  const int probe = m.GridNode(100, 0, 0);
  const double dt = solver.StableTimeStep();
  double arrival = -1;
  while (solver.time_s() < 1.5 * probe_x / c) {
    ASSERT_TRUE(solver.Step(dt).ok);
    if (arrival < 0 && solver.velocities_m_s()[probe].x() >= 0.5 * impact) arrival = solver.time_s();
  }
  ASSERT_GT(arrival, 0);
  EXPECT_NEAR(probe_x / arrival, c, 0.02 * c) << "c = " << c << " m/s";
}

// A soil column on a fixed floor with rollers on its sides, under gravity: oedometric static
// solution sigma_zz = -rho g (H - z), sigma_xx = nu / (1 - nu) sigma_zz, top settlement
// rho g H^2 / (2 M), M = K + 4G/3.
// With mass scaling f the column settles to the same static answer (weight is the physical
// mass's) while its stable step is sqrt(f) times longer. Returns the stable step.
double CheckColumnUnderSelfWeight(double mass_scaling) {
  const double depth = 4.0;
  const int layers = 16;
  std::vector<double> z(layers + 1);
  for (int k = 0; k <= layers; ++k) z[k] = -depth + depth * k / layers;
  HexMesh mesh = MeshBox(Lines(1, 0.25), Lines(1, 0.25), z);
  ExplicitOptions options = Options();
  options.gravity_m_s2 = Vec3(0, 0, -units::kStandardGravityMps2);
  options.mass_scaling = mass_scaling;
  const double c = std::sqrt(PWaveModulus() / (mass_scaling * kDensity));
  options.mass_damping_per_s = units::kPi * c / depth;  // critical for the first mode
  ExplicitSolver solver(mesh, Elastic(), options);
  const HexMesh& m = solver.mesh();
  for (int n = 0; n < m.num_nodes(); ++n) {
    solver.PrescribeVelocity(n, 0);
    solver.PrescribeVelocity(n, 1);
  }
  for (int n : m.NodesOnPlane(2, -depth)) solver.PrescribeVelocity(n, 2);
  const double dt = solver.StableTimeStep();
  while (solver.time_s() < 40 * depth / c) {
    const StepStatus status = solver.Step(dt);
    EXPECT_TRUE(status.ok) << status.reason;
    if (!status.ok) return dt;
  }

  const double g = units::kStandardGravityMps2;
  const double settlement = kDensity * g * depth * depth / (2 * PWaveModulus());
  const double top_z = solver.positions_m()[m.GridNode(0, 0, layers)].z();
  EXPECT_NEAR(-top_z, settlement, 0.01 * settlement);
  for (int e = 0; e < m.num_elements(); ++e) {
    const double centre_depth = depth * (layers - e - 0.5) / layers;  // elements stack upwards
    const double szz = -kDensity * g * centre_depth;
    const Eigen::Matrix3d& s = solver.element_stress_pa()[e];
    EXPECT_NEAR(s(2, 2), szz, 0.01 * kDensity * g * depth) << e;
    EXPECT_NEAR(s(0, 0), kPoisson / (1 - kPoisson) * szz, 0.01 * kDensity * g * depth) << e;
  }
  EXPECT_THROW(solver.SetMassScaling(2 * mass_scaling), std::logic_error);
  return dt;
}

TEST(ExplicitSolverTest, ColumnUnderSelfWeight) { CheckColumnUnderSelfWeight(1); }

TEST(ExplicitSolverTest, MassScalingKeepsTheWeightAndLengthensTheStep) {
  const double unscaled_dt = CheckColumnUnderSelfWeight(1);
  EXPECT_NEAR(CheckColumnUnderSelfWeight(16) / unscaled_dt, 4.0, 1e-12);
  // Set after construction, the same as given in the options.
  HexMesh mesh = MeshBox(Lines(1, 1.0), Lines(1, 1.0), Lines(1, 1.0));
  ExplicitOptions options = Options();
  ExplicitSolver later(mesh, Elastic(), options);
  later.SetMassScaling(9);
  options.mass_scaling = 9;
  ExplicitSolver given(mesh, Elastic(), options);
  EXPECT_DOUBLE_EQ(later.StableTimeStep(), given.StableTimeStep());
  EXPECT_DOUBLE_EQ(later.nodal_masses_kg()[0], given.nodal_masses_kg()[0]);
  EXPECT_THROW(later.SetMassScaling(0.5), InputError);
}

// One element under a drained triaxial path (lateral stress held by forces on the side faces,
// axial compression by prescribed velocity) reaches the Mohr-Coulomb deviator at failure,
// q_f = 2 (c cos phi + sigma_3 sin phi) / (1 - sin phi), through the whole FE path (F, S, nodal
// forces), not only the material point.
TEST(ExplicitSolverTest, DruckerPragerTriaxialThroughTheElement) {
  material::DruckerPragerParams p;
  p.young_pa = 20e6;
  p.poisson = 0.3;
  p.cohesion_pa = 5e3;
  p.friction_angle_deg = 30;
  p.dilation_angle_deg = 0;
  auto model = std::make_shared<material::DruckerPrager>(p);
  const double side = 0.1, sigma3 = 50e3;
  HexMesh mesh = MeshBox(Lines(1, side), Lines(1, side), Lines(1, side));
  ExplicitOptions options = Options();
  const double c = std::sqrt((model->InitialElasticModuli().bulk_pa +
                              4.0 / 3 * model->InitialElasticModuli().shear_pa) /
                             kDensity);
  options.mass_damping_per_s = units::kPi * c / side;
  ExplicitSolver solver(mesh, model, options);
  const HexMesh& m = solver.mesh();
  // Symmetry rollers on x = 0, y = 0, z = 0; confining forces on x = side and y = side.
  for (int n : m.NodesOnPlane(0, 0)) solver.PrescribeVelocity(n, 0);
  for (int n : m.NodesOnPlane(1, 0)) solver.PrescribeVelocity(n, 1);
  for (int n : m.NodesOnPlane(2, 0)) solver.PrescribeVelocity(n, 2);
  const double dt = solver.StableTimeStep();
  const double wave_time = side / c;
  auto confine = [&](double fraction) {
    // Face force sigma3 * area spread over 4 nodes; the area follows the current face.
    for (auto& f : solver.external_forces_n()) f.setZero();
    for (int axis = 0; axis < 2; ++axis) {
      const std::vector<int> face = m.NodesOnPlane(axis, side);
      const int other = 1 - axis;
      double lo1 = 1e9, hi1 = -1e9, lo2 = 1e9, hi2 = -1e9;
      for (int n : face) {
        lo1 = std::min(lo1, solver.positions_m()[n][other]);
        hi1 = std::max(hi1, solver.positions_m()[n][other]);
        lo2 = std::min(lo2, solver.positions_m()[n][2]);
        hi2 = std::max(hi2, solver.positions_m()[n][2]);
      }
      const double span1 = hi1 - lo1, span2 = hi2 - lo2;
      for (int n : face) solver.external_forces_n()[n][axis] = -fraction * sigma3 * span1 * span2 / 4;
    }
  };
  for (int k = 0; solver.time_s() < 200 * wave_time; ++k) {
    confine(std::min(1.0, solver.time_s() / (100 * wave_time)));
    ASSERT_TRUE(solver.Step(dt).ok);
  }
  const std::vector<int> top = m.NodesOnPlane(2, side);
  const double rate = 0.05 * side / (2000 * wave_time);  // 5 % strain over 2000 wave times
  for (int n : top) solver.PrescribeVelocity(n, 2, -rate);
  while (solver.time_s() < 2200 * wave_time) {
    confine(1.0);
    ASSERT_TRUE(solver.Step(dt).ok);
  }
  const Eigen::Matrix3d s = solver.element_stress_pa()[0];
  const double phi = units::DegreesToRadians(p.friction_angle_deg);
  const double q_expected = 2 * (p.cohesion_pa * std::cos(phi) + sigma3 * std::sin(phi)) /
                            (1 - std::sin(phi));
  EXPECT_NEAR(-s(0, 0), sigma3, 0.02 * sigma3);
  EXPECT_NEAR(-s(1, 1), sigma3, 0.02 * sigma3);
  EXPECT_NEAR(-s(2, 2) + s(0, 0), q_expected, 0.02 * q_expected);
}

TEST(ExplicitSolverTest, ThreadCountDoesNotChangeTheBits) {
  auto run = [](int threads) {
    HexMesh mesh = MeshBox(Lines(6, 0.6), Lines(4, 0.4), Lines(4, 0.4));
    material::DruckerPragerParams p{10e6, 0.3, 2e3, 30, 5};
    ExplicitOptions o = Options(5);
    o.threads = threads;
    o.gravity_m_s2 = Vec3(0, 0, -units::kStandardGravityMps2);
    ExplicitSolver solver(mesh, std::make_shared<material::DruckerPrager>(p), o);
    for (int n : solver.mesh().NodesOnPlane(2, 0)) {
      for (int d = 0; d < 3; ++d) solver.PrescribeVelocity(n, d);
    }
    for (int n : solver.mesh().NodesOnPlane(2, 0.4)) solver.PrescribeVelocity(n, 0, 0.05);
    for (int k = 0; k < 300; ++k) EXPECT_TRUE(solver.Step(solver.StableTimeStep()).ok);
    return solver.positions_m();
  };
  const auto one = run(1), two = run(2);
  for (size_t n = 0; n < one.size(); ++n) EXPECT_EQ(one[n], two[n]) << n;
}

TEST(ExplicitSolverTest, AnInvertedElementFailsTheStepAndChangesNothing) {
  HexMesh mesh = MeshBox(Lines(1, 0.1), Lines(1, 0.1), Lines(1, 0.1));
  ExplicitSolver solver(mesh, Elastic(), Options());
  const int corner = solver.mesh().GridNode(1, 1, 1);
  // One step that throws the top corner through the opposite face.
  for (int d = 0; d < 3; ++d) solver.PrescribeVelocity(corner, d, -1.0);
  ASSERT_TRUE(solver.Step(0.2).ok);
  const std::vector<Vec3> before = solver.positions_m();
  const double t = solver.time_s();
  const StepStatus status = solver.Step(0.2);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.reason.find("inside out"), std::string::npos) << status.reason;
  EXPECT_EQ(solver.positions_m(), before);
  EXPECT_EQ(solver.time_s(), t);
}

// Linear elastic whose update of element 0 fails while `refuse` is set: a material failure (the
// kind an RVE or a return map may report) that the solver must survive.
class RefusingMaterial : public material::ConstitutiveModel {
 public:
  std::string Name() const override { return "refusing-linear-elastic"; }
  std::unique_ptr<material::MaterialState> InitialState() const override {
    return inner_.InitialState();
  }
  std::unique_ptr<material::MaterialState> RestoreState(const std::string& bytes) const override {
    return inner_.RestoreState(bytes);
  }
  std::vector<material::PointResponse> Update(
      const std::vector<material::PointIncrement>& increments, bool want_tangent) const override {
    std::vector<material::PointResponse> responses = inner_.Update(increments, want_tangent);
    if (refuse && !responses.empty()) {
      responses[0] = material::PointResponse();
      responses[0].reason = "refused";
    }
    return responses;
  }
  bool refuse = false;

 private:
  material::LinearElastic inner_{material::LinearElasticParams{kYoung, kPoisson}};
};

// A failed material update discards the step's trial states: the committed states, positions and
// time stay, and retrying the step gives the bits of a run that never failed.
TEST(ExplicitSolverTest, AFailedMaterialUpdateDiscardsTheTrialStates) {
  auto make = [](std::shared_ptr<const material::ConstitutiveModel> model) {
    auto solver = std::make_unique<ExplicitSolver>(
        MeshBox(Lines(2, 0.2), Lines(1, 0.1), Lines(1, 0.1)), std::move(model), Options(5));
    for (int n : solver->mesh().NodesOnPlane(2, 0)) {
      for (int d = 0; d < 3; ++d) solver->PrescribeVelocity(n, d);
    }
    for (int n : solver->mesh().NodesOnPlane(2, 0.1)) solver->PrescribeVelocity(n, 2, -0.01);
    return solver;
  };
  auto refusing = std::make_shared<RefusingMaterial>();
  auto solver = make(refusing);
  auto reference = make(std::make_shared<material::LinearElastic>(
      material::LinearElasticParams{kYoung, kPoisson}));
  const double dt = solver->StableTimeStep();
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(solver->Step(dt).ok);
    ASSERT_TRUE(reference->Step(dt).ok);
  }
  const material::MaterialPointStore& points = solver->material_points();
  std::vector<std::string> committed;
  for (int e = 0; e < solver->mesh().num_elements(); ++e) {
    committed.push_back(points.Serialize(solver->element_point(e)));
  }
  const std::vector<Vec3> positions = solver->positions_m();
  refusing->refuse = true;
  const StepStatus status = solver->Step(dt);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.reason.find("refused"), std::string::npos) << status.reason;
  for (int e = 0; e < solver->mesh().num_elements(); ++e) {
    EXPECT_EQ(points.Serialize(solver->element_point(e)), committed[e]) << e;  // element 1 too
  }
  EXPECT_EQ(solver->positions_m(), positions);
  refusing->refuse = false;
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(solver->Step(dt).ok);
    ASSERT_TRUE(reference->Step(dt).ok);
  }
  EXPECT_EQ(solver->positions_m(), reference->positions_m());
  for (int e = 0; e < solver->mesh().num_elements(); ++e) {
    EXPECT_EQ(points.Serialize(solver->element_point(e)),
              reference->material_points().Serialize(reference->element_point(e)));
  }
}

// Hourglass control, incremental stiffness form: its scale factor r against closed forms, and
// in an elastic element the increments add up to the total-displacement force kappa gamma^T q.
TEST(HourglassTest, RetainedFractionIsOneElasticAndTheRadialReturnFactorPlastic) {
  const double cohesion = 10e3, shear_modulus = kYoung / (2 * (1 + kPoisson));
  material::DruckerPragerParams p;
  p.young_pa = kYoung;
  p.poisson = kPoisson;
  p.cohesion_pa = cohesion;
  p.friction_angle_deg = 0;  // von Mises: sqrt(J2) = xi c, xi = 2 / sqrt(3) (compression match)
  const material::DruckerPrager model(p);
  const auto state = model.InitialState();
  auto shear = [&](double gamma) {
    material::PointIncrement increment;
    increment.displacement_gradient_increment(0, 1) = gamma;
    increment.committed = state.get();
    const std::vector<material::PointResponse> responses = model.Update({increment}, false);
    const material::PointResponse& response = responses[0];
    return RetainedDeviatoricFraction(Eigen::Matrix3d::Zero(), response.stress_pa,
                                      increment.displacement_gradient_increment, shear_modulus);
  };
  // Elastic: ||s|| = sqrt(2) G gamma below sqrt(2) (2 / sqrt(3)) c.
  EXPECT_EQ(shear(0.5 * cohesion / shear_modulus), 1.0);
  // Plastic, G gamma = 4 c: r = (2 sqrt(2) c / sqrt(3)) / (sqrt(2) G gamma) = 1 / (2 sqrt(3)).
  EXPECT_NEAR(shear(4 * cohesion / shear_modulus), 1 / (2 * std::sqrt(3.0)), 1e-9);
}

TEST(HourglassTest, ElasticIncrementsAddUpToTheTotalForm) {
  ExplicitOptions options = Options();
  options.hourglass_viscosity = 0;
  ExplicitSolver solver(MeshBox(Lines(1, 0.1), Lines(1, 0.1), Lines(1, 0.1)), Elastic(), options);
  const Hex8Reference& r = solver.element_reference(0);
  // Drive the nodes along the first hourglass vector in x over 20 steps, then hold them.
  const double dt = 1e-4, amplitude_m = 1e-4;
  for (int k = 0; k <= 20; ++k) {
    for (int a = 0; a < 8; ++a) {
      const int node = solver.mesh().elements[0][a];
      const double v = k < 20 ? amplitude_m * r.hourglass_vectors(0, a) / (20 * dt) : 0.0;
      for (int d = 0; d < 3; ++d) solver.PrescribeVelocity(node, d, d == 0 ? v : 0.0);
    }
    ASSERT_TRUE(solver.Step(dt).ok);
  }
  // Pure hourglass motion: no centroid strain, so no stress, and the force is kappa gamma^T q.
  EXPECT_LT(solver.element_stress_pa()[0].norm(), 1e-6);
  const double kappa = options.hourglass_coefficient * PWaveModulus() * r.volume_m3 *
                       r.gradients_per_m.squaredNorm() / 3.0;
  const double q = amplitude_m * r.hourglass_vectors.row(0).squaredNorm();
  for (int a = 0; a < 8; ++a) {
    const int node = solver.mesh().elements[0][a];
    EXPECT_NEAR(solver.internal_forces_n()[node].x(), kappa * r.hourglass_vectors(0, a) * q,
                1e-9 * kappa * q);
  }
}

TEST(MeshTest, GradedLinesEndExactlyAndGrow) {
  const std::vector<double> l = GradedLines(0, 1.0, 0.05, 0.2, 1.3, 0.2);
  EXPECT_DOUBLE_EQ(l.front(), 0.0);
  EXPECT_DOUBLE_EQ(l.back(), 1.0);
  for (size_t i = 1; i < l.size(); ++i) {
    const double size = l[i] - l[i - 1];
    EXPECT_GT(size, 0.0);
    EXPECT_LE(size, 0.2 * 1.5 + 1e-12);
    if (l[i] <= 0.2 + 1e-12) {
      EXPECT_NEAR(size, 0.05, 1e-12);
    }
  }
  SoilBinSpec bin{2.0, 1.0, 0.5, 0.05, 0.15, 0.2};
  const HexMesh m = MeshSoilBin(bin);
  EXPECT_DOUBLE_EQ(m.z_lines_m.back(), 0.0);
  EXPECT_DOUBLE_EQ(m.z_lines_m.front(), -0.5);
  EXPECT_DOUBLE_EQ(m.y_lines_m.front(), 0.0);
  EXPECT_DOUBLE_EQ(m.y_lines_m.back(), 0.5);
  bin.element_size_m = -1;
  EXPECT_THROW(MeshSoilBin(bin), InputError);
}

}  // namespace
}  // namespace gonogo::fe
