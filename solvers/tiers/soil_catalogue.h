// The soil catalogue: every named soil gonogo ships, with a parameter set per soil model it has
// been calibrated for, each with its source. Assembled from the compiled-in tables, one per model,
// whose columns are the model's declared parameter names (solvers/common/soil_model.cc):
//
//   model               table                                        read by
//   bekker              solvers/terramech/data/bekker_soils.csv      the bekker tier
//   drucker-prager      solvers/rig/data/fe_soils.csv                the fe-classic tier
//   dem-eepa            solvers/tiers/data/dem_eepa_soils.csv        (the dem tier, to come)
//   dem-hertz-mindlin   solvers/tiers/data/dem_hertz_mindlin_soils.csv (the fe-de tier, to come)
//
// Every set is validated against its model's declaration when the catalogue is built, so a table
// that drifts from its model fails the build's tests, not a user's request.
#pragma once

#include <string>
#include <vector>

#include "solvers/common/soil_model.h"

namespace gonogo::tiers {

struct CatalogueEntry {
  std::string soil;           // as written in its table
  SoilParameters parameters;  // validated, defaults filled
  std::string source;
};

class SoilCatalogue {
 public:
  // Rows of a table whose header is `name`, the parameters of `model` (any order, each at most
  // once; missing ones take the model's default), then `source`. Throws InputError naming
  // "<model> table line L column C" for a bad cell and the parameter for a value out of range.
  void AddTable(const std::string& model, const std::string& csv_text);

  // Case-insensitive; nullptr when the soil has no set of that model.
  const CatalogueEntry* Find(const std::string& soil, const std::string& model) const;
  std::vector<std::string> Names() const;  // sorted, as written
  std::vector<std::string> ModelsOf(const std::string& soil) const;
  const std::vector<CatalogueEntry>& Entries() const { return entries_; }

 private:
  std::vector<CatalogueEntry> entries_;
};

// The four built-in tables; built once, thread-safe.
const SoilCatalogue& BuiltinSoilCatalogue();

}  // namespace gonogo::tiers
