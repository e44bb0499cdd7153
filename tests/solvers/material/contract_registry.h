// The registry the material contract test runs over: the built-in models of
// solvers/material/registry.cc plus the periodic DE RVE of solvers/dem/rve/
// (its production registration) in a cheap configuration. gonogo_material knows nothing of the DEM library
// (the dependency goes material <- dem/rve); only this test binary links both.
#pragma once

#include "solvers/material/registry.h"

namespace gonogo::material {

// RegisterBuiltinMaterials, then "dem-rve" with the cheap example parameters below.
MaterialRegistry ContractRegistry();

// Registers "dem-rve" through the production RegisterRveMaterial (solvers/dem/rve/rve_soil.h)
// with this test's cheap example parameters: 100 grains (fewer make a cell thinner than three
// neighbour bins), 20 + 30 DE steps per increment, 2 batch threads. The template RVE of a
// parameter set is generated once per process and copied into every model built from that set.
void RegisterCheapRveMaterial(MaterialRegistry& registry);

}  // namespace gonogo::material
