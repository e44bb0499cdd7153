// The continuum soils of the fe-classic tier: density, elastic and Drucker-Prager strength
// parameters, each row with its sources. The built-in library is solvers/rig/data/fe_soils.csv,
// compiled in (no file is read at run time).
//
// CSV columns (solvers/common/named_csv.h):
//   name,density_kg_m3,young_pa,poisson,cohesion_pa,friction_angle_deg,dilation_angle_deg,source
#pragma once

#include <string>
#include <vector>

#include "solvers/material/drucker_prager.h"

namespace gonogo::rig {

struct FeSoil {
  std::string name;
  double density_kg_m3 = 0;
  material::DruckerPragerParams strength;  // E, nu, c, phi, psi; matched in triaxial compression
  std::string source;

  void Validate(const std::string& field_prefix) const;
};

class FeSoilLibrary {
 public:
  // Throws InputError naming "line L column C" for a malformed row or a row that fails
  // validation.
  static FeSoilLibrary Parse(const std::string& csv_text);
  static const FeSoilLibrary& Builtin();

  const FeSoil* Find(const std::string& name) const;  // case-insensitive; nullptr if unknown
  std::vector<std::string> Names() const;

 private:
  std::vector<FeSoil> soils_;
};

const char* BuiltinFeSoilsCsv();

}  // namespace gonogo::rig
