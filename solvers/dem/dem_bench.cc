// gonogo-dem-bench --grains N --steps S [--threads T] [--seed K]
//                  [--trace M] [--friction MU] [--rolling-limit ETA] [--tangential-damping 0|1]
//                  [--write-liggghts DIR [--trace-every M]]
//
// A periodic cubic packing of N polydisperse grains with the seed 000 parameters (E 1.5 GPa,
// nu 0.293, mu 0.452, beta 2.25, eta 0.99, radius 0.87 mm +-5 %, density 2650 kg/m3, e 0.5) on a
// lattice of spacing 2 r_mean, so about half the neighbours start overlapping, run for S steps at
// 0.2 of the Rayleigh step. Prints particle-steps per second and the peak resident memory
// (figures only; not a test).
//
// --trace M: no timing; from step 0 to S, every M steps, print kinetic energy (translational,
// rotational), contact count, and position and velocity of grains 1 and N/2 + 1 (LIGGGHTS ids).
// --write-liggghts DIR: write the same packing, law, box, skin and time step for LIGGGHTS 3.8 as
// DIR/data.bench, DIR/in.bench (10 warm-up steps, then S timed steps: the second "Loop time") and
// DIR/in.trace (the --trace output of LIGGGHTS), then exit. --friction, --rolling-limit (0: no
// rolling resistance) and --tangential-damping 0 change the law, to check one part at a time.
// See solvers/dem/README.md, "Benchmark".
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "solvers/dem/simulation.h"
#include "solvers/common/cli_checks.h"

namespace {

using gonogo::dem::Vec3;

struct Options {
  int grains = 5000;
  int steps = 1000;
  int threads = 1;
  unsigned seed = 1;
  int trace_every = 0;  // 0: timed run
  std::string liggghts_dir;
  int liggghts_trace_every = 10;
  double friction = -1.0;       // < 0: seed 000 value
  double rolling_limit = -1.0;  // < 0: seed 000 value; 0 switches rolling resistance off
  bool tangential_damping = true;
};

constexpr int kWarmupSteps = 10;

// A count of at least 1, and a finite number >= 0 (CLI11's own NonNegativeNumber takes "nan").
const CLI::Validator kAtLeastOne = gonogo::cli_checks::AtLeastOne();
const CLI::Validator kNonNegative = gonogo::cli_checks::FiniteNumber(0.0);

// Returns the options, or the exit code when the program should stop here: 0 after --help, 2 on a
// usage error (unknown or mistyped option, value out of range), with the message on stderr.
std::optional<int> Parse(int argc, char** argv, Options* options) {
  CLI::App app(
      "A periodic cubic packing of N polydisperse grains with the seed 000 parameters, run for S "
      "steps at 0.2 of the Rayleigh step; prints particle-steps per second and the peak resident "
      "memory (figures only; not a test). See solvers/dem/README.md, \"Benchmark\".",
      "gonogo-dem-bench");
  app.add_option("--grains", options->grains, "grains N")
      ->check(kAtLeastOne)
      ->capture_default_str();
  app.add_option("--steps", options->steps, "timed steps S")
      ->check(kAtLeastOne)
      ->capture_default_str();
  app.add_option("--threads", options->threads, "OpenMP threads T")
      ->check(kAtLeastOne)
      ->capture_default_str();
  app.add_option("--seed", options->seed, "random seed K of the packing")->capture_default_str();
  app.add_option("--trace", options->trace_every,
                 "no timing; from step 0 to S, every M steps, print kinetic energy (translational, "
                 "rotational), contact count, and position and velocity of grains 1 and N/2 + 1 "
                 "(LIGGGHTS ids)")
      ->check(kAtLeastOne);
  CLI::Option* write = app.add_option(
      "--write-liggghts", options->liggghts_dir,
      "write the same packing, law, box, skin and time step for LIGGGHTS 3.8 as DIR/data.bench, "
      "DIR/in.bench (10 warm-up steps, then S timed steps: the second \"Loop time\") and "
      "DIR/in.trace (the --trace output of LIGGGHTS), then exit");
  app.add_option("--trace-every", options->liggghts_trace_every,
                 "trace interval M of the DIR/in.trace written by --write-liggghts")
      ->check(kAtLeastOne)
      ->needs(write)
      ->capture_default_str();
  app.add_option("--friction", options->friction,
                 "sliding friction coefficient MU (default: seed 000's)")
      ->check(kNonNegative);
  app.add_option("--rolling-limit", options->rolling_limit,
                 "rolling resistance limit ETA (default: seed 000's; 0: no rolling resistance)")
      ->check(kNonNegative);
  app.add_option_function<int>(
         "--tangential-damping",
         [options](const int& on) { options->tangential_damping = on == 1; },
         "1: the tangential dashpot of the seed 000 law; 0: off (LIGGGHTS `tangential_damping "
         "off`)")
      ->check(CLI::IsMember({0, 1}))
      ->default_str("1");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return std::nullopt;
}

// Peak resident set size of this process (VmHWM), in KiB; -1 if unknown.
long PeakRssKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return -1;
}

