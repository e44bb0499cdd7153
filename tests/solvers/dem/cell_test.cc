// The deforming periodic cell: contacts through the sheared image, affine remapping of grains and
// cell edges, the rebuild rule under deformation, and bit-identical save and restore.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "solvers/common/errors.h"
#include "solvers/dem/neighbor_list.h"
#include "solvers/dem/simulation.h"

namespace gonogo::dem {
namespace {

constexpr double kRadiusM = 1e-3;
constexpr double kSideM = 10e-3;

SimulationParams FrictionlessCube() {
  SimulationParams params;
  params.material.friction = 0.0;
  params.material.rolling_stiffness = 0.0;
  params.box.hi_m = Vec3::Constant(kSideM);
  return params;
}

// 216 grains on a 6 x 6 x 6 lattice of spacing 1.9 mm, radii 1 mm +- 5 % (so neighbours overlap)
// and small random velocities, in a periodic cube: a jammed packing once it runs.
constexpr int kLatticeSide = 6;
constexpr double kLatticeSpacingM = 1.9e-3;

Particles JammedLatticeGrains() {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Particles grains;
  const int side = kLatticeSide;
  for (int g = 0; g < side * side * side; ++g) {
    const Vec3 site((g % side + 0.5) * kLatticeSpacingM,
                    ((g / side) % side + 0.5) * kLatticeSpacingM,
                    (g / (side * side) + 0.5) * kLatticeSpacingM);
    grains.Add(site, 0.02 * Vec3(unit(random), unit(random), unit(random)),
               kRadiusM * (1.0 + 0.05 * unit(random)), 2650.0);
  }
  return grains;
}

SimulationParams JammedLatticeParams() {
  SimulationParams params;
  params.material.restitution = 0.5;
  params.box.hi_m = Vec3::Constant(kLatticeSide * kLatticeSpacingM);
  return params;
}

// Simple shear u_x = gamma z brings B's image through the top face into contact with A, and only
// the sheared image: in the unsheared cell the same image is 2.12 r_sum away.
TEST(DeformingCell, ContactThroughTheShearedImageOfTheTopFace) {
  const double gamma = 0.5, overlap_m = 0.05e-3, gap_m = 2.0 * kRadiusM - overlap_m;
  const Vec3 a(2e-3, 5e-3, 1.5e-3);
  // After the shear, A' = A + gamma z_A e_x; B' - c' (c' = (gamma L, 0, L)) must sit gap_m
  // below A'.
  const double z_b = kSideM + a.z() - gap_m;
  const double x_b = a.x() + gamma * (a.z() + kSideM - z_b);
  // Very heavy grains: the contact force does not move them, so the geometry stays closed-form.
  const double density_kg_m3 = 2650e9;
  Particles grains;
  grains.Add(a, Vec3::Zero(), kRadiusM, density_kg_m3);
  grains.Add(Vec3(x_b, a.y(), z_b), Vec3::Zero(), kRadiusM, density_kg_m3);
  SimulationParams params = FrictionlessCube();
  params.material.density_kg_m3 = density_kg_m3;
  params.time_step_s = 1e-7;
  Simulation sim(params, grains);
  sim.Run(1);
  EXPECT_EQ(sim.ContactCount(), 0);  // no contact through the unsheared cell
  const int steps = 200;
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  gradient(0, 2) = gamma / (steps * params.time_step_s);
  sim.SetVelocityGradient(gradient);
  sim.Run(steps - 1);
  sim.SetVelocityGradient(Eigen::Matrix3d::Zero());
  sim.Run(1);  // the remaining step with the cell fixed: the shear totals gamma - gamma/steps

  // The cell's third edge is (gamma L, 0, L) (exactly, up to the last step), the first two are
  // untouched.
  const Eigen::Matrix3d& edges = sim.cell().edges_m;
  EXPECT_NEAR(edges(0, 2), gamma * kSideM * (steps - 1) / steps, 1e-12);
  EXPECT_NEAR(edges(2, 2), kSideM, 1e-15);
  EXPECT_NEAR(edges(0, 0), kSideM, 1e-15);
  EXPECT_NEAR(edges(1, 1), kSideM, 1e-15);
  ASSERT_EQ(sim.ContactCount(), 1);
  // Branch d = A' - image of B': (-(gamma/steps) gap, 0, gap), the missing last share of the shear
  // acting over the gap; force along d with the Hertz magnitude of the resulting overlap.
  const Vec3 branch(-gamma / steps * gap_m, 0.0, gap_m);
  const double overlap_now_m = 2.0 * kRadiusM - branch.norm();
  const double e_star_pa = params.material.EffectiveModulusPa();
  const double force_n = 4.0 / 3.0 * e_star_pa * std::sqrt(0.5 * kRadiusM) *
                         std::pow(overlap_now_m, 1.5);
  const Eigen::Matrix3d expected = branch * (force_n * branch.normalized()).transpose();
  const Eigen::Matrix3d virial = sim.ContactVirialNM();
  EXPECT_LT((virial - expected).norm(), 1e-6 * expected.norm()) << virial << "\n" << expected;
}

// The affine map moves every grain with the cell: after an isotropic stretch the fractional
// coordinates of a contact-free gas are unchanged.
TEST(DeformingCell, GrainsFollowTheCellAffinely) {
  Particles grains;
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  for (int g = 0; g < 8; ++g) {
    grains.Add(Vec3(unit(random) * kSideM, (g + 0.5) * kSideM / 8, unit(random) * kSideM),
               Vec3::Zero(), 0.2e-3, 2650.0);
  }
  SimulationParams params = FrictionlessCube();
  params.time_step_s = 1e-6;
  Simulation sim(params, grains);
  Eigen::Matrix3d gradient;
  gradient << 10.0, 0.0, 30.0, 0.0, -20.0, 0.0, 5.0, 0.0, 10.0;  // 1/s
  sim.SetVelocityGradient(gradient);
  sim.Run(1000);
  const Eigen::Matrix3d to_fraction = sim.cell().edges_m.inverse();
  for (int g = 0; g < 8; ++g) {
    const Vec3 fraction0 = grains.position_m[g] / kSideM;
    const Vec3 fraction = to_fraction * sim.UnwrappedPositionM(g);
    EXPECT_LT((fraction - fraction0).norm(), 1e-12) << "grain " << g;
  }
  // V = V0 det(product of (I + dt L)).
  const Eigen::Matrix3d step = Eigen::Matrix3d::Identity() + 1e-6 * gradient;
  double det = 1.0;
  for (int s = 0; s < 1000; ++s) det *= step.determinant();
  EXPECT_NEAR(sim.cell().VolumeM3() / std::pow(kSideM, 3), det, 1e-12);
}

// A deforming cell needs every axis periodic and no walls.
TEST(DeformingCell, RefusedWithWallsOrOpenAxes) {
  Particles grains;
  grains.Add(Vec3::Constant(5e-3), Vec3::Zero(), kRadiusM, 2650.0);
  SimulationParams params = FrictionlessCube();
  params.box.periodic = {true, true, false};
  Simulation open(params, grains);
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  gradient(0, 1) = 1.0;
  EXPECT_THROW(open.SetVelocityGradient(gradient), InputError);
  gradient(0, 1) = std::nan("");
  EXPECT_THROW(open.SetVelocityGradient(gradient), InputError);
}

// Simple shear to gamma = 3 of a contact-free gas: the cell is reduced at every half edge of tilt
// (gamma 0.5, 1.5, 2.5). The grains also drift along z (each in its own y slab, so they never
// meet) and wrap through the sheared faces; their unwrapped positions follow the recurrence of
// the integrator, x += dt L x + dt v, through every reduction.
TEST(DeformingCell, ShearToGammaThreeReducesTheCellAndKeepsUnwrappedPositions) {
  Particles grains;
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  for (int g = 0; g < 8; ++g) {
    grains.Add(Vec3(unit(random) * kSideM, (g + 0.5) * kSideM / 8, unit(random) * kSideM),
               Vec3(0.0, 0.0, (g % 2 == 0 ? 1.0 : -1.0) * (2.0 + g)), 0.2e-3, 2650.0);
  }
  SimulationParams params = FrictionlessCube();
  params.time_step_s = 1e-6;
  Simulation sim(params, grains);
  const int steps = 3000;
  const double gamma = 3.0;
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  gradient(0, 2) = gamma / (steps * params.time_step_s);
  sim.SetVelocityGradient(gradient);
  sim.Run(steps);
  EXPECT_EQ(sim.cell_reduction_count(), 3);
  // The reduced third edge is (gamma - 3) L e_x + L e_z: tilt within half an edge.
  EXPECT_NEAR(sim.cell().edges_m(0, 2), (gamma - 3.0) * kSideM, 1e-12);
  EXPECT_NEAR(sim.cell().edges_m(2, 2), kSideM, 1e-15);
  EXPECT_NEAR(sim.cell().VolumeM3(), std::pow(kSideM, 3), 1e-18);
  const Eigen::Matrix3d increment = params.time_step_s * gradient;
  int wrapped = 0;
  for (int g = 0; g < 8; ++g) {
    Vec3 expected_m = grains.position_m[g];
    for (int step = 0; step < steps; ++step) {
      expected_m += increment * expected_m + params.time_step_s * grains.velocity_m_s[g];
    }
    EXPECT_LT((sim.UnwrappedPositionM(g) - expected_m).norm(), 1e-12) << g;
    wrapped += sim.particles().image[g][2] != 0;
  }
  EXPECT_GE(wrapped, 4);  // the z drift (6 to 27 mm) takes grains through the sheared faces
}

// A jammed packing sheared from gamma 0 to 0.8 (past the reduction at 0.5) with and without
// reducing the cell: the same periodic system, so the same contacts, stress and unwrapped
// positions up to round-off; without reduction the tilt stays 0.8 L.
TEST(DeformingCell, ReducingTheCellChangesNothingPhysical) {
  const Particles grains = JammedLatticeGrains();
  const SimulationParams params = JammedLatticeParams();
  SimulationParams fixed = params;
  fixed.reduce_sheared_cell = false;
  Simulation reduced(params, grains), unreduced(fixed, grains);
  const int steps = 400;
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  gradient(0, 2) = 0.8 / (steps * reduced.time_step_s());
  reduced.SetVelocityGradient(gradient);
  unreduced.SetVelocityGradient(gradient);
  reduced.Run(steps);
  unreduced.Run(steps);
  EXPECT_EQ(reduced.cell_reduction_count(), 1);
  EXPECT_EQ(unreduced.cell_reduction_count(), 0);
  EXPECT_NEAR(unreduced.cell().edges_m(0, 2), 0.8 * kLatticeSide * kLatticeSpacingM, 1e-12);
  EXPECT_NEAR(reduced.cell().edges_m(0, 2), -0.2 * kLatticeSide * kLatticeSpacingM, 1e-12);
  ASSERT_GT(reduced.ContactCount(), 100);
  EXPECT_EQ(reduced.ContactCount(), unreduced.ContactCount());
  const Eigen::Matrix3d virial = unreduced.ContactVirialNM();
  EXPECT_LT((reduced.ContactVirialNM() - virial).norm(), 1e-9 * virial.norm());
  for (std::size_t g = 0; g < grains.size(); ++g) {
    ASSERT_LT((reduced.UnwrappedPositionM(g) - unreduced.UnwrappedPositionM(g)).norm(), 1e-12) << g;
  }
}

// A jammed, sheared packing saved mid-run and restored into a fresh Simulation continues
// bit-identically; a damaged buffer is refused and leaves the target untouched.
TEST(DeformingCell, SaveAndRestoreContinueBitIdentically) {
  const Particles grains = JammedLatticeGrains();
  const SimulationParams params = JammedLatticeParams();
  Simulation original(params, grains);
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  gradient(0, 2) = 20.0;
  gradient(2, 2) = -5.0;
  original.SetVelocityGradient(gradient);
  original.Run(300);
  const std::string saved = original.SaveState();
  original.Run(400);

  Particles single_grain;
  single_grain.Add(Vec3::Zero(), Vec3::Zero(), kRadiusM, 2650.0);
  Simulation restored(params, single_grain);
  restored.RestoreState(saved);
  restored.Run(400);
  ASSERT_GT(original.ContactCount(), 100);
  EXPECT_EQ(restored.ContactCount(), original.ContactCount());
  EXPECT_EQ(restored.time_s(), original.time_s());
  EXPECT_TRUE(restored.cell().edges_m == original.cell().edges_m);
  EXPECT_TRUE(restored.ContactVirialNM() == original.ContactVirialNM());
  for (std::size_t p = 0; p < grains.size(); ++p) {
    ASSERT_TRUE(restored.particles().position_m[p] == original.particles().position_m[p]) << p;
    ASSERT_TRUE(restored.particles().angular_velocity_rad_s[p] ==
                original.particles().angular_velocity_rad_s[p])
        << p;
  }
  // About 180 bytes per grain (with the neighbour list's build positions), 150 per contact.
  EXPECT_LT(saved.size(), 200u * grains.size() + 200u * original.ContactCount());

  Simulation untouched(params, single_grain);
  const std::string before = untouched.SaveState();
  EXPECT_THROW(untouched.RestoreState(saved.substr(0, saved.size() / 2)), InputError);
  EXPECT_THROW(untouched.RestoreState("not a state"), InputError);
  std::string corrupt = saved;
  corrupt[0] = 'X';
  EXPECT_THROW(untouched.RestoreState(corrupt), InputError);
  // A state of an older format is refused by name, not misread.
  std::string older = saved;
  older[6] = '0';
  older[7] = '1';
  try {
    untouched.RestoreState(older);
    ADD_FAILURE() << "an older format was read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("saved in format GNGDEM01"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(untouched.SaveState(), before);
}

// A cell squeezed along z until it is 1, 2, 3 or 5 neighbour bins thick (a small RVE under a
// plate), and sheared: the linked-cell list holds exactly the (i, j, image) a search over all 27
// images of every pair finds within r_i + r_j + skin. Two images of one neighbour can both be
// within reach in the thinnest cells; each is a pair of its own.
TEST(NeighbourList, ThinShearedCellsListEveryImageWithinReachOnce) {
  const double radius_m = 1e-3, skin_m = 0.2e-3, reach_max_m = 2 * 1.05 * radius_m + skin_m;
  for (double bins_thick : {1.2, 2.5, 3.5, 5.5}) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    Cell cell;
    cell.edges_m << 12e-3, 0.0, 0.3 * bins_thick * reach_max_m,  //
        0.0, 11e-3, 0.0,                                        //
        0.0, 0.0, bins_thick * reach_max_m;
    Particles grains;
    for (int g = 0; g < 60; ++g) {
      const Vec3 fraction(unit(random), unit(random), unit(random));
      grains.Add(cell.edges_m * fraction, Vec3::Zero(), radius_m * (0.95 + 0.1 * unit(random)),
                 2650.0);
    }
    std::set<std::tuple<int, int, int, int, int>> expected;
    for (int i = 0; i < 60; ++i) {
      for (int j = i + 1; j < 60; ++j) {
        for (int wx = -1; wx <= 1; ++wx) {
          for (int wy = -1; wy <= 1; ++wy) {
            for (int wz = -1; wz <= 1; ++wz) {
              const Vec3 separation = grains.position_m[j] +
                                      cell.edges_m * Vec3(wx, wy, wz) - grains.position_m[i];
              const double reach = grains.radius_m[i] + grains.radius_m[j] + skin_m;
              if (separation.squaredNorm() < reach * reach) expected.insert({i, j, wx, wy, wz});
            }
          }
        }
      }
    }
    NeighborList list;
    list.Build(grains, cell, skin_m, 1);
    std::set<std::tuple<int, int, int, int, int>> listed;
    for (const NeighborPair& pair : list.pairs()) {
      const bool inserted =
          listed.insert({pair.i, pair.j, pair.image[0], pair.image[1], pair.image[2]}).second;
      EXPECT_TRUE(inserted) << bins_thick << " bins: pair " << pair.i << "-" << pair.j
                            << " listed twice";
    }
    EXPECT_EQ(listed, expected) << bins_thick << " bins thick";
    EXPECT_GT(expected.size(), 20u);
  }
  // Thinner than one reach: refused, naming the cause.
  Cell flat;
  flat.edges_m = Eigen::Vector3d(12e-3, 11e-3, 0.8 * reach_max_m).asDiagonal();
  Particles two;
  two.Add(Vec3(1e-3, 1e-3, 0.5e-3), Vec3::Zero(), 1.05 * radius_m, 2650.0);
  two.Add(Vec3(5e-3, 5e-3, 0.5e-3), Vec3::Zero(), 1.05 * radius_m, 2650.0);
  NeighborList list;
  try {
    list.Build(two, flat, skin_m, 1);
    ADD_FAILURE() << "a cell thinner than 2 r_max + skin was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 r_max + skin thick"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace gonogo::dem
