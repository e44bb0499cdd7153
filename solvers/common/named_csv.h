// Small data tables compiled into gonogo (soil libraries): CSV text with one header line, then
// one named row per line. Blank lines and lines whose first non-blank character is '#' are
// skipped. Columns: `name`, then numeric columns, then `source`, which is free text and takes the
// rest of the line (it may hold commas).
#pragma once

#include <string>
#include <vector>

namespace gonogo {

struct NamedCsvRow {
  int line = 0;                 // 1-based line in the text
  std::string name;
  std::vector<double> values;   // one per numeric column, in header order
  std::string source;
};

// `columns` is the whole expected header, "name" first and "source" last. Throws InputError with
// field "line L column C" for a bad header, a missing value, a value that is not a finite number,
// an empty source or a duplicate name (case-insensitive).
std::vector<NamedCsvRow> ParseNamedCsv(const std::string& csv_text,
                                       const std::vector<std::string>& columns);

// "line L column C", the field name of a cell.
std::string NamedCsvCell(int line, const std::string& column);

// Lower-case, trimmed form under which names are compared.
std::string NamedCsvKey(const std::string& name);

}  // namespace gonogo
