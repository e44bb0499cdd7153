#include "solvers/common/soil_model.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "solvers/common/errors.h"

namespace gonogo {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string RangeText(const SoilParameterSpec& p) {
  const std::string lo = std::isinf(p.min) ? "(-inf" : (p.min_open ? "(" : "[") + Number(p.min);
  const std::string hi = std::isinf(p.max) ? "inf)" : Number(p.max) + (p.max_open ? ")" : "]");
  return lo + ", " + hi;
}

bool InRange(const SoilParameterSpec& p, double v) {
  if (!std::isfinite(v)) return false;
  if (p.min_open ? !(v > p.min) : !(v >= p.min)) return false;
  if (p.max_open ? !(v < p.max) : !(v <= p.max)) return false;
  return true;
}

SoilParameterSpec Param(std::string name, std::string unit, double min, double max,
                        std::string description, std::optional<double> default_value = {},
                        bool min_open = false, bool max_open = false) {
  SoilParameterSpec p;
  p.name = std::move(name);
  p.unit = std::move(unit);
  p.min = min;
  p.max = max;
  p.min_open = min_open;
  p.max_open = max_open;
  p.default_value = default_value;
  p.description = std::move(description);
  return p;
}

}  // namespace

const SoilParameterSpec* SoilModelSpec::Find(const std::string& parameter) const {
  for (const SoilParameterSpec& p : parameters) {
    if (p.name == parameter) return &p;
  }
  return nullptr;
}

double SoilParameters::Get(const std::string& name) const {
  auto it = values.find(name);
  if (it == values.end()) throw InputError(name, "is missing from the " + model + " parameters");
  return it->second;
}

std::string CanonicalText(const std::optional<SoilParameters>& parameters) {
  if (!parameters) return "";
  std::string text = parameters->model + "{";
  bool first = true;
  for (const auto& [name, value] : parameters->values) {  // std::map: sorted by name
    text += (first ? "" : ",") + name + "=" + Number(value);
    first = false;
  }
  return text + "}";
}

std::optional<SoilParameters> ParseCanonicalText(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const size_t open = text.find('{');
  if (open == std::string::npos || open == 0 || text.back() != '}') {
    throw std::invalid_argument("not a canonical soil parameter text: " + text);
  }
  SoilParameters p;
  p.model = text.substr(0, open);
  const std::string body = text.substr(open + 1, text.size() - open - 2);
  size_t start = 0;
  while (start < body.size()) {
    size_t end = body.find(',', start);
    if (end == std::string::npos) end = body.size();
    const std::string item = body.substr(start, end - start);
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::invalid_argument("not a canonical soil parameter text: " + text);
    }
    char* parsed_end = nullptr;
    const std::string number = item.substr(eq + 1);
    const double value = std::strtod(number.c_str(), &parsed_end);
    if (parsed_end == number.c_str() || *parsed_end != '\0') {
      throw std::invalid_argument("not a canonical soil parameter text: " + text);
    }
    p.values[item.substr(0, eq)] = value;
    start = end + 1;
  }
  return p;
}

SoilParameters SnapToCanonical(SoilParameters parameters) {
  for (auto& [name, value] : parameters.values) value = std::strtod(Number(value).c_str(), nullptr);
  return parameters;
}

void SoilModelRegistry::Register(SoilModelSpec spec) {
  Require(!spec.name.empty(), "soil_model", "a soil model needs a name");
  Require(!models_.count(spec.name), "soil_model", "soil model '" + spec.name + "' is registered twice");
  models_[spec.name] = std::move(spec);
}

const SoilModelSpec* SoilModelRegistry::Find(const std::string& model) const {
  auto it = models_.find(model);
  return it == models_.end() ? nullptr : &it->second;
}

const SoilModelSpec& SoilModelRegistry::Get(const std::string& model,
                                            const std::string& field) const {
  if (const SoilModelSpec* spec = Find(model)) return *spec;
  std::string known;
  for (const auto& [name, _] : models_) known += (known.empty() ? "" : ", ") + name;
  throw InputError(field, (model.empty() ? std::string("the soil model is missing")
                                         : "unknown soil model '" + model + "'") +
                              "; known: " + known);
}

