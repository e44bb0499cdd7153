// Whole-system checks: energy over many elastic collisions, momentum, settling on a wall under
// gravity, history across rebuilds, determinism and thread-count independence.
#include "solvers/dem/simulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"

namespace gonogo::dem {
namespace {

// Velocity Verlet at 0.1 of the Rayleigh step: bounded, O(dt^2) energy error.
constexpr double kEnergyDriftBound = 2e-4;

// `count` grains of radius 0.87 mm +-5 % on a cubic lattice of spacing `spacing_radii` r_mean in a
// periodic box, random velocities up to `speed_m_s` per component and spins up to `spin_rad_s`.
Particles Lattice(int side, double spacing_radii, double speed_m_s, double spin_rad_s,
                  unsigned seed, double* box_length_m) {
  const double radius_m = 0.87e-3, spacing_m = spacing_radii * radius_m;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Particles grains;
  for (int g = 0; g < side * side * side; ++g) {
    const Vec3 site((g % side + 0.5) * spacing_m, ((g / side) % side + 0.5) * spacing_m,
                    (g / (side * side) + 0.5) * spacing_m);
    const Vec3 velocity(unit(random), unit(random), unit(random));
    const Vec3 spin(unit(random), unit(random), unit(random));
    const std::size_t p =
        grains.Add(site, speed_m_s * velocity, radius_m * (1.0 + 0.05 * unit(random)), 2650.0);
    grains.angular_velocity_rad_s[p] = spin_rad_s * spin;
  }
  *box_length_m = side * spacing_m;
  return grains;
}

TEST(Simulation, EnergyIsConservedOverManyElasticFrictionlessCollisions) {
  SimulationParams params;
  params.material.restitution = 1.0;
  params.material.friction = 0.0;
  params.material.rolling_stiffness = 0.0;
  double length_m = 0.0;
  Particles grains = Lattice(6, 3.0, 1.0, 0.0, 7, &length_m);
  params.box.hi_m = Vec3::Constant(length_m);
  params.time_step_safety = 0.1;
  Simulation sim(params, grains);
  const double energy0_j = sim.KineticEnergyJ() + sim.ElasticNormalEnergyJ();
  double contact_steps = 0.0, worst = 0.0;
  for (int step = 0; step < 60000; ++step) {
    sim.Step();
    contact_steps += sim.ContactCount();
    const double energy_j = sim.KineticEnergyJ() + sim.ElasticNormalEnergyJ();
    worst = std::max(worst, std::abs(energy_j / energy0_j - 1.0));
  }
  // A 1 m/s impact lasts t_c ~ 2.2e-6 s: convert contact-steps to collisions.
  const double collisions = contact_steps * sim.time_step_s() / 2.2e-6;
  EXPECT_GT(collisions, 1000.0);
  EXPECT_LT(worst, kEnergyDriftBound);
}

TEST(Simulation, IsolatedClusterConservesLinearAndAngularMomentum) {
  SimulationParams params;
  params.material.restitution = 0.5;  // full seed 000 law: damping, friction, rolling
  params.box.periodic = {false, false, false};
  double length_m = 0.0;
  Particles grains = Lattice(5, 2.1, 0.5, 200.0, 11, &length_m);
  params.box.hi_m = Vec3::Constant(length_m);
  // Pull everything towards the centre so that the cluster collides.
  for (std::size_t p = 0; p < grains.size(); ++p) {
    grains.velocity_m_s[p] -=
        0.3 * (grains.position_m[p] - Vec3::Constant(0.5 * length_m)) / (0.5 * length_m);
  }
  Simulation sim(params, grains);
  const Vec3 p0 = sim.LinearMomentumKgMS();
  const Vec3 l0 = sim.AngularMomentumKgM2S();
  const double p_scale = 125 * grains.mass_kg[0] * 0.5;
  const double l_scale = p_scale * length_m;
  long contact_steps = 0;
  for (int step = 0; step < 20000; ++step) {
    sim.Step();
    contact_steps += sim.ContactCount();
  }
  EXPECT_GT(contact_steps, 5000);
  EXPECT_LT((sim.LinearMomentumKgMS() - p0).norm(), 1e-12 * p_scale);
  EXPECT_LT((sim.AngularMomentumKgM2S() - l0).norm(), 1e-11 * l_scale);
}

TEST(Simulation, SphereSettlesOnAFloorAtTheHertzStaticOverlap) {
  SimulationParams params;
  params.material.restitution = 0.3;
  params.box.periodic = {false, false, false};
  params.box.lo_m = Vec3::Constant(-0.01);
  params.box.hi_m = Vec3::Constant(0.01);
  params.walls.push_back(Wall{Vec3::Zero(), Vec3::UnitZ()});
  params.gravity_m_s2 = Vec3(0.0, 0.0, -units::kStandardGravityMps2);
  const double radius_m = 0.87e-3;
  Particles grains;
  grains.Add(Vec3(0, 0, radius_m * 1.01), Vec3::Zero(), radius_m, 2650.0);
  Simulation sim(params, grains);
  sim.Run(static_cast<int>(0.1 / sim.time_step_s()));
  // m g = 4/3 E* sqrt(r) d^{3/2} for a sphere on a rigid plane with the pair E*.
  const double weight_n = grains.mass_kg[0] * units::kStandardGravityMps2;
  const double expected_m =
      std::pow(3.0 * weight_n / (4.0 * params.material.EffectiveModulusPa() * std::sqrt(radius_m)),
               2.0 / 3.0);
  const double overlap_m = radius_m - sim.particles().position_m[0].z();
  EXPECT_NEAR(overlap_m / expected_m, 1.0, 1e-3);
  EXPECT_LT(sim.particles().velocity_m_s[0].norm(), 1e-6);
}

// A damped dense packing (the benchmark's state) after `steps` steps.
Particles DensePacking(int threads, double skin_fraction, int steps) {
  SimulationParams params;
  params.material.restitution = 0.5;
  params.threads = threads;
  params.skin_fraction = skin_fraction;
  double length_m = 0.0;
  Particles grains = Lattice(8, 2.0, 0.05, 0.0, 3, &length_m);
  params.box.hi_m = Vec3::Constant(length_m);
  Simulation sim(params, grains);
  sim.Run(steps);
  EXPECT_GT(sim.ContactCount(), 500);
  return sim.particles();
}

double MaxDifferenceM(const Particles& a, const Particles& b) {
  double worst = 0.0;
  for (std::size_t p = 0; p < a.size(); ++p) {
    Vec3 delta = a.position_m[p] - b.position_m[p];
    worst = std::max(worst, delta.cwiseAbs().maxCoeff());
  }
  return worst;
}

TEST(Simulation, TwoRunsAreBitIdenticalAndThreadCountDoesNotMatter) {
  const Particles first = DensePacking(2, 0.2, 400);
  const Particles second = DensePacking(2, 0.2, 400);
  for (std::size_t p = 0; p < first.size(); ++p) {
    ASSERT_EQ(first.position_m[p], second.position_m[p]) << p;
    ASSERT_EQ(first.angular_velocity_rad_s[p], second.angular_velocity_rad_s[p]) << p;
  }
  // Pairs are computed independently and summed per particle in pair order, on two threads in a
  // second pass, on one thread as each pair is done: the same additions in the same order, so
  // the two agree bit for bit.
  const Particles serial = DensePacking(1, 0.2, 400);
  for (std::size_t p = 0; p < first.size(); ++p) {
    ASSERT_EQ(first.position_m[p], serial.position_m[p]) << p;
    ASSERT_EQ(first.angular_velocity_rad_s[p], serial.angular_velocity_rad_s[p]) << p;
  }
}

TEST(Simulation, ContactHistorySurvivesNeighbourListRebuilds) {
  // A tiny skin rebuilds the list every few steps; a large one rarely. Carried history makes the
  // two runs agree to round-off; losing it would reset every tangential and rolling spring.
  const Particles often = DensePacking(1, 0.002, 2000);
  const Particles rarely = DensePacking(1, 0.5, 2000);
  EXPECT_LT(MaxDifferenceM(often, rarely), 1e-12);
}

TEST(Simulation, RayleighStepAndValidation) {
  MaterialParams material;
  // pi r sqrt(rho / G) / (0.1631 nu + 0.8766) for the seed 000 grain.
  const double shear_pa = 1.5e9 / (2.0 * 1.293);
  const double expected_s =
      units::kPi * 0.87e-3 * std::sqrt(2650.0 / shear_pa) / (0.1631 * 0.293 + 0.8766);
  EXPECT_NEAR(RayleighTimeStepS(0.87e-3, material) / expected_s, 1.0, 1e-12);
  SimulationParams params;
  Particles grains;
  grains.Add(Vec3::Constant(0.5), Vec3::Zero(), 0.87e-3, 2650.0);
  Simulation sim(params, grains);
  EXPECT_NEAR(sim.time_step_s() / (0.2 * expected_s), 1.0, 1e-12);
  params.threads = 0;
  EXPECT_THROW(Simulation(params, grains), InputError);
  params.threads = 1;
  params.box.hi_m = Vec3::Constant(1.5e-3);  // < 2 r + skin: a grain would touch its own image
  EXPECT_THROW(Simulation(params, grains).Step(), InputError);
}

}  // namespace
}  // namespace gonogo::dem
