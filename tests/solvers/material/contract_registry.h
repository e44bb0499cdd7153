// The registry the material contract test runs over: the built-in models of
// solvers/material/registry.cc plus, registered here on the test side, the periodic DE RVE of
// solvers/dem/rve/ in a cheap configuration. gonogo_material knows nothing of the DEM library
// (the dependency goes material <- dem/rve); only this test binary links both.
#pragma once

#include "solvers/material/registry.h"

namespace gonogo::material {

// RegisterBuiltinMaterials, then "dem-rve" with the cheap example parameters below.
MaterialRegistry ContractRegistry();

// Registers "dem-rve": dem::rve::RveMaterial built from a flat map (grain_count, seed,
// consolidation_pressure_pa, min_steps_per_increment, relax_steps, max_strain_increment,
// batch_threads; every other field keeps its RveParams default). Its example parameters are a
// cheap configuration: 72 grains (the fewest for which a consolidated cell stays three
// neighbour bins wide on every axis) and short relaxation. The template RVE of a parameter set
// is generated once per process and copied into every model built from that set.
void RegisterCheapRveMaterial(MaterialRegistry& registry);

}  // namespace gonogo::material
