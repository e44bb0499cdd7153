#include "clients/cli_wheel_soil.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "clients/cli_commands.h"
#include "solvers/common/units.h"

namespace gonogo::cli {
namespace {

// "KEY=VALUE,KEY=VALUE" -> values; `option` names the option in errors.
std::map<std::string, double> ParseKeyValues(const std::string& text, const std::string& option) {
  std::map<std::string, double> values;
  std::istringstream items(text);
  for (std::string item; std::getline(items, item, ',');) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) throw UsageError(option + ": '" + item + "' is not KEY=VALUE");
    const std::string key = item.substr(0, eq);
    if (values.count(key)) throw UsageError(option + ": " + key + " is given twice");
    try {
      size_t used = 0;
      values[key] = std::stod(item.substr(eq + 1), &used);
      if (used != item.size() - eq - 1) throw std::invalid_argument("");
    } catch (const std::logic_error&) {
      throw UsageError(option + ": " + key + " needs a number");
    }
  }
  return values;
}

// --bekker "n=0.7,kc=5270,kphi=1515040,c=1300,phi_deg=31.1,K=0.0115": the bekker model's set in
// the short names of the Bekker literature, every key exactly once.
v1::SoilParameterSet ParseBekker(const std::string& text) {
  std::map<std::string, double> values = ParseKeyValues(text, "--bekker");
  const std::vector<std::pair<std::string, std::string>> names = {{"n", "n"},
                                                                  {"kc", "kc"},
                                                                  {"kphi", "kphi"},
                                                                  {"c", "cohesion_pa"},
                                                                  {"phi_deg", "friction_angle_deg"},
                                                                  {"K", "shear_deformation_m"}};
  for (const auto& [short_name, _] : names) {
    if (!values.count(short_name)) throw UsageError("--bekker: " + short_name + "= is missing");
  }
  if (values.size() != names.size()) {
    throw UsageError("--bekker: only n, kc, kphi, c, phi_deg and K are known");
  }
  v1::SoilParameterSet p;
  p.set_model("bekker");
  for (const auto& [short_name, name] : names) (*p.mutable_values())[name] = values[short_name];
  return p;
}

// --soil-params "MODEL:NAME=VALUE,...": any soil model's set, in its declared names and units
// (`gonogo soils` lists them); the server checks names and ranges.
v1::SoilParameterSet ParseSoilParameters(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos || colon == 0) {
    throw UsageError(
        "--soil-params: give MODEL:NAME=VALUE,... (e.g. drucker-prager:young_pa=1.5e7,...)");
  }
  v1::SoilParameterSet p;
  p.set_model(text.substr(0, colon));
  for (const auto& [name, value] : ParseKeyValues(text.substr(colon + 1), "--soil-params")) {
    (*p.mutable_values())[name] = value;
  }
  return p;
}

// The tyre and wheel load of one axle of the vehicle in `file`.
void WheelOfVehicle(const std::string& file, int axle_number, v1::Tyre* tyre,
                    double* wheel_load_n) {
  const auto vehicle = ReadJson<v1::Vehicle>(file, "vehicle file");
  const int axle = axle_number - 1;
  if (axle < 0 || axle >= vehicle.axles_size()) {
    throw UsageError("--axle must lie in 1.." + std::to_string(vehicle.axles_size()));
  }
  const v1::Axle& ax = vehicle.axles(axle);
  double fraction = ax.load_fraction();
  // Two axles without load fractions: the centre of gravity splits the weight.
  if (fraction == 0 && vehicle.wheelbase_m() > 0 && vehicle.axles_size() == 2) {
    const double rear = vehicle.cg_behind_front_axle_m() / vehicle.wheelbase_m();
    fraction = axle == 0 ? 1 - rear : rear;
  }
  *tyre = ax.tyre();
  *wheel_load_n = vehicle.mass_kg() * units::kStandardGravityMps2 * fraction / std::max(1u, ax.wheels());
}

}  // namespace

