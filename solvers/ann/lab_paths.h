// Laboratory strain paths on one material point (MaterialPointDriver), recorded as
// StrainHistory: the training data of a surrogate (issue "FE-ANN tier"). Compression is positive
// in these specifications (a confining pressure of 10e3 Pa); the histories keep the seam's
// tension-positive stresses.
//
// Every path first brings the point to the isotropic stress `pressure_pa` (stress-controlled
// steps from whatever stress the model starts at: zero for a continuum, the preparation pressure
// for an RVE) and records those steps too, then:
//   isotropic      mean stress up by strain: volumetric strain max_strain in `steps` steps, then
//                  back by half of it (unloading);
//   triaxial       drained: axial (zz) strain max_strain in compression, lateral stresses held at
//                  pressure_pa, no shear;
//   simple-shear   u_x = gamma z (dH_xz = gamma per step, strain and spin) to gamma = max_strain,
//                  sigma_zz held at pressure_pa, the other strains zero (a shear ring's band);
//   unload-reload  triaxial to max_strain / 2, axial unloading by max_strain / 4, reloading to
//                  max_strain (the steps split 2 : 1 : 3);
//   random-walk    every strain component a random walk (steps of walk_step_strain in norm,
//                  direction uniform on the 6-sphere, seeded), reflected at +- max_strain per
//                  component from the settled state, with a compressive drift of a quarter of a
//                  step per step in the volumetric strain, so that a cohesionless point keeps
//                  contact. The envelope of the inputs is what these bounds state. With
//                  walk_persistence rho > 0 the directions are correlated from step to step: the
//                  direction is that of g_k = rho g_(k-1) + sqrt(1 - rho^2) xi_k (xi_k standard
//                  normal; an AR(1) process of which only the direction is used), a walk that
//                  loads on for about 1 / (1 - rho) steps before it turns, as a point under a
//                  rolling wheel does; rho = 0 is the uncorrelated walk, draw for draw.
// A step the model refuses (or a stress it cannot hold) ends the history there with
// stopped_reason set, not an exception: a random walk may wander where a point fails.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/ann/point_driver.h"
#include "solvers/ann/strain_history.h"

namespace gonogo::ann {

enum class LabPath { kIsotropic, kTriaxial, kSimpleShear, kUnloadReload, kRandomWalk };

// "isotropic", "triaxial", "simple-shear", "unload-reload", "random-walk"; ParseLabPath throws
// InputError(field, ...) listing the names for any other.
std::string LabPathName(LabPath path);
LabPath ParseLabPath(const std::string& name, const std::string& field);
std::vector<LabPath> AllLabPaths();

struct LabPathSpec {
  LabPath path = LabPath::kTriaxial;
  double pressure_pa = 10e3;    // confining / normal / starting mean stress, compression positive
  double max_strain = 0.05;     // axial, volumetric or shear strain reached (see above)
  int steps = 50;               // after settling
  int settle_steps = 5;         // isotropic stress-controlled steps to pressure_pa
  double walk_step_strain = 1e-3;  // random walk: norm of one step's strain increment
  double walk_persistence = 0;     // random walk: rho in [0, 1), the steps' directions' correlation
  std::uint64_t seed = 1;          // random walk
  // Throws InputError naming field_prefix + the field: pressure > 0, max_strain in (0, 0.5],
  // steps in [1, 100000], settle_steps in [1, 1000], walk step in (0, max_strain],
  // walk_persistence in [0, 1).
  void Validate(const std::string& field_prefix) const;
};

StrainHistory RunLabPath(const material::ConstitutiveModel& model, const LabPathSpec& spec,
                         const DriverOptions& options = {},
                         const InternalVariables& internal = {});

}  // namespace gonogo::ann