std::vector<std::string> SoilModelRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, _] : models_) names.push_back(name);
  return names;
}

SoilParameters SoilModelRegistry::Validate(const SoilParameters& parameters,
                                           const std::string& field) const {
  const SoilModelSpec& spec = Get(parameters.model, field + ".model");
  const std::string prefix = field + ".";
  for (const auto& [name, value] : parameters.values) {
    if (spec.Find(name)) continue;
    std::string known;
    for (const SoilParameterSpec& p : spec.parameters) known += (known.empty() ? "" : ", ") + p.name;
    throw InputError(prefix + name, "is not a parameter of the " + spec.name + " model (its parameters: " + known + ")");
  }
  SoilParameters out{parameters.model, {}};
  for (const SoilParameterSpec& p : spec.parameters) {
    auto it = parameters.values.find(p.name);
    if (it == parameters.values.end()) {
      Require(p.default_value.has_value(), prefix + p.name,
              "is missing (" + p.unit + ", " + RangeText(p) + ": " + p.description + ")");
      out.values[p.name] = *p.default_value;
      continue;
    }
    Require(InRange(p, it->second), prefix + p.name,
            "must lie in " + RangeText(p) + " " + p.unit + " (got " + Number(it->second) + ")");
    out.values[p.name] = it->second;
  }
  if (spec.check) spec.check(out.values, prefix);
  return out;
}

