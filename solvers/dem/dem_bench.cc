// gonogo-dem-bench --grains N --steps S [--threads T] [--seed K]
//
// A periodic cubic packing of N polydisperse grains with the seed 000 parameters (E 1.5 GPa,
// nu 0.293, mu 0.452, beta 2.25, eta 0.99, radius 0.87 mm +-5 %, density 2650 kg/m3, e 0.5) on a
// lattice of spacing 2 r_mean, so about half the neighbours start overlapping, run for S steps at
// 0.2 of the Rayleigh step. Prints particle-steps per second (figures only; not a test).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <random>
#include <string>

#include "solvers/dem/simulation.h"

namespace {

struct Options {
  int grains = 5000;
  int steps = 1000;
  int threads = 1;
  unsigned seed = 1;
};

Options Parse(int argc, char** argv) {
  Options options;
  if ((argc - 1) % 2 != 0) {
    std::fprintf(stderr, "usage: gonogo-dem-bench --grains N --steps S [--threads T]\n");
    std::exit(2);
  }
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string flag = argv[a];
    const int value = std::atoi(argv[a + 1]);
    if (flag == "--grains") {
      options.grains = value;
    } else if (flag == "--steps") {
      options.steps = value;
    } else if (flag == "--threads") {
      options.threads = value;
    } else if (flag == "--seed") {
      options.seed = static_cast<unsigned>(value);
    } else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      std::exit(2);
    }
  }
  if (options.grains < 1 || options.steps < 1 || options.threads < 1) {
    std::fprintf(stderr, "usage: gonogo-dem-bench --grains N --steps S [--threads T]\n");
    std::exit(2);
  }
  return options;
}

}  // namespace

int main(int argc, char** argv) {
  using gonogo::dem::Vec3;
  const Options options = Parse(argc, argv);
  try {
    gonogo::dem::SimulationParams params;
    params.material.restitution = 0.5;
    params.threads = options.threads;
    const double mean_radius_m = 0.87e-3;
    const int side = static_cast<int>(std::ceil(std::cbrt(static_cast<double>(options.grains))));
    const double spacing_m = 2.0 * mean_radius_m;
    params.box.lo_m = Vec3::Zero();
    params.box.hi_m = Vec3::Constant(side * spacing_m);

    std::mt19937_64 random(options.seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    gonogo::dem::Particles grains;
    for (int g = 0; g < options.grains; ++g) {
      const Vec3 site((g % side + 0.5) * spacing_m, ((g / side) % side + 0.5) * spacing_m,
                      (g / (side * side) + 0.5) * spacing_m);
      const Vec3 velocity(0.05 * unit(random), 0.05 * unit(random), 0.05 * unit(random));
      grains.Add(site, velocity, mean_radius_m * (1.0 + 0.05 * unit(random)),
                 params.material.density_kg_m3);
    }
    gonogo::dem::Simulation simulation(params, grains);
    simulation.Run(10);  // first neighbour build and force evaluation outside the timing

    const auto start = std::chrono::steady_clock::now();
    simulation.Run(options.steps);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double rate = static_cast<double>(options.grains) * options.steps / seconds;
    std::printf("grains,steps,threads,dt_s,contacts,rebuilds,wall_s,particle_steps_per_s\n");
    std::printf("%d,%d,%d,%.3e,%d,%d,%.3f,%.4e\n", options.grains, options.steps, options.threads,
                simulation.time_step_s(), simulation.ContactCount(), simulation.rebuild_count(),
                seconds, rate);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "gonogo-dem-bench: %s\n", error.what());
    return 1;
  }
  return 0;
}
