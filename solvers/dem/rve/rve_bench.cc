// gonogo-rve-bench [--rves R] [--grains N] [--steps S] [--threads T]
//
// RVE-steps per second for a batch of R consolidated RVEs of N grains (default 64 x 500), each
// sheared by the same small increment through the constitutive seam (one RVE per thread, the
// grains of an RVE on one thread), S DE steps per RVE. Prints figures only; not a test.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include "solvers/dem/rve/rve_material.h"
#include "solvers/common/cli_checks.h"

int main(int argc, char** argv) {
  int rves = 64, grains = 500, steps = 2000, threads = 2;
  CLI::App app(
      "RVE-steps per second for a batch of R consolidated RVEs of N grains, each sheared by the "
      "same small increment through the constitutive seam (one RVE per thread, the grains of an "
      "RVE on one thread), S DE steps per RVE. Prints figures only; not a test.",
      "gonogo-rve-bench");
  const CLI::Validator at_least_one = gonogo::cli_checks::AtLeastOne();
  app.add_option("--rves", rves, "RVEs R in the batch")->check(at_least_one)->capture_default_str();
  app.add_option("--grains", grains, "grains N per RVE")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--steps", steps, "DE steps S per RVE")
      ->check(at_least_one)
      ->capture_default_str();
  app.add_option("--threads", threads, "threads T of the batch")
      ->check(at_least_one)
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    using namespace gonogo;
    dem::rve::RveMaterialParams params;
    params.rve.grain_count = grains;
    params.batch_threads = threads;
    // Every step of the timed update is a straining step: no relaxation, a fixed step count.
    params.relax_steps = 0;
    params.min_steps_per_increment = steps;
    const auto generate_start = std::chrono::steady_clock::now();
    const dem::rve::RveMaterial material(params);
    const double generate_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - generate_start).count();
    std::vector<std::unique_ptr<material::MaterialState>> states;
    std::vector<material::PointIncrement> increments(rves);
    for (int r = 0; r < rves; ++r) states.push_back(material.InitialState());
    for (int r = 0; r < rves; ++r) {
      increments[r].committed = states[r].get();
      // A small simple shear, slow enough to stay under the rate cap in `steps` steps.
      increments[r].displacement_gradient_increment(0, 2) = 1e-5;
    }
    const auto start = std::chrono::steady_clock::now();
    const std::vector<material::PointResponse> responses = material.Update(increments, true);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    int failed = 0;
    for (const auto& response : responses) failed += response.status != material::UpdateStatus::kOk;
    std::printf("rves,grains,steps_per_rve,threads,generate_s,wall_s,rve_steps_per_s,"
                "particle_steps_per_s,failed\n");
    std::printf("%d,%d,%d,%d,%.2f,%.3f,%.4e,%.4e,%d\n", rves, grains, steps, threads, generate_s,
                seconds, rves * static_cast<double>(steps) / seconds,
                rves * static_cast<double>(steps) * grains / seconds, failed);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "gonogo-rve-bench: %s\n", error.what());
    return 1;
  }
  return 0;
}
