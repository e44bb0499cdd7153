#include "solvers/ann/study_command_line.h"

namespace gonogo::ann {

void AddStudyOptions(CLI::App& app, StudyCommandLine& line) {
  app.add_option("--soil", line.soil, "dem-hertz-mindlin soil of the catalogue")
      ->capture_default_str();
  app.add_option("--preset", line.preset, "fe-de preset whose RVE numerics the paths use")
      ->capture_default_str();
  app.add_option("--steps", line.steps, "steps per path after settling")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--held-out-walks", line.held_out_walks,
                 "random walks in the held-out set (seeds 1001, 1002, ...)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--walks", line.walks, "random walks in the training set")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("--pressures-kpa", line.pressures_kpa,
                 "confining pressures of the training paths, kPa, increasing (default: "
                 "2.5 5 10 20 40 80)");
  app.add_option("--architecture", line.architectures,
                 "MLP hidden widths joined by x (64x64; the seed's 600x600x600x600x600x600x600), "
                 "or a GRU and its width (gru32; one network, not an ensemble)")
      ->capture_default_str();
  app.add_flag("--hybrid", line.hybrid,
               "MLPs with a second network's term homogeneous in the strain increment beside the "
               "anchored one (MlpArchitecture::homogeneous_term)");
  app.add_flag("--previous-direction", line.previous_direction,
               "MLPs that also see the previous step's increment direction "
               "(MlpArchitecture::previous_direction)");
  app.add_flag("--unanchored", line.unanchored,
               "MLPs without the at-rest anchor (d_sigma(0) = 0; stress_surrogate.h)");
  app.add_option("--pressure-scaled", line.pressure_reference_pa,
                 "MLPs that see the stress relative to s = max(p, 0) + this reference pressure "
                 "(Pa) and answer d_sigma / s (stress_surrogate.h); 0: unscaled")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--rig-load-n", line.rig_load_n,
                 "record the paths of an fe-de rig run of the preset at this wheel load (N) and "
                 "train and check on them too (seed 000's step 2); 0: none")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--rig-diameter-m", line.rig_diameter_m, "the rig wheel's diameter, m")
      ->check(CLI::Range(0.05, 5.0))
      ->capture_default_str();
  app.add_option("--rig-width-m", line.rig_width_m, "the rig wheel's width, m")
      ->check(CLI::Range(0.01, 2.0))
      ->capture_default_str();
  app.add_option("--rig-points", line.rig_points,
                 "recorded points in the training set (half as many others held out)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--rig-held-out-as", line.rig_held_out_as,
                 "hold out the recorded points that --rig-points of this many holds out, and "
                 "spread the training points over the others: recipes with more or fewer training "
                 "points checked on the same held-out paths (default: --rig-points itself)")
      ->check(CLI::Range(1, 100000));
  app.add_flag("--record-fabric", line.record_fabric,
               "the histories --out writes also record, per step, the RVE's coordination number, "
               "solid fraction and contact fabric (fabric_xx ... fabric_xy; trace 1): for "
               "studies of what a network might carry (solvers/ann/studies/fabric.py)");
  app.add_option("--carry", line.carried,
                 "internal variables of the RVE the MLPs carry as further inputs and outputs "
                 "(coordination_number, solid_fraction; stress_surrogate.h); the histories record "
                 "them")
      ->type_name("NAME");
  app.add_option("--return-after-steps", line.return_after_steps,
                 "--validate-load-n's fe-ann runs: a fallen-back point returns to the network "
                 "after this many FE steps in a row its ensemble would not have flagged (0: never)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--packing-seeds", line.packing_seeds,
                 "also run the held-out paths on the soil's RVE packed from these seeds (the "
                 "study's packing is the preset's, seed 1; a held-out rig path replayed from its "
                 "initial stress) and print their stresses' difference "
                 "from the study's packing's, measured as a replay's error: the RVE's own spread, "
                 "the floor under a held-out error; with --register, in the model's record")
      ->check(CLI::PositiveNumber);
  app.add_option("--validate-load-n", line.validate_loads_n,
                 "run each MLP ensemble as the fe-ann tier on the rig at these loads (N) against "
                 "fe-de");
  app.add_option("--validate-spread-scales", line.validate_spread_scales,
                 "--validate-load-n's runs once at each of these multiples of the model's spread "
                 "threshold (below 1: more points fall back to the RVE)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--validate-pressure-floors-kpa", line.validate_pressure_floors_kpa,
                 "--validate-load-n's runs (and the held-out rig paths' guarded replays) once at "
                 "each of these pressure floors, kPa: a point whose mean compression is below "
                 "the floor falls back to the RVE (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--register", line.register_data_dir,
                 "register each MLP ensemble with its provenance in this gonogo-server data "
                 "directory (DATA_DIR/models), where the fe-ann tier finds it")
      ->type_name("DATA_DIR");
  app.add_option("--from", line.from_model_dir,
                 "transfer learning: also fine-tune this ensemble (a directory: DATA_DIR/models/ID "
                 "or --out's) on the study's data, beside the architectures trained from scratch")
      ->type_name("MODEL_DIR");
  app.add_option("--tune-learning-rate", line.tune_learning_rate,
                 "Adam's learning rate when fine-tuning")
      ->check(CLI::Range(1e-8, 0.5))
      ->capture_default_str();
  app.add_option("--rest-kpa", line.rest_kpa,
                 "only the rest test: the RVE settled at this pressure (kPa), then --rest-steps "
                 "zero increments; prints its stress as it drifts")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--rest-axial-strain", line.rest_axial_strain,
                 "the rest test's compression along z (lateral strains held) before the zero "
                 "increments: a deviatoric load")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  app.add_option("--rest-steps", line.rest_steps, "zero increments of the rest test")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--increment-kpa", line.increment_kpa,
                 "only the increment-size study: --increment-path at this pressure (kPa) taken "
                 "in each of --increment-steps steps; prints p and q along each")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--increment-path", line.increment_path,
                 "the increment study's laboratory path (triaxial, simple-shear, ...)")
      ->capture_default_str();
  app.add_option("--increment-steps", line.increment_steps, "the increment study's step counts")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--members", line.members, "ensemble members")
      ->check(CLI::Range(3, 64))
      ->capture_default_str();
  app.add_option("--epochs", line.epochs, "training epochs")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--path-stress-weighting", line.path_stress_weighting,
                 "each training step's squared error weighed by its path's mean |sigma| to the "
                 "power -2x: 0 every step alike, 1 relative to the path's stress (MLPs)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--rollout-steps", line.rollout_steps,
                 "a rollout term in the loss: windows of this many steps replayed on the "
                 "network's own stresses, their error relative to the path's stress (MLPs; 0: "
                 "none)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--rollout-weight", line.rollout_weight, "the rollout term's weight in the loss")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--stress-noise", line.stress_noise,
                 "training noise on the stress before each step, its standard deviation a "
                 "fraction of the path's mean |sigma| (MLPs; 0: none)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--noise-correction", line.noise_correction,
                 "the share of the noise each step's target takes back: 1 ends the step on the "
                 "recorded stress, 0 as far off as it began")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--walk-share", line.walk_share,
                 "the random walks' share of the training loss (their steps weighed to give it); "
                 "0: their share of the steps")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  app.add_option("--rig-weight", line.rig_weight,
                 "each step of the rig's recorded training paths weighs this many laboratory "
                 "steps in the loss (--rig-load-n; after --walk-share, which counts them as 1)")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  app.add_option("--walk-persistence", line.walk_persistence,
                 "the training walks' correlation of one step's direction with the last's (0: "
                 "drawn afresh; 0.9: loading on for about 10 steps); held-out walks stay at 0")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str();
  app.add_option("--training-seed", line.training_seed,
                 "the first member's seed of weights and batch order (member k: seed + k)")
      ->capture_default_str();
  app.add_option("--threads", line.threads, "OpenMP threads generating the paths")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--out", line.out, "directory for the histories (.npy) and the ensembles");
}

}  // namespace gonogo::ann
