// A library of named Bekker-Janosi soil parameter sets, read from CSV text. The built-in library is
// solvers/terramech/data/bekker_soils.csv, compiled into the binary at build time (CMake generates
// a .cc holding its text), so no file is read at run time.
//
// CSV format: one header line, then one soil per line. Blank lines and lines whose first
// non-blank character is '#' are skipped. Columns, SI units:
//   name,n,kc,kphi,cohesion_pa,friction_angle_deg,shear_deformation_m,source
//   n -, kc N/m^(n+1), kphi N/m^(n+2), c Pa, phi degrees, K m; source is free text and is the
//   rest of the line (it may hold commas).
// Names are matched case-insensitively and must be unique; every row must pass
// BekkerParameters::Validate.
#pragma once

#include <string>
#include <vector>

#include "solvers/common/traction.h"

namespace gonogo::terramech {

struct BekkerSoil {
  std::string name;
  BekkerParameters parameters;
  std::string source;  // publication and table the numbers come from
};

class BekkerSoilLibrary {
 public:
  // Throws InputError with field "line L column C" (C the column name) for a bad header, a
  // missing or extra value, a value that is not a finite number, parameters that fail
  // validation (the column of the failing parameter) or a duplicate name.
  static BekkerSoilLibrary Parse(const std::string& csv_text);

  // The library compiled from data/bekker_soils.csv; parsed once, thread-safe.
  static const BekkerSoilLibrary& Builtin();

  // nullptr when no soil has that name (case-insensitive).
  const BekkerSoil* Find(const std::string& name) const;
  // Names in file order.
  std::vector<std::string> Names() const;
  const std::vector<BekkerSoil>& Soils() const { return soils_; }

 private:
  std::vector<BekkerSoil> soils_;
};

// The text of data/bekker_soils.csv (defined in the .cc that CMake generates from it).
const char* BuiltinBekkerSoilsCsv();

}  // namespace gonogo::terramech
