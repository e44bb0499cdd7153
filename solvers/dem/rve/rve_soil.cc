#include "solvers/dem/rve/rve_soil.h"

#include <cmath>
#include <exception>
#include <future>
#include <ios>
#include <map>
#include <mutex>
#include <sstream>
#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::dem::rve {
namespace {

std::string NumberText(double value) {
  std::ostringstream text;
  text.precision(10);
  text << value;
  return text.str();
}

// `value` as a whole number in [min, max]; throws InputError(field, ...) otherwise. A flat
// parameter map carries integers as doubles.
double WholeNumber(double value, const std::string& field, double min, double max) {
  Require(std::isfinite(value) && value == std::floor(value), field,
          "must be an integer (got " + NumberText(value) + ")");
  Require(value >= min && value <= max, field,
          "must lie in [" + NumberText(min) + ", " + NumberText(max) + "] (got " +
              NumberText(value) + ")");
  return value;
}

// Every field of RveParams, each double in hexadecimal (exact), so that two parameter sets share
// a template only when Rve::Generate would make the same one. The structured bindings list every
// data member: a field added to RveParams or MaterialParams stops this from compiling until it
// joins the key.
std::string TemplateKey(const RveParams& params) {
  const auto& [material, grain_count, mean_radius_m, radius_spread, seed, initial_solid_fraction,
               consolidation_pressure_pa, consolidation_friction, time_step_safety,
               max_inertial_number, threads] = params;
  const auto& [youngs_modulus_pa, poisson_ratio, density_kg_m3, friction, rolling_stiffness,
               rolling_limit, restitution] = material;
  std::ostringstream key;
  key << std::hexfloat;
  for (double value :
       {youngs_modulus_pa, poisson_ratio, density_kg_m3, friction, rolling_stiffness, rolling_limit,
        restitution, mean_radius_m, radius_spread, initial_solid_fraction,
        consolidation_pressure_pa, consolidation_friction, time_step_safety, max_inertial_number}) {
    key << value << ';';
  }
  key << grain_count << ';' << seed << ';' << threads;
  return key.str();
}

std::unique_ptr<RveMaterial> MakeRveMaterial(const RveMaterialParams& params) {
  params.Validate();
  return std::make_unique<RveMaterial>(params, Rve(*SharedRveTemplate(params.rve)));
}

// The "dem-rve" parameter map split into the soil set, the numerics and the batch threads.
RveMaterialParams RveMaterialParamsFromMap(const material::ParameterMap& parameters) {
  const SoilModelSpec& soil_model = SoilModels().Get(kRveSoilModel, "material.model");
  SoilParameters soil{kRveSoilModel, {}};
  RveNumerics numerics;
  int batch_threads = 1;
  for (const auto& [key, value] : parameters) {
    const std::string field = "material." + key;
    if (soil_model.Find(key) != nullptr) {
      soil.values[key] = value;
    } else if (key == "min_steps_per_increment") {
      numerics.min_steps_per_increment = static_cast<int>(WholeNumber(value, field, 1, 1e9));
    } else if (key == "relax_steps") {
      numerics.relax_steps = static_cast<int>(WholeNumber(value, field, 0, 1e9));
    } else if (key == "max_strain_increment") {
      numerics.max_strain_increment = value;
    } else if (key == "max_inertial_number") {
      numerics.max_inertial_number = value;
    } else if (key == "seed") {
      numerics.seed = static_cast<unsigned>(WholeNumber(value, field, 0, 4294967295.0));
    } else if (key == "batch_threads") {
      batch_threads = static_cast<int>(WholeNumber(value, field, 1, 1024));
    } else {
      std::string known;
      for (const SoilParameterSpec& p : soil_model.parameters) known += p.name + ", ";
      throw InputError(field, "is not a parameter of dem-rve (its parameters: " + known +
                                  "min_steps_per_increment, relax_steps, max_strain_increment, "
                                  "max_inertial_number, seed, batch_threads)");
    }
  }
  RveMaterialParams params = RveMaterialParamsFromSoil(soil, numerics, "material");
  params.batch_threads = batch_threads;
  return params;
}

}  // namespace

void RveNumerics::Validate(const std::string& field_prefix) const {
  Require(min_steps_per_increment >= 1, field_prefix + "min_steps_per_increment",
          "must be >= 1 (got " + std::to_string(min_steps_per_increment) + ")");
  Require(relax_steps >= 0, field_prefix + "relax_steps",
          "must be >= 0 (got " + std::to_string(relax_steps) + ")");
  Require(std::isfinite(max_strain_increment) && max_strain_increment > 0.0 &&
              max_strain_increment <= 0.1,
          field_prefix + "max_strain_increment",
          "must lie in (0, 0.1] (got " + NumberText(max_strain_increment) + ")");
  // Above about 0.1 a granular flow is no longer quasi-static (GDR MiDi 2004).
  Require(
      std::isfinite(max_inertial_number) && max_inertial_number > 0.0 && max_inertial_number <= 0.1,
      field_prefix + "max_inertial_number",
      "must lie in (0, 0.1] (got " + NumberText(max_inertial_number) + ")");
}

