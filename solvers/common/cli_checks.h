// CLI11 checks shared by gonogo's programs (the solver tools, the benchmarks): numbers must be
// finite (CLI11 alone takes "nan" and "inf"), counts at least one. Header-only; include it only
// from a program's main file, which links CLI11::CLI11.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <limits>
#include <string>

namespace gonogo::cli_checks {

// A finite number; with `min_inclusive`, also >= that bound.
inline CLI::Validator FiniteNumber(double min_inclusive = -std::numeric_limits<double>::infinity()) {
  const bool bounded = std::isfinite(min_inclusive);
  return CLI::Validator(
      [min_inclusive, bounded](std::string& text) {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) ||
            value < min_inclusive) {
          return (bounded ? "needs a finite number >= " + CLI::detail::to_string(min_inclusive)
                          : std::string("needs a finite number")) +
                 ", got '" + text + "'";
        }
        return std::string();
      },
      bounded ? ">= " + CLI::detail::to_string(min_inclusive) : "", "FINITE");
}

// A whole count of at least one.
inline CLI::Validator AtLeastOne() {
  return CLI::Range(1, std::numeric_limits<int>::max()).description(">= 1");
}

}  // namespace gonogo::cli_checks
