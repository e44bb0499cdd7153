// The constitutive models a solver can build by name from a flat parameter map (what a request or
// a soil table carries). A model is added by writing its class and one Register call in
// RegisterBuiltinMaterials (registry.cc); nothing registers itself statically.
//
//   MaterialRegistry registry;
//   RegisterBuiltinMaterials(registry);
//   std::unique_ptr<ConstitutiveModel> model = registry.Make("drucker-prager", parameters);
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"

namespace gonogo::material {

// Parameter name (SI unit in the name: "young_pa", "friction_angle_deg") -> value.
using ParameterMap = std::map<std::string, double>;

struct ModelEntry {
  std::string name;         // what ConstitutiveModel::Name() returns
  std::string description;  // one line
  // Builds the model. Throws gonogo::InputError naming "material.<key>" for a missing, unknown or
  // invalid parameter.
  std::function<std::unique_ptr<ConstitutiveModel>(const ParameterMap&)> make;
  ParameterMap example_parameters;  // a valid set, for documentation and the contract test
};

class MaterialRegistry {
 public:
  // Throws gonogo::InputError("material", ...) for an empty or duplicate name or no factory.
  void Register(ModelEntry entry);
  // Throws gonogo::InputError("material", "unknown material model 'x'; known: a, b").
  const ModelEntry& Get(const std::string& name) const;
  // Get(name).make(parameters).
  std::unique_ptr<ConstitutiveModel> Make(const std::string& name,
                                          const ParameterMap& parameters) const;
  std::vector<std::string> Names() const;  // sorted

 private:
  std::map<std::string, ModelEntry> entries_;
};

// Registers "linear-elastic" (young_pa, poisson) and "drucker-prager" (young_pa, poisson,
// cohesion_pa, friction_angle_deg, dilation_angle_deg, optional plane_strain_match 0 or 1).
void RegisterBuiltinMaterials(MaterialRegistry& registry);

}  // namespace gonogo::material