RveMaterialParams RveMaterialParamsFromSoil(const SoilParameters& soil, const RveNumerics& numerics,
                                            const std::string& field) {
  Require(soil.model == kRveSoilModel, field + ".model",
          "is '" + soil.model + "'; the DE RVE is built from a " + kRveSoilModel + " set");
  const SoilParameters valid = SoilModels().Validate(soil, field);
  const double grains = valid.Get("grains_per_rve");
  Require(grains == std::floor(grains), field + ".grains_per_rve",
          "must be an integer (got " + NumberText(grains) + ")");
  numerics.Validate(field + ".");

  RveMaterialParams params;
  RveParams& rve = params.rve;
  // Grain contact law of seed 000 (solvers/dem/contact_model.h); restitution stays
  // SeedMaterial's, which the soil model does not carry.
  rve.material.youngs_modulus_pa = valid.Get("young_pa");
  rve.material.poisson_ratio = valid.Get("poisson");
  rve.material.friction = valid.Get("friction");
  rve.material.rolling_stiffness = valid.Get("rolling_stiffness");
  rve.material.rolling_limit = valid.Get("rolling_limit");
  rve.material.density_kg_m3 = valid.Get("density_kg_m3");
  // The packing.
  rve.mean_radius_m = valid.Get("particle_radius_m");
  rve.grain_count = static_cast<int>(grains);  // [50, 100000] by the soil model's range
  rve.initial_solid_fraction = valid.Get("initial_solid_fraction");
  rve.consolidation_pressure_pa = valid.Get("consolidation_pressure_pa");
  // The numerics.
  rve.seed = numerics.seed;
  rve.max_inertial_number = numerics.max_inertial_number;
  params.min_steps_per_increment = numerics.min_steps_per_increment;
  params.relax_steps = numerics.relax_steps;
  params.max_strain_increment = numerics.max_strain_increment;
  params.Validate();
  return params;
}

std::shared_ptr<const Rve> SharedRveTemplate(const RveParams& params) {
  params.Validate();
  using Template = std::shared_ptr<const Rve>;
  static std::mutex mutex;
  // Key -> the template, or its generation in progress (a future the waiters share).
  static std::map<std::string, std::shared_future<Template>> templates;
  const std::string key = TemplateKey(params);
  std::promise<Template> generated;
  std::shared_future<Template> result;
  bool generate_here = false;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto found = templates.find(key);
    if (found != templates.end()) {
      result = found->second;
    } else {
      result = generated.get_future().share();
      templates.emplace(key, result);
      generate_here = true;
    }
  }
  // Generated outside the lock, so that other parameter sets need not wait for this one.
  if (generate_here) {
    try {
      generated.set_value(std::make_shared<const Rve>(Rve::Generate(params)));
    } catch (...) {
      generated.set_exception(std::current_exception());
      const std::lock_guard<std::mutex> lock(mutex);
      templates.erase(key);
    }
  }
  return result.get();
}

std::shared_ptr<const RveMaterial> SharedRveMaterial(const RveMaterialParams& params) {
  return MakeRveMaterial(params);
}

double ConsolidatedBulkDensityKgM3(const RveMaterial& material) {
  const Rve& initial = material.initial();
  return initial.params().material.density_kg_m3 * initial.Snapshot().solid_fraction;
}

void RegisterRveMaterial(material::MaterialRegistry& registry) {
  registry.Register(
      {"dem-rve",
       "periodic DE RVE of seed 000's FE-DE model (solvers/dem/rve), one RVE per point, built "
       "from a dem-hertz-mindlin soil set plus DE numerics",
       [](const material::ParameterMap& parameters)
           -> std::unique_ptr<material::ConstitutiveModel> {
         return MakeRveMaterial(RveMaterialParamsFromMap(parameters));
       },
       // Cheap: 100 grains (the soil model's least) and 30 relaxation steps keep the material
       // contract test at about a second.
       {{"grains_per_rve", 100},
        {"consolidation_pressure_pa", 100e3},
        {"seed", 1},
        {"min_steps_per_increment", 20},
        {"relax_steps", 30},
        {"max_strain_increment", 0.01},
        {"batch_threads", 2}}});
}

}  // namespace gonogo::dem::rve
