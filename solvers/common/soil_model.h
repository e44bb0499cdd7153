// Open soil description: a soil model is a name plus named, unit-bearing parameters, declared once.
// The declaration (SoilModelSpec) drives validation (errors name the field and the range), and the
// generic form (SoilParameters: model name + map) is what the cache key, the store and the wire
// carry, so a new model is one declaration and the code that reads it, nothing else
// (CONVENTIONS "Seams"; LIGGGHTS registerSettings).
//
//   SoilParameters p{"bekker", {{"n", 0.79}, {"kc", 102000}, ...}};
//   SoilModels().Validate(p, "soil.parameters");          // InputError("soil.parameters.n", ...)
//   CanonicalText(p);   // "bekker{cohesion_pa=1300,friction_angle_deg=31.1,kc=102000,...}"
//
// Models are registered explicitly (RegisterBuiltinSoilModels); SoilModels() is the process's
// registry, holding the built-in models, to which a test or a plug-in may add more.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace gonogo {

// One parameter of a soil model.
struct SoilParameterSpec {
  std::string name;         // as on the wire and in the key: "kc", "young_pa" (unit in the name
                            // where it is SI and short; `unit` says it in full)
  std::string unit;         // "Pa", "N/m^(n+1)", "-", "deg", "m", "kg/m^3"
  double min = 0;           // valid range [min, max] (or open ends, below)
  double max = 0;
  bool min_open = false;    // true: value must exceed min
  bool max_open = false;    // true: value must stay below max
  std::optional<double> default_value;  // used when the parameter is not given; none: required
  std::string description;  // one line: the symbol and its meaning
};

// A soil model's declaration.
struct SoilModelSpec {
  std::string name;         // "bekker", "drucker-prager", "dem-hertz-mindlin", ...
  std::string description;  // one line
  std::string source;       // where the model and its parameters are defined
  std::vector<SoilParameterSpec> parameters;
  // Rules across parameters (e.g. kc and kphi not both zero); throws InputError naming
  // `field_prefix` + parameter. May be empty.
  std::function<void(const std::map<std::string, double>& values, const std::string& field_prefix)>
      check;

  const SoilParameterSpec* Find(const std::string& parameter) const;
};

// An explicit parameter set of one model: what a request, a soil table or the catalogue carries.
struct SoilParameters {
  std::string model;
  std::map<std::string, double> values;  // parameter name -> value in the declared unit

  bool operator==(const SoilParameters& o) const { return model == o.model && values == o.values; }
  // The value of `name`; throws InputError(name, "missing") when absent (call after Validate,
  // which fills defaults).
  double Get(const std::string& name) const;
};

// Canonical text of a parameter set: "model{a=1,b=2.5}", parameters sorted by name, nine
// significant digits each: the one text used by the cache key and the store. "" for no parameters.
std::string CanonicalText(const std::optional<SoilParameters>& parameters);
// Inverse of CanonicalText; throws std::invalid_argument for text it did not write.
std::optional<SoilParameters> ParseCanonicalText(const std::string& text);
// Every value rounded to the nine significant digits of its canonical text, so that a computed
// curve is exactly the curve of its key.
SoilParameters SnapToCanonical(SoilParameters parameters);

class SoilModelRegistry {
 public:
  // Throws InputError("soil_model", ...) for an empty or duplicate name.
  void Register(SoilModelSpec spec);
  const SoilModelSpec* Find(const std::string& model) const;
  // Throws InputError(field, "unknown soil model 'x'; known: a, b").
  const SoilModelSpec& Get(const std::string& model, const std::string& field) const;
  std::vector<std::string> Names() const;  // sorted

  // The set with its defaults filled in, checked against its model: unknown model, unknown or
  // missing parameter, a value outside its range or not finite, the model's own rules. Errors are
  // InputError naming `field` + "." + parameter, with the unit and the range.
  SoilParameters Validate(const SoilParameters& parameters, const std::string& field) const;

 private:
  std::map<std::string, SoilModelSpec> models_;
};

// Declares "bekker", "drucker-prager", "linear-elastic", "dem-hertz-mindlin" and "dem-eepa"
// (solvers/common/README.md lists their parameters, units, ranges and sources).
void RegisterBuiltinSoilModels(SoilModelRegistry& registry);

// The process's soil-model registry: the built-in models, registered on first use.
SoilModelRegistry& SoilModels();

}  // namespace gonogo
