#include "solvers/common/named_csv.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>

#include "solvers/common/errors.h"

namespace gonogo {
namespace {

std::string Trim(const std::string& s) {
  size_t begin = 0, end = s.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(s[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(s[end - 1]))) --end;
  return s.substr(begin, end - begin);
}

// The first `count - 1` comma-separated fields, and the rest of the line as the last.
std::vector<std::string> SplitRow(const std::string& line, size_t count) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (fields.size() + 1 < count) {
    const size_t comma = line.find(',', start);
    if (comma == std::string::npos) break;
    fields.push_back(Trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
  fields.push_back(Trim(line.substr(start)));
  return fields;
}

double ParseNumber(const std::string& text, int line, const std::string& column) {
  Require(!text.empty(), NamedCsvCell(line, column), "missing value");
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  Require(end == text.c_str() + text.size() && errno == 0 && std::isfinite(v),
          NamedCsvCell(line, column), "not a finite number: '" + text + "'");
  return v;
}

}  // namespace

std::string NamedCsvCell(int line, const std::string& column) {
  return "line " + std::to_string(line) + " column " + column;
}

std::string NamedCsvKey(const std::string& name) {
  std::string s = Trim(name);
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<NamedCsvRow> ParseNamedCsv(const std::string& csv_text,
                                       const std::vector<std::string>& columns) {
  const size_t count = columns.size();
  std::string header_text;
  for (size_t c = 0; c < count; ++c) header_text += (c ? "," : "") + columns[c];
  std::vector<NamedCsvRow> rows;
  std::set<std::string> names;
  std::istringstream in(csv_text);
  std::string raw;
  bool header_seen = false;
  for (int line = 1; std::getline(in, raw); ++line) {
    const std::string text = Trim(raw);
    if (text.empty() || text[0] == '#') continue;
    const std::vector<std::string> fields = SplitRow(text, count);
    if (!header_seen) {
      for (size_t c = 0; c < count; ++c) {
        const std::string got = c < fields.size() ? fields[c] : "";
        Require(got == columns[c], NamedCsvCell(line, columns[c]),
                "header must read " + header_text + " (got '" + got + "')");
      }
      header_seen = true;
      continue;
    }
    if (fields.size() < count) {
      throw InputError(NamedCsvCell(line, columns[fields.size()]),
                       "missing value: a row has " + std::to_string(count) + " columns");
    }
    NamedCsvRow row;
    row.line = line;
    row.name = fields[0];
    Require(!row.name.empty(), NamedCsvCell(line, "name"), "missing value");
    Require(names.insert(NamedCsvKey(row.name)).second, NamedCsvCell(line, "name"),
            "duplicate soil name '" + row.name + "'");
    for (size_t c = 1; c + 1 < count; ++c) {
      row.values.push_back(ParseNumber(fields[c], line, columns[c]));
    }
    row.source = fields[count - 1];
    Require(!row.source.empty(), NamedCsvCell(line, "source"), "every soil names its source");
    rows.push_back(std::move(row));
  }
  Require(header_seen, NamedCsvCell(1, "name"), "no header line: the library is empty");
  return rows;
}

}  // namespace gonogo
