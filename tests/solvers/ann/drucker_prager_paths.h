// The soil the surrogate tests learn (fast, with closed-form behaviour) and its laboratory paths:
// a Drucker-Prager point (E 20 MPa, nu 0.3, c 1 kPa, phi 35 deg, psi 5 deg), 60 steps a path.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "solvers/ann/lab_paths.h"
#include "solvers/material/drucker_prager.h"

namespace gonogo::ann::testing {

inline const material::DruckerPrager& Soil() {
  static const material::DruckerPrager* soil = [] {
    material::DruckerPragerParams params;
    params.young_pa = 20e6;
    params.poisson = 0.3;
    params.cohesion_pa = 1e3;
    params.friction_angle_deg = 35;
    params.dilation_angle_deg = 5;
    return new material::DruckerPrager(params);
  }();
  return *soil;
}

// What a network may carry of a Drucker-Prager point: its equivalent plastic strain (an
// invariant that grows past yield).
inline InternalVariables PlasticStrain() {
  InternalVariables internal;
  internal.names = {"equivalent_plastic_strain"};
  internal.read = [](const material::MaterialState& state) {
    return std::vector<double>{
        static_cast<const material::DruckerPragerState&>(state).equivalent_plastic_strain()};
  };
  return internal;
}

// A 60-step laboratory path on `model` (walk steps of 5e-4), recording `internal`.
inline StrainHistory PathOn(const material::ConstitutiveModel& model, LabPath path,
                            double pressure_pa, double max_strain, std::uint64_t seed = 1,
                            const InternalVariables& internal = {}) {
  LabPathSpec spec;
  spec.path = path;
  spec.pressure_pa = pressure_pa;
  spec.max_strain = max_strain;
  spec.steps = 60;
  spec.seed = seed;
  spec.walk_step_strain = 5e-4;
  StrainHistory history = RunLabPath(model, spec, {}, internal);
  EXPECT_TRUE(history.stopped_reason.empty()) << history.stopped_reason;
  return history;
}

inline StrainHistory Path(LabPath path, double pressure_pa, double max_strain,
                          std::uint64_t seed = 1, const InternalVariables& internal = {}) {
  return PathOn(Soil(), path, pressure_pa, max_strain, seed, internal);
}

// Triaxials and simple shears at 10-80 kPa, unload-reload and isotropic paths, 24 random walks;
// each recording `internal`.
inline std::vector<StrainHistory> TrainingPaths(const InternalVariables& internal = {}) {
  std::vector<StrainHistory> paths;
  for (double p : {10e3, 20e3, 40e3, 80e3}) {
    paths.push_back(Path(LabPath::kTriaxial, p, 0.02, 1, internal));
  }
  for (double p : {10e3, 40e3, 80e3}) {
    paths.push_back(Path(LabPath::kSimpleShear, p, 0.04, 1, internal));
  }
  for (double p : {10e3, 40e3}) paths.push_back(Path(LabPath::kUnloadReload, p, 0.02, 1, internal));
  for (double p : {10e3, 80e3}) paths.push_back(Path(LabPath::kIsotropic, p, 0.004, 1, internal));
  for (std::uint64_t seed = 1; seed <= 24; ++seed) {
    paths.push_back(Path(LabPath::kRandomWalk, 10e3 * (1 + seed % 8), 0.004, seed, internal));
  }
  return paths;
}

}  // namespace gonogo::ann::testing
