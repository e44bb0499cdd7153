#include "solvers/material/registry.h"

#include <utility>

#include "solvers/common/errors.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/material/linear_elastic.h"

namespace gonogo::material {
namespace {

std::string JoinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

// Reads a model's parameters from a map: refuses keys the model does not know, and names the
// missing ones.
class ParameterReader {
 public:
  ParameterReader(const ParameterMap& parameters, const std::string& model,
                  const std::vector<std::string>& known_keys)
      : parameters_(parameters) {
    for (const auto& [key, value] : parameters) {
      bool known = false;
      for (const std::string& candidate : known_keys) known = known || candidate == key;
      Require(known, "material." + key,
              "unknown parameter of " + model + "; known: " + JoinNames(known_keys));
    }
  }
  double Required(const std::string& key) const {
    auto found = parameters_.find(key);
    Require(found != parameters_.end(), "material." + key, "missing");
    return found->second;
  }
  double Optional(const std::string& key, double fallback) const {
    auto found = parameters_.find(key);
    return found == parameters_.end() ? fallback : found->second;
  }

 private:
  const ParameterMap& parameters_;
};

std::unique_ptr<ConstitutiveModel> MakeLinearElastic(const ParameterMap& parameters) {
  const ParameterReader reader(parameters, "linear-elastic", {"young_pa", "poisson"});
  LinearElasticParams params;
  params.young_pa = reader.Required("young_pa");
  params.poisson = reader.Required("poisson");
  params.Validate("material.");
  return std::make_unique<LinearElastic>(params);
}

std::unique_ptr<ConstitutiveModel> MakeDruckerPrager(const ParameterMap& parameters) {
  const ParameterReader reader(parameters, "drucker-prager",
                               {"young_pa", "poisson", "cohesion_pa", "friction_angle_deg",
                                "dilation_angle_deg", "plane_strain_match"});
  DruckerPragerParams params;
  params.young_pa = reader.Required("young_pa");
  params.poisson = reader.Required("poisson");
  params.cohesion_pa = reader.Required("cohesion_pa");
  params.friction_angle_deg = reader.Required("friction_angle_deg");
  params.dilation_angle_deg = reader.Required("dilation_angle_deg");
  const double plane_strain = reader.Optional("plane_strain_match", 0.0);
  Require(plane_strain == 0.0 || plane_strain == 1.0, "material.plane_strain_match",
          "must be 0 (triaxial compression match) or 1 (plane strain match)");
  params.match = plane_strain == 1.0 ? DruckerPragerParams::Match::kPlaneStrain
                                     : DruckerPragerParams::Match::kTriaxialCompression;
  params.Validate("material.");
  return std::make_unique<DruckerPrager>(params);
}

}  // namespace

void MaterialRegistry::Register(ModelEntry entry) {
  Require(!entry.name.empty(), "material", "a model entry needs a name");
  Require(static_cast<bool>(entry.make), "material", entry.name + " has no factory");
  Require(entries_.count(entry.name) == 0, "material", entry.name + " is registered twice");
  std::string name = entry.name;
  entries_.emplace(std::move(name), std::move(entry));
}

const ModelEntry& MaterialRegistry::Get(const std::string& name) const {
  auto found = entries_.find(name);
  Require(found != entries_.end(), "material",
          "unknown material model '" + name + "'; known: " + JoinNames(Names()));
  return found->second;
}

std::unique_ptr<ConstitutiveModel> MaterialRegistry::Make(const std::string& name,
                                                          const ParameterMap& parameters) const {
  return Get(name).make(parameters);
}

std::vector<std::string> MaterialRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, entry] : entries_) names.push_back(name);
  return names;
}

void RegisterBuiltinMaterials(MaterialRegistry& registry) {
  registry.Register({"linear-elastic",
                     "isotropic linear elasticity, hypoelastic with the Hughes-Winget update",
                     MakeLinearElastic,
                     {{"young_pa", 20e6}, {"poisson", 0.3}}});
  registry.Register({"drucker-prager",
                     "perfectly plastic Drucker-Prager cone matched to Mohr-Coulomb, "
                     "non-associated flow (de Souza Neto et al. 2008, sec. 8.3.2)",
                     MakeDruckerPrager,
                     {{"young_pa", 20e6},
                      {"poisson", 0.3},
                      {"cohesion_pa", 10e3},
                      {"friction_angle_deg", 30},
                      {"dilation_angle_deg", 10},
                      {"plane_strain_match", 0}}});
}

}  // namespace gonogo::material