void AddWheelOptions(CLI::App& app, WheelOptions* w) {
  const std::string group = "Wheel (a vehicle's axle, or the wheel itself)";
  CLI::Option* vehicle =
      app.add_option("--vehicle", w->vehicle_file, "vehicle JSON (clients/vehicles/*.json)")
          ->type_name("FILE")
          ->check(InputFile())
          ->group(group);
  app.add_option("--axle", w->axle, "axle of the vehicle, 1 = front")
      ->type_name("N")
      ->capture_default_str()
      ->needs(vehicle)
      ->group(group);
  // The wheel itself, in place of a vehicle.
  const auto own = [&](CLI::Option* o, const char* unit) {
    o->type_name(unit)->group(group)->excludes(vehicle);
  };
  own(app.add_option("--wheel-diameter", w->diameter_m, "unloaded outside diameter d, m"), "M");
  own(app.add_option("--wheel-width", w->width_m, "section width b, m"), "M");
  own(app.add_option("--wheel-load", w->wheel_load_n, "vertical load on the wheel, N"), "N");
  own(app.add_option("--section-height", w->section_height_m,
                     "section height h, m; without it the wheel is rigid (d/4 is sent)"),
      "M");
  own(app.add_option("--deflection", w->deflection_m, "vertical deflection under load, m")
          ->capture_default_str(),
      "M");
  own(app.add_option("--rolling-radius", w->rolling_radius_m,
                     "rolling radius, m; 0: d/2 - deflection")
          ->capture_default_str(),
      "M");
  own(app.add_option("--inflation-pressure-kpa", w->inflation_pressure_kpa,
                     "gauge inflation pressure, kPa; 0: not given")
          ->capture_default_str(),
      "KPA");
}

void AddSoilOptions(CLI::App& app, SoilOptions* s) {
  const std::string group = "Soil (at least one; --cone-index and --soil combine with the others)";
  app.add_option("--cone-index", s->cone_index_kpa,
                 "cone index, kPa (rating cone index for the empirical tier)")
      ->type_name("KPA")
      ->group(group);
  app.add_option("--soil", s->soil_name, "soil catalogue name (gonogo soils lists them)")
      ->type_name("NAME")
      ->group(group);
  auto* bekker = app.add_option("--bekker", s->bekker,
                                "Bekker parameters in SI: kc N/m^(n+1), kphi N/m^(n+2), c Pa, "
                                "phi degrees, K m")
                     ->type_name("n=N,kc=KC,kphi=KPHI,c=C,phi_deg=PHI,K=K")
                     ->group(group);
  app.add_option("--soil-params", s->soil_params,
                 "any soil model's parameters, in the names and units gonogo soils lists")
      ->type_name("MODEL:NAME=VALUE,...")
      ->group(group)
      ->excludes(bekker);
}

void WheelFromOptions(const WheelOptions& w, v1::Tyre* tyre, double* wheel_load_n) {
  if (!w.vehicle_file.empty()) {
    WheelOfVehicle(w.vehicle_file, w.axle, tyre, wheel_load_n);
    return;
  }
  for (const auto& [value, name] :
       {std::pair{&w.diameter_m, "--wheel-diameter"}, std::pair{&w.width_m, "--wheel-width"},
        std::pair{&w.wheel_load_n, "--wheel-load"}}) {
    if (!value->has_value()) {
      throw UsageError(std::string(name) + " is required without --vehicle");
    }
  }
  tyre->set_diameter_m(*w.diameter_m);
  tyre->set_width_m(*w.width_m);
  // A rigid wheel has no section height: a quarter of the diameter stands in (it only enters
  // the empirical tier's deflection ratio, which is 0 for a rigid wheel).
  tyre->set_section_height_m(w.section_height_m.value_or(0.25 * *w.diameter_m));
  tyre->set_deflection_m(w.deflection_m);
  tyre->set_rolling_radius_m(w.rolling_radius_m);
  tyre->set_inflation_pressure_pa(w.inflation_pressure_kpa * 1000.0);
  *wheel_load_n = *w.wheel_load_n;
}

v1::SoilState SoilFromOptions(const SoilOptions& s) {
  if (!s.cone_index_kpa && s.soil_name.empty() && s.bekker.empty() && s.soil_params.empty()) {
    throw UsageError(
        "give the soil: --cone-index KPA, --soil NAME, --bekker ... or --soil-params MODEL:...");
  }
  v1::SoilState soil;
  if (s.cone_index_kpa) soil.set_cone_index_pa(*s.cone_index_kpa * 1000.0);
  soil.set_soil_name(s.soil_name);
  if (!s.bekker.empty()) *soil.mutable_parameters() = ParseBekker(s.bekker);
  if (!s.soil_params.empty()) *soil.mutable_parameters() = ParseSoilParameters(s.soil_params);
  return soil;
}

}  // namespace gonogo::cli
