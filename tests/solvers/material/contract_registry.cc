#include "contract_registry.h"

#include <utility>

#include "solvers/dem/rve/rve_soil.h"

namespace gonogo::material {

// The production registration (dem::rve::RegisterRveMaterial: a dem-hertz-mindlin soil set plus
// DE numerics; templates generated once per parameter set and process), with the contract's own
// example parameters pinned here, since contract_test.cc's tolerances for "dem-rve" were measured
// on exactly this configuration: 100 grains of seed 000's law (every soil parameter at its
// default), seed 1, consolidated to 100 kPa, 20 + 30 DE steps per increment, 2 batch threads.
void RegisterCheapRveMaterial(MaterialRegistry& registry) {
  MaterialRegistry production;
  dem::rve::RegisterRveMaterial(production);
  ModelEntry entry = production.Get("dem-rve");
  entry.example_parameters = {{"grains_per_rve", 100},
                              {"seed", 1},
                              {"consolidation_pressure_pa", 100e3},
                              {"min_steps_per_increment", 20},
                              {"relax_steps", 30},
                              {"max_strain_increment", 0.01},
                              {"batch_threads", 2}};
  registry.Register(std::move(entry));
}

MaterialRegistry ContractRegistry() {
  MaterialRegistry registry;
  RegisterBuiltinMaterials(registry);
  RegisterCheapRveMaterial(registry);
  return registry;
}

}  // namespace gonogo::material