void RegisterBuiltinSoilModels(SoilModelRegistry& registry) {
  // Bekker-Wong pressure-sinkage and Janosi-Hanamoto shear (solvers/terramech/bekker.h):
  // p = (kc / b + kphi) z^n;  tau = (c + sigma tan phi) (1 - exp(-j / K)).
  SoilModelSpec bekker;
  bekker.name = "bekker";
  bekker.description = "Bekker-Wong pressure-sinkage with Janosi-Hanamoto shear";
  bekker.source = "Wong (2008) Theory of Ground Vehicles, 4th ed., sections 2.4-2.5 and Table 2.3";
  bekker.parameters = {
      Param("n", "-", 0, 3, "sinkage exponent n", {}, true),
      Param("kc", "N/m^(n+1)", 0, kInf, "cohesive modulus k_c"),
      Param("kphi", "N/m^(n+2)", 0, kInf, "frictional modulus k_phi"),
      Param("cohesion_pa", "Pa", 0, kInf, "cohesion c"),
      Param("friction_angle_deg", "deg", 0, 90, "internal friction angle phi", {}, true, true),
      Param("shear_deformation_m", "m", 0, kInf, "Janosi-Hanamoto shear deformation modulus K", {},
            true)};
  bekker.check = [](const std::map<std::string, double>& v, const std::string& prefix) {
    Require(v.at("kc") > 0 || v.at("kphi") > 0, prefix + "kphi", "kc and kphi cannot both be zero");
  };
  registry.Register(std::move(bekker));

  // Continuum closures of the FE soil bin (solvers/material/).
  SoilModelSpec dp;
  dp.name = "drucker-prager";
  dp.description = "elastic-perfectly plastic Drucker-Prager fitted to Mohr-Coulomb (c, phi, psi)";
  dp.source = "solvers/material/README.md; strengths of solvers/rig/data/fe_soils.csv";
  dp.parameters = {
      Param("density_kg_m3", "kg/m^3", 100, 5000, "bulk density rho"),
      Param("young_pa", "Pa", 0, kInf, "Young's modulus E", {}, true),
      Param("poisson", "-", 0, 0.5, "Poisson's ratio nu", {}, false, true),
      Param("cohesion_pa", "Pa", 0, kInf, "cohesion c"),
      Param("friction_angle_deg", "deg", 0, 90, "friction angle phi", {}, false, true),
      Param("dilation_angle_deg", "deg", 0, 90, "dilation angle psi <= phi", 0.0, false, true)};
  dp.check = [](const std::map<std::string, double>& v, const std::string& prefix) {
    Require(v.at("dilation_angle_deg") <= v.at("friction_angle_deg"), prefix + "dilation_angle_deg",
            "must not exceed the friction angle");
  };
  registry.Register(std::move(dp));

  SoilModelSpec elastic;
  elastic.name = "linear-elastic";
  elastic.description = "isotropic linear elasticity (a reference closure for the FE soil bin)";
  elastic.source = "solvers/material/linear_elastic.h";
  elastic.parameters = {Param("density_kg_m3", "kg/m^3", 100, 5000, "bulk density rho"),
                        Param("young_pa", "Pa", 0, kInf, "Young's modulus E", {}, true),
                        Param("poisson", "-", 0, 0.5, "Poisson's ratio nu", {}, false, true)};
  registry.Register(std::move(elastic));

  // Grain-scale soils: the periodic DE RVE of the FE-DE model (seed 000) and the EEPA bin (seed 001).
  SoilModelSpec hm;
  hm.name = "dem-hertz-mindlin";
  hm.description = "Hertz-Mindlin grains with rolling resistance in a periodic RVE (seed 000)";
  hm.source = "seed 000 (shared/reference/rve_hertz_mindlin.csv); defaults are its values";
  hm.parameters = {
      Param("young_pa", "Pa", 0, kInf, "grain Young's modulus E", 1.5e9, true),
      Param("poisson", "-", 0, 0.5, "grain Poisson's ratio nu", 0.293, false, true),
      Param("friction", "-", 0, 10, "Coulomb friction mu", 0.452),
      Param("rolling_stiffness", "-", 0, 100, "rolling stiffness beta", 2.25),
      Param("rolling_limit", "-", 0, 10, "rolling friction eta", 0.99),
      Param("particle_radius_m", "m", 0, 1, "mean grain radius", 0.87e-3, true),
      Param("density_kg_m3", "kg/m^3", 100, 20000, "grain density rho", 2650.0),
      // At least 100: a smaller cell is under 4 grain diameters across, too few grains for a
      // homogenised response (and soon thinner than 2 r_max + skin when compressed).
      Param("grains_per_rve", "-", 100, 100000, "grains in one RVE", 500.0),
      Param("consolidation_pressure_pa", "Pa", 0, kInf, "isotropic confining stress of the RVE",
            100e3, true),
      Param("initial_solid_fraction", "-", 0, 0.4, "solid fraction of the gas before consolidation",
            0.25, true)};
  registry.Register(std::move(hm));

  SoilModelSpec eepa;
  eepa.name = "dem-eepa";
  eepa.description = "Edinburgh Elasto-Plastic Adhesion grains (seed 001 Table 3)";
  eepa.source = "seed 001 Table 3 (shared/reference/soils_dem_eepa.csv); defaults are its FGS column";
  eepa.parameters = {
      Param("shear_modulus_pa", "Pa", 0, kInf, "grain shear modulus G", 5.0e8, true),
      Param("poisson", "-", 0, 0.5, "grain Poisson's ratio nu", 0.25, false, true),
      Param("density_kg_m3", "kg/m^3", 100, 20000, "grain density rho", 2500.0),
      Param("particle_radius_m", "m", 0, 1, "grain radius", 5e-3, true),
      Param("restitution", "-", 0, 1, "coefficient of restitution e", 0.6, true),
      Param("friction", "-", 0, 10, "static friction mu", 0.5),
      Param("rolling_friction", "-", 0, 10, "rolling friction", 0.01),
      Param("pull_off_force_n", "N", -kInf, 0, "constant pull-off force f0 (negative)", -2.0),
      Param("surface_energy_j_m2", "J/m^2", 0, kInf, "surface energy", 7.0),
      Param("plasticity_ratio", "-", 0, 1, "contact plasticity ratio lambda_p", 0.9, false, true),
      Param("slope_exponent", "-", 1, 10, "loading and unloading exponent n", 1.5),
      Param("tensile_exponent", "-", 1, 10, "adhesive branch exponent chi", 1.5),
      Param("tangential_stiffness_multiplier", "-", 0, 10, "k_t over loading k_n", 0.67, true)};
  registry.Register(std::move(eepa));
}

SoilModelRegistry& SoilModels() {
  static SoilModelRegistry* registry = [] {
    auto* r = new SoilModelRegistry;
    RegisterBuiltinSoilModels(*r);
    return r;
  }();
  return *registry;
}

}  // namespace gonogo
