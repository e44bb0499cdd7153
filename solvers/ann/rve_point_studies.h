// The soil's RVE alone as one material point, for what a network trained on laboratory paths
// would have to follow at an FE point (gonogo-ann --rest-kpa, --increment-kpa; README.md, "Paths
// recorded in the rig"). Each prints its table (CSV, '#' lines of context) to stdout.
#pragma once

#include <string>
#include <vector>

#include "solvers/ann/lab_paths.h"
#include "solvers/dem/rve/rve_material.h"

namespace gonogo::ann {

struct RestTestOptions {
  double pressure_kpa = 5;  // settled isotropically at this mean compression
  // Then compressed along z by this strain with the lateral strains held (oedometric, in 20
  // increments: a deviatoric load like a point's under a wheel); 0: none.
  double axial_strain = 0;
  int zero_increments = 200;
};

// The RVE settled and loaded as `options` says, then held still: zero increments, each committed.
// Prints the mean stress p and the deviatoric q (von Mises) every tenth zero increment and their
// change from the first, per cent (a surrogate anchored at rest answers no change at all).
// `label` names the soil and preset in the first line. Throws NumericalError where the RVE fails.
void RunRestTest(const dem::rve::RveMaterial& rve, const RestTestOptions& options,
                 const std::string& label);

struct IncrementStudyOptions {
  double pressure_kpa = 10;
  LabPath path = LabPath::kTriaxial;  // to 5 % axial strain; a simple shear to 10 % shear
  std::vector<int> step_counts = {40, 160, 640};
};

// One laboratory path at `options.pressure_kpa`, taken in each of `options.step_counts` steps. A
// quasi-static packing answers the same whatever the step; the RVE spreads each increment over at
// least min_steps_per_increment DE steps and relaxes it for relax_steps, so a path of many small
// increments (an FE point's) gets more DE steps per unit of strain than one of few large ones (a
// laboratory path's). Prints p and q at fractions of the path, per step count, and names a run
// that stopped early. Throws InputError naming --increment-steps for a step count out of [1,
// 100000].
void RunIncrementStudy(const dem::rve::RveMaterial& rve, const IncrementStudyOptions& options,
                       const std::string& label);

}  // namespace gonogo::ann
