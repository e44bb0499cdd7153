#include "contract_registry.h"

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/dem/rve/rve_material.h"

namespace gonogo::material {
namespace {

int IntegerParameter(const ParameterMap& parameters, const std::string& key, int fallback) {
  const auto found = parameters.find(key);
  if (found == parameters.end()) return fallback;
  Require(found->second == static_cast<double>(static_cast<int>(found->second)), "material." + key,
          "must be an integer");
  return static_cast<int>(found->second);
}

dem::rve::RveMaterialParams RveParamsFrom(const ParameterMap& parameters) {
  static const std::vector<std::string> kKnown = {"grain_count",
                                                  "seed",
                                                  "consolidation_pressure_pa",
                                                  "min_steps_per_increment",
                                                  "relax_steps",
                                                  "max_strain_increment",
                                                  "batch_threads"};
  for (const auto& [key, value] : parameters) {
    bool known = false;
    for (const std::string& candidate : kKnown) known = known || candidate == key;
    Require(known, "material." + key, "unknown parameter of dem-rve");
  }
  dem::rve::RveMaterialParams params;
  params.rve.grain_count = IntegerParameter(parameters, "grain_count", params.rve.grain_count);
  params.rve.seed = static_cast<unsigned>(
      IntegerParameter(parameters, "seed", static_cast<int>(params.rve.seed)));
  if (parameters.count("consolidation_pressure_pa") != 0) {
    params.rve.consolidation_pressure_pa = parameters.at("consolidation_pressure_pa");
  }
  params.min_steps_per_increment =
      IntegerParameter(parameters, "min_steps_per_increment", params.min_steps_per_increment);
  params.relax_steps = IntegerParameter(parameters, "relax_steps", params.relax_steps);
  if (parameters.count("max_strain_increment") != 0) {
    params.max_strain_increment = parameters.at("max_strain_increment");
  }
  params.batch_threads = IntegerParameter(parameters, "batch_threads", params.batch_threads);
  params.Validate();
  return params;
}

// Consolidating even a small packing takes many DE steps, so each parameter set is generated
// once and every model built from it starts from a copy (RveMaterial(params, initial)).
std::unique_ptr<ConstitutiveModel> MakeRve(const ParameterMap& parameters) {
  static std::mutex mutex;
  static std::map<ParameterMap, std::string> saved_templates;
  const dem::rve::RveMaterialParams params = RveParamsFrom(parameters);
  const std::lock_guard<std::mutex> lock(mutex);
  auto found = saved_templates.find(parameters);
  if (found == saved_templates.end()) {
    found = saved_templates.emplace(parameters, dem::rve::Rve::Generate(params.rve).Save()).first;
  }
  return std::make_unique<dem::rve::RveMaterial>(params, dem::rve::Rve::Restore(found->second));
}

}  // namespace

void RegisterCheapRveMaterial(MaterialRegistry& registry) {
  registry.Register({"dem-rve",
                     "periodic DE RVE of seed 000's FE-DE model (solvers/dem/rve), one RVE per "
                     "point; cheap test configuration",
                     MakeRve,
                     {{"grain_count", 100},
                      {"seed", 1},
                      {"consolidation_pressure_pa", 100e3},
                      {"min_steps_per_increment", 20},
                      {"relax_steps", 30},
                      {"max_strain_increment", 0.01},
                      {"batch_threads", 2}}});
}

MaterialRegistry ContractRegistry() {
  MaterialRegistry registry;
  RegisterBuiltinMaterials(registry);
  RegisterCheapRveMaterial(registry);
  return registry;
}

}  // namespace gonogo::material
