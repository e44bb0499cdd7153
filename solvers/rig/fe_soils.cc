#include "solvers/rig/fe_soils.h"

#include <cmath>

#include "solvers/common/errors.h"
#include "solvers/common/named_csv.h"

namespace gonogo::rig {

void FeSoil::Validate(const std::string& p) const {
  Require(density_kg_m3 > 0 && std::isfinite(density_kg_m3), p + "density_kg_m3",
          "must be positive");
  strength.Validate(p);
}

FeSoilLibrary FeSoilLibrary::Parse(const std::string& csv_text) {
  static const std::vector<std::string> kColumns = {
      "name",        "density_kg_m3",      "young_pa",           "poisson",
      "cohesion_pa", "friction_angle_deg", "dilation_angle_deg", "source"};
  FeSoilLibrary library;
  for (const NamedCsvRow& row : ParseNamedCsv(csv_text, kColumns)) {
    FeSoil soil;
    soil.name = row.name;
    soil.density_kg_m3 = row.values[0];
    soil.strength.young_pa = row.values[1];
    soil.strength.poisson = row.values[2];
    soil.strength.cohesion_pa = row.values[3];
    soil.strength.friction_angle_deg = row.values[4];
    soil.strength.dilation_angle_deg = row.values[5];
    soil.source = row.source;
    try {
      soil.Validate("");
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw InputError(NamedCsvCell(row.line, e.field()), what.substr(e.field().size() + 2));
    }
    library.soils_.push_back(std::move(soil));
  }
  return library;
}

const FeSoilLibrary& FeSoilLibrary::Builtin() {
  static const FeSoilLibrary builtin = Parse(BuiltinFeSoilsCsv());
  return builtin;
}

const FeSoil* FeSoilLibrary::Find(const std::string& name) const {
  const std::string key = NamedCsvKey(name);
  for (const FeSoil& soil : soils_) {
    if (NamedCsvKey(soil.name) == key) return &soil;
  }
  return nullptr;
}

std::vector<std::string> FeSoilLibrary::Names() const {
  std::vector<std::string> names;
  for (const FeSoil& soil : soils_) names.push_back(soil.name);
  return names;
}

}  // namespace gonogo::rig