struct Setup {
  gonogo::dem::SimulationParams params;
  gonogo::dem::Particles grains;
};

Setup MakePacking(const Options& options) {
  Setup setup;
  gonogo::dem::SimulationParams& params = setup.params;
  params.material.restitution = 0.5;
  if (options.friction >= 0.0) params.material.friction = options.friction;
  if (options.rolling_limit >= 0.0) params.material.rolling_limit = options.rolling_limit;
  params.threads = options.threads;
  const double mean_radius_m = 0.87e-3;
  const int side = static_cast<int>(std::ceil(std::cbrt(static_cast<double>(options.grains))));
  const double spacing_m = 2.0 * mean_radius_m;
  params.box.lo_m = Vec3::Zero();
  params.box.hi_m = Vec3::Constant(side * spacing_m);

  std::mt19937_64 random(options.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int g = 0; g < options.grains; ++g) {
    const Vec3 site((g % side + 0.5) * spacing_m, ((g / side) % side + 0.5) * spacing_m,
                    (g / (side * side) + 0.5) * spacing_m);
    const Vec3 velocity(0.05 * unit(random), 0.05 * unit(random), 0.05 * unit(random));
    setup.grains.Add(site, velocity, mean_radius_m * (1.0 + 0.05 * unit(random)),
                     params.material.density_kg_m3);
  }
  return setup;
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

// The input shared by in.bench and in.trace: same box, grains, law, skin and step as the engine.
std::string LiggghtsSetup(const Setup& setup, bool tangential_damping, double dt_s, double skin_m) {
  const gonogo::dem::MaterialParams& m = setup.params.material;
  std::ostringstream in;
  in.precision(17);
  in << "# Written by gonogo-dem-bench --write-liggghts (solvers/dem/README.md, \"Benchmark\").\n"
     << "# Hertz, Mindlin history with Coulomb cap, elastic-plastic rolling (epsd3, no\n"
     << "# rolling dashpot), Tsuji damping from e; limitForce off (default).\n"
     << "atom_style sphere\n"
     << "atom_modify map array\n"
     << "boundary p p p\n"
     << "newton off\n"
     << "communicate single vel yes\n"
     << "units si\n"
     << "hard_particles yes\n"
     << "read_data data.bench\n"
     << "neighbor " << skin_m << " bin\n"
     << "neigh_modify delay 0 every 1 check yes\n"
     << "fix m1 all property/global youngsModulus peratomtype " << m.youngs_modulus_pa << "\n"
     << "fix m2 all property/global poissonsRatio peratomtype " << m.poisson_ratio << "\n"
     << "fix m3 all property/global coefficientRestitution peratomtypepair 1 " << m.restitution
     << "\n"
     << "fix m4 all property/global coefficientFriction peratomtypepair 1 " << m.friction << "\n";
  if (m.rolling_limit > 0.0 && m.rolling_stiffness > 0.0) {
    in << "fix m5 all property/global coefficientRollingFriction peratomtypepair 1 "
       << m.rolling_limit << "\n"
       << "fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 0.0\n"
       << "# epsd3: k_r = rollingStiffness k_n rmu^2 r_e^2, k_n = 4/3 E* sqrt(r_e d) (secant);\n"
       << "# engine: k_r = beta k_n eta^2 r_e^2, k_n = 2 E* sqrt(r_e d): 1.5 beta.\n"
       << "fix m7 all property/global rollingStiffness scalar " << 1.5 * m.rolling_stiffness << "\n"
       << "pair_style gran model hertz tangential history rolling_friction epsd3";
  } else {
    in << "pair_style gran model hertz tangential history rolling_friction off";
  }
  in << (tangential_damping ? "\n" : " tangential_damping off\n");
  in << "pair_coeff * *\n"
     << "timestep " << dt_s << "\n"
     << "fix integr all nve/sphere\n";
  return in.str();
}

void WriteLiggghts(const Options& options, const Setup& setup) {
  const std::string& dir = options.liggghts_dir;
  ::mkdir(dir.c_str(), 0755);  // an existing folder is fine; a failure shows when writing
  const gonogo::dem::Particles& g = setup.grains;
  // The step the engine takes for this packing (time_step_s 0: safety x Rayleigh step).
  const double dt_s = gonogo::dem::Simulation(setup.params, setup.grains).time_step_s();
  const double max_radius_m = *std::max_element(g.radius_m.begin(), g.radius_m.end());
  const double skin_m = setup.params.skin_fraction * max_radius_m;
  const Vec3 lo = setup.params.box.lo_m;
  const Vec3 hi = setup.params.box.hi_m;

  std::ostringstream data;
  data.precision(17);
  data << "LIGGGHTS data file written by gonogo-dem-bench (" << g.size() << " grains)\n\n"
       << g.size() << " atoms\n1 atom types\n\n"
       << lo.x() << " " << hi.x() << " xlo xhi\n"
       << lo.y() << " " << hi.y() << " ylo yhi\n"
       << lo.z() << " " << hi.z() << " zlo zhi\n\nAtoms\n\n";
  for (std::size_t p = 0; p < g.size(); ++p) {
    // atom_style sphere: id type diameter density x y z
    data << p + 1 << " 1 " << 2.0 * g.radius_m[p] << " " << setup.params.material.density_kg_m3
         << " " << g.position_m[p].x() << " " << g.position_m[p].y() << " " << g.position_m[p].z()
         << "\n";
  }
  data << "\nVelocities\n\n";
  for (std::size_t p = 0; p < g.size(); ++p) {
    const Vec3& v = g.velocity_m_s[p];
    const Vec3& w = g.angular_velocity_rad_s[p];
    data << p + 1 << " " << v.x() << " " << v.y() << " " << v.z() << " " << w.x() << " " << w.y()
         << " " << w.z() << "\n";
  }
  WriteFile(dir + "/data.bench", data.str());

  const std::string common = LiggghtsSetup(setup, options.tangential_damping, dt_s, skin_m);
  std::ostringstream bench;
  bench << common << "thermo 1000000000\n"
        << "run " << kWarmupSteps << "\n"
        << "run " << options.steps << "\n";
  WriteFile(dir + "/in.bench", bench.str());

  const int second = static_cast<int>(g.size() / 2) + 1;
  std::ostringstream trace;
  trace << common << "compute ket all ke\n"
        << "compute ker all erotate/sphere\n"
        << "compute cn all contact/atom\n"
        << "compute cnsum all reduce sum c_cn\n"
        << "variable contacts equal c_cnsum/2\n";
  for (const int id : {1, second}) {
    for (const char* q : {"x", "y", "z", "vx", "vy", "vz"}) {
      trace << "variable " << q << id << " equal " << q << "[" << id << "]\n";
    }
  }
  trace << "thermo_style custom step c_ket c_ker v_contacts";
  for (const int id : {1, second}) {
    for (const char* q : {"x", "y", "z", "vx", "vy", "vz"}) trace << " v_" << q << id;
  }
  trace << "\nthermo_modify norm no format float %.10e\n"
        << "thermo " << options.liggghts_trace_every << "\n"
        << "run " << options.steps << "\n";
  WriteFile(dir + "/in.trace", trace.str());
  std::printf("wrote %s/data.bench, in.bench, in.trace (%zu grains, dt %.6e s, skin %.6e m)\n",
              dir.c_str(), g.size(), dt_s, skin_m);
}

void PrintTraceLine(const gonogo::dem::Simulation& sim, int step) {
  const gonogo::dem::Particles& g = sim.particles();
  double translational_j = 0.0;
  double rotational_j = 0.0;
  for (std::size_t p = 0; p < g.size(); ++p) {
    translational_j += 0.5 * g.mass_kg[p] * g.velocity_m_s[p].squaredNorm();
    rotational_j += 0.5 * g.angular_velocity_rad_s[p].squaredNorm() / g.inverse_inertia_1_kg_m2[p];
  }
  std::printf("%d,%.10e,%.10e,%d", step, translational_j, rotational_j, sim.ContactCount());
  const Vec3 edges = sim.cell().edges_m.diagonal();
  for (const std::size_t p : {std::size_t{0}, g.size() / 2}) {
    // Positions wrapped into [0, L) as LIGGGHTS reports them.
    const Vec3 x = sim.UnwrappedPositionM(static_cast<int>(p));
    for (int d = 0; d < 3; ++d) {
      std::printf(",%.10e", x[d] - std::floor(x[d] / edges[d]) * edges[d]);
    }
    for (int d = 0; d < 3; ++d) std::printf(",%.10e", g.velocity_m_s[p][d]);
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (const std::optional<int> exit_code = Parse(argc, argv, &options)) return *exit_code;
  try {
    Setup setup = MakePacking(options);
    if (!options.liggghts_dir.empty()) {
      WriteLiggghts(options, setup);
      return 0;
    }
    const int grains = options.grains;
    gonogo::dem::ContactModel model =
        gonogo::dem::ContactModel::HertzMindlin(setup.params.material);
    if (!options.tangential_damping) {
      // The seed 000 law with the tangential dashpot off (LIGGGHTS `tangential_damping off`).
      const gonogo::dem::MaterialParams& m = setup.params.material;
      std::shared_ptr<const gonogo::dem::RollingModel> rolling;
      if (m.rolling_stiffness > 0.0 && m.rolling_limit > 0.0) {
        rolling = std::make_shared<gonogo::dem::ElasticPlasticRolling>(m.rolling_stiffness,
                                                                       m.rolling_limit);
      } else {
        rolling = std::make_shared<gonogo::dem::NoRolling>();
      }
      model = gonogo::dem::ContactModel(
          std::make_shared<gonogo::dem::HertzNormal>(m),
          std::make_shared<gonogo::dem::RestitutionDamping>(m.restitution, false),
          std::make_shared<gonogo::dem::MindlinTangential>(m), rolling);
    }
    gonogo::dem::Simulation simulation(setup.params, std::move(setup.grains), std::move(model));

    if (options.trace_every > 0) {
      const int second = grains / 2 + 1;
      std::printf(
          "step,ke_translational_j,ke_rotational_j,contacts,x%d,y%d,z%d,vx%d,vy%d,vz%d,"
          "x%d,y%d,z%d,vx%d,vy%d,vz%d\n",
          1, 1, 1, 1, 1, 1, second, second, second, second, second, second);
      PrintTraceLine(simulation, 0);  // contacts are 0 until the first force evaluation
      for (int step = 1; step <= options.steps; ++step) {
        simulation.Step();
        if (step % options.trace_every == 0) PrintTraceLine(simulation, step);
      }
      return 0;
    }

    simulation.Run(kWarmupSteps);  // first neighbour build and force evaluation outside the timing
    const auto start = std::chrono::steady_clock::now();
    simulation.Run(options.steps);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double rate = static_cast<double>(grains) * options.steps / seconds;
    std::printf(
        "grains,steps,threads,dt_s,contacts,rebuilds,wall_s,particle_steps_per_s,peak_rss_kib\n");
    std::printf("%d,%d,%d,%.3e,%d,%d,%.3f,%.4e,%ld\n", grains, options.steps, options.threads,
                simulation.time_step_s(), simulation.ContactCount(), simulation.rebuild_count(),
                seconds, rate, PeakRssKiB());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "gonogo-dem-bench: %s\n", error.what());
    return 1;
  }
  return 0;
}
