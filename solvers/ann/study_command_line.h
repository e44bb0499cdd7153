// gonogo-ann's command line: what a study runs (ann_main.cc) and the options that set it.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "solvers/tiers/surrogate_training.h"

namespace gonogo::ann {

struct StudyCommandLine {
  std::string soil = "seed000_sand_rve100";
  std::string preset = "ci";
  // The recipe's own defaults (solvers/tiers/surrogate_training.h).
  int steps = tiers::SurrogateRecipe().steps;
  int walks = tiers::SurrogateRecipe().walks;
  int held_out_walks = tiers::SurrogateRecipe().held_out_walks;
  std::vector<double> pressures_kpa;  // empty: the recipe's
  bool unanchored = false;
  bool hybrid = false;               // MlpArchitecture::homogeneous_term
  bool previous_direction = false;   // MlpArchitecture::previous_direction
  double pressure_reference_pa = 0;  // MlpArchitecture::pressure_reference_pa
  double rig_load_n = 0;             // 0: no rig paths
  double rig_diameter_m = 0.5;
  double rig_width_m = 0.2;
  int rig_points = 16;
  int rig_held_out_as = 0;  // > 0: hold out the rig points --rig-points of this many would
  std::vector<double> validate_loads_n;
  // --validate-load-n's runs at each of these multiples of the model's spread threshold.
  std::vector<double> validate_spread_scales = {1.0};
  std::vector<double> validate_pressure_floors_kpa = {0.0};
  std::string register_data_dir;  // non-empty: register each MLP ensemble there
  std::string from_model_dir;     // non-empty: also fine-tune this ensemble on the study's data
  double rest_kpa = 0;            // > 0: only the rest test at this pressure
  int rest_steps = 200;
  double rest_axial_strain = 0;  // the rest test's oedometric compression before resting
  double increment_kpa = 0;      // > 0: only the increment-size study at this pressure
  std::string increment_path = "triaxial";
  std::vector<int> increment_steps = {40, 160, 640};
  double tune_learning_rate = 1e-3;
  std::vector<std::string> architectures = {"64x64"};
  int members = 3;
  int epochs = 300;
  double path_stress_weighting = 0;
  int rollout_steps = 0;  // TrainingOptions::rollout_steps
  double rollout_weight = 1;
  double stress_noise = 0;  // TrainingOptions::stress_noise
  double noise_correction = 1;
  double walk_share = 0;        // > 0: the random walks' share of the loss
  double rig_weight = 1;        // the rig's recorded paths' steps, each weighed as this many
  double walk_persistence = 0;  // the training walks' (ann::LabPathSpec::walk_persistence)
  std::uint64_t training_seed = 1;
  bool record_fabric = false;  // histories record the RVE's coordination and fabric (--out)
  int return_after_steps = 0;  // --validate-load-n: fallen-back points return to the network
  std::vector<unsigned> packing_seeds;  // held-out paths also run on these packings (RVE spread)
  std::vector<std::string> carried;     // internal variables the MLPs carry (implies record_fabric)
  int threads = 2;
  std::string out;
};

// Declares every option of gonogo-ann on `app`, each bound to its field of `line` with its range
// check and its default shown in --help.
void AddStudyOptions(CLI::App& app, StudyCommandLine& line);

}  // namespace gonogo::ann
