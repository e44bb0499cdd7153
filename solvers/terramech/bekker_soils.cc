#include "solvers/terramech/bekker_soils.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "solvers/common/errors.h"

namespace gonogo::terramech {

namespace {

constexpr int kColumnCount = 8;
const char* const kColumns[kColumnCount] = {
    "name",  "n", "kc", "kphi", "cohesion_pa", "friction_angle_deg", "shear_deformation_m",
    "source"};

std::string Trim(const std::string& s) {
  size_t begin = 0, end = s.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(s[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(s[end - 1]))) --end;
  return s.substr(begin, end - begin);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Where(int line, const std::string& column) {
  return "line " + std::to_string(line) + " column " + column;
}

// The first seven comma-separated fields, and the rest of the line as the eighth (source).
std::vector<std::string> SplitRow(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (static_cast<int>(fields.size()) < kColumnCount - 1) {
    const size_t comma = line.find(',', start);
    if (comma == std::string::npos) break;
    fields.push_back(Trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
  fields.push_back(Trim(line.substr(start)));
  return fields;
}

double ParseNumber(const std::string& text, int line, const std::string& column) {
  Require(!text.empty(), Where(line, column), "missing value");
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  Require(end == text.c_str() + text.size() && errno == 0 && std::isfinite(v), Where(line, column),
          "not a finite number: '" + text + "'");
  return v;
}

}  // namespace

BekkerSoilLibrary BekkerSoilLibrary::Parse(const std::string& csv_text) {
  BekkerSoilLibrary library;
  std::istringstream in(csv_text);
  std::string raw;
  bool header_seen = false;
  for (int line = 1; std::getline(in, raw); ++line) {
    const std::string text = Trim(raw);
    if (text.empty() || text[0] == '#') continue;
    const std::vector<std::string> fields = SplitRow(text);
    if (!header_seen) {
      for (int c = 0; c < kColumnCount; ++c) {
        const std::string got = c < static_cast<int>(fields.size()) ? fields[c] : "";
        Require(got == kColumns[c], Where(line, kColumns[c]),
                "header must read name,n,kc,kphi,cohesion_pa,friction_angle_deg,"
                "shear_deformation_m,source (got '" +
                    got + "')");
      }
      header_seen = true;
      continue;
    }
    if (static_cast<int>(fields.size()) < kColumnCount) {
      throw InputError(Where(line, kColumns[fields.size()]), "missing value: a row has 8 columns");
    }
    BekkerSoil soil;
    soil.name = fields[0];
    Require(!soil.name.empty(), Where(line, "name"), "missing value");
    Require(library.Find(soil.name) == nullptr, Where(line, "name"),
            "duplicate soil name '" + soil.name + "'");
    BekkerParameters& p = soil.parameters;
    p.n = ParseNumber(fields[1], line, "n");
    p.kc = ParseNumber(fields[2], line, "kc");
    p.kphi = ParseNumber(fields[3], line, "kphi");
    p.cohesion_pa = ParseNumber(fields[4], line, "cohesion_pa");
    p.friction_angle_deg = ParseNumber(fields[5], line, "friction_angle_deg");
    p.shear_deformation_m = ParseNumber(fields[6], line, "shear_deformation_m");
    soil.source = fields[7];
    Require(!soil.source.empty(), Where(line, "source"), "every soil names its source");
    // Validate names its field ("n", "kc", ...): report it as this row's column.
    try {
      p.Validate("");
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw InputError(Where(line, e.field()), what.substr(e.field().size() + 2));
    }
    library.soils_.push_back(std::move(soil));
  }
  Require(header_seen, "line 1 column name", "no header line: the library is empty");
  return library;
}

const BekkerSoilLibrary& BekkerSoilLibrary::Builtin() {
  static const BekkerSoilLibrary builtin = Parse(BuiltinBekkerSoilsCsv());
  return builtin;
}

const BekkerSoil* BekkerSoilLibrary::Find(const std::string& name) const {
  const std::string key = Lower(Trim(name));
  for (const BekkerSoil& soil : soils_) {
    if (Lower(soil.name) == key) return &soil;
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
