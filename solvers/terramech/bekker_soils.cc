#include "solvers/terramech/bekker_soils.h"

#include "solvers/common/errors.h"
#include "solvers/common/named_csv.h"

namespace gonogo::terramech {

BekkerSoilLibrary BekkerSoilLibrary::Parse(const std::string& csv_text) {
  static const std::vector<std::string> kColumns = {
      "name", "n", "kc", "kphi", "cohesion_pa", "friction_angle_deg", "shear_deformation_m",
      "source"};
  BekkerSoilLibrary library;
  for (const NamedCsvRow& row : ParseNamedCsv(csv_text, kColumns)) {
    BekkerSoil soil;
    soil.name = row.name;
    BekkerParameters& p = soil.parameters;
    p.n = row.values[0];
    p.kc = row.values[1];
    p.kphi = row.values[2];
    p.cohesion_pa = row.values[3];
    p.friction_angle_deg = row.values[4];
    p.shear_deformation_m = row.values[5];
    soil.source = row.source;
    // Validate names its field ("n", "kc", ...): report it as this row's column.
    try {
      p.Validate("");
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw InputError(NamedCsvCell(row.line, e.field()), what.substr(e.field().size() + 2));
    }
    library.soils_.push_back(std::move(soil));
  }
  return library;
}

const BekkerSoilLibrary& BekkerSoilLibrary::Builtin() {
  static const BekkerSoilLibrary builtin = Parse(BuiltinBekkerSoilsCsv());
  return builtin;
}

const BekkerSoil* BekkerSoilLibrary::Find(const std::string& name) const {
  const std::string key = NamedCsvKey(name);
  for (const BekkerSoil& soil : soils_) {
    if (NamedCsvKey(soil.name) == key) return &soil;
  }
  return nullptr;
}

std::vector<std::string> BekkerSoilLibrary::Names() const {
  std::vector<std::string> names;
  names.reserve(soils_.size());
  for (const BekkerSoil& soil : soils_) names.push_back(soil.name);
  return names;
}

}  // namespace gonogo::terramech
