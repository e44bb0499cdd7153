#include "solvers/tiers/soil_catalogue.h"

#include <algorithm>
#include <set>
#include <sstream>

#include "solvers/common/errors.h"
#include "solvers/common/named_csv.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/terramech/bekker_soils.h"

namespace gonogo::tiers {

const char* BuiltinDemEepaSoilsCsv();
const char* BuiltinDemHertzMindlinSoilsCsv();

namespace {

// The header line of a table: the first line that is neither blank nor a comment.
std::vector<std::string> HeaderOf(const std::string& csv_text) {
  std::istringstream lines(csv_text);
  for (std::string line; std::getline(lines, line);) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::vector<std::string> columns;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) {
      cell.erase(0, cell.find_first_not_of(" \t\r"));
      cell.erase(cell.find_last_not_of(" \t\r") + 1);
      columns.push_back(cell);
    }
    return columns;
  }
  return {};
}

}  // namespace

void SoilCatalogue::AddTable(const std::string& model, const std::string& csv_text) {
  const SoilModelSpec& spec = SoilModels().Get(model, model + " table");
  const std::vector<std::string> columns = HeaderOf(csv_text);
  Require(columns.size() >= 2 && columns.front() == "name" && columns.back() == "source",
          model + " table", "the header must be name, the model's parameters, source");
  for (size_t c = 1; c + 1 < columns.size(); ++c) {
    Require(spec.Find(columns[c]) != nullptr, model + " table column " + columns[c],
            "is not a parameter of the " + model + " model");
  }
  for (const NamedCsvRow& row : ParseNamedCsv(csv_text, columns)) {
    SoilParameters p{model, {}};
    for (size_t c = 1; c + 1 < columns.size(); ++c) p.values[columns[c]] = row.values[c - 1];
    CatalogueEntry entry;
    entry.soil = row.name;
    entry.parameters = SoilModels().Validate(p, model + " table line " + std::to_string(row.line));
    entry.source = row.source;
    Require(Find(row.name, model) == nullptr, model + " table line " + std::to_string(row.line),
            "soil '" + row.name + "' is listed twice");
    entries_.push_back(std::move(entry));
  }
}

const CatalogueEntry* SoilCatalogue::Find(const std::string& soil, const std::string& model) const {
  const std::string key = NamedCsvKey(soil);
  for (const CatalogueEntry& e : entries_) {
    if (e.parameters.model == model && NamedCsvKey(e.soil) == key) return &e;
  }
  return nullptr;
}

std::vector<std::string> SoilCatalogue::Names() const {
  std::set<std::string> keys;
  std::vector<std::string> names;
  for (const CatalogueEntry& e : entries_) {
    if (keys.insert(NamedCsvKey(e.soil)).second) names.push_back(e.soil);
  }
  std::sort(names.begin(), names.end(),
            [](const std::string& a, const std::string& b) { return NamedCsvKey(a) < NamedCsvKey(b); });
  return names;
}

std::vector<std::string> SoilCatalogue::ModelsOf(const std::string& soil) const {
  std::vector<std::string> models;
  for (const CatalogueEntry& e : entries_) {
    if (NamedCsvKey(e.soil) == NamedCsvKey(soil)) models.push_back(e.parameters.model);
  }
  std::sort(models.begin(), models.end());
  return models;
}

const SoilCatalogue& BuiltinSoilCatalogue() {
  static const SoilCatalogue catalogue = [] {
    SoilCatalogue c;
    c.AddTable("bekker", terramech::BuiltinBekkerSoilsCsv());
    c.AddTable("drucker-prager", rig::BuiltinFeSoilsCsv());
    c.AddTable("dem-eepa", BuiltinDemEepaSoilsCsv());
    c.AddTable("dem-hertz-mindlin", BuiltinDemHertzMindlinSoilsCsv());
    return c;
  }();
  return catalogue;
}

}  // namespace gonogo::tiers
