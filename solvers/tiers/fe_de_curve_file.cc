#include "solvers/tiers/fe_de_curve_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "solvers/common/errors.h"

namespace gonogo::tiers {
namespace {

constexpr const char* kConfigurationPrefix = "# gonogo-fe-de curve: ";
constexpr const char* kHeader =
    "slip,drawbar_pull_n,torque_nm,sinkage_m,tractive_efficiency,gross_traction_n,"
    "motion_resistance_n";

bool ParseNumber(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

}  // namespace

std::string ConfigurationNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::map<std::string, std::string> FeDeRigConfiguration(const std::string& tier_version,
                                                        const std::string& soil,
                                                        const std::string& preset,
                                                        const std::string& overrides,
                                                        const TractionRequest& request) {
  return {{"tier", tier_version},
          {"soil", soil},
          {"preset", preset},
          {"overrides", overrides},
          {"wheel_diameter_m", ConfigurationNumber(request.tyre.diameter_m)},
          {"wheel_width_m", ConfigurationNumber(request.tyre.width_m)},
          {"wheel_load_n", ConfigurationNumber(request.wheel_load_n)}};
}

std::string FeDeCurveFileText(const FeDeCurveFile& file) {
  std::string text = kConfigurationPrefix;
  bool first = true;
  for (const auto& [key, value] : file.configuration) {
    text += (first ? "" : " ") + key + "=" + value;
    first = false;
  }
  text += std::string("\n") + kHeader + "\n";
  for (const TractionPoint& p : file.points) {
    char row[256];
    std::snprintf(row, sizeof row, "%.4f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", p.slip, p.drawbar_pull_n,
                  p.torque_nm, p.sinkage_m, p.tractive_efficiency, p.gross_traction_n,
                  p.motion_resistance_n);
    text += row;
  }
  return text;
}

FeDeCurveFile ReadFeDeCurveFile(const std::string& path, const std::string& field) {
  std::ifstream in(path);
  if (!in) throw InputError(field, "cannot read '" + path + "'");
  FeDeCurveFile file;
  std::string line;
  const std::string prefix = kConfigurationPrefix;
  if (!std::getline(in, line) || line.rfind(prefix, 0) != 0) {
    const std::string reason = "' line 1: not an fe-de curve file (its first line starts '" +
                               prefix + "', as gonogo-fe-de --curve-csv writes it)";
    throw InputError(field, "'" + path + reason);
  }
  std::istringstream words(line.substr(prefix.size()));
  for (std::string word; words >> word;) {
    const std::size_t equals = word.find('=');
    if (equals == std::string::npos || equals == 0) {
      throw InputError(field, "'" + path + "' line 1: '" + word + "' is not key=value");
    }
    file.configuration[word.substr(0, equals)] = word.substr(equals + 1);
  }
  if (!std::getline(in, line) || line != kHeader) {
    throw InputError(field, "'" + path + "' line 2: the header must read " + kHeader);
  }
  for (int number = 3; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::vector<double> values;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) {
      double value = 0;
      if (!ParseNumber(cell, value)) {
        throw InputError(field, "'" + path + "' line " + std::to_string(number) + ": '" + cell +
                                    "' is not a finite number");
      }
      values.push_back(value);
    }
    if (values.size() != 7) {
      throw InputError(field, "'" + path + "' line " + std::to_string(number) +
                                  ": 7 numbers expected, found " + std::to_string(values.size()));
    }
    file.points.push_back(
        {values[0], values[1], values[2], values[3], values[4], values[5], values[6]});
  }
  if (file.points.empty()) throw InputError(field, "'" + path + "' holds no curve point");
  return file;
}

void RequireFeDeConfiguration(const FeDeCurveFile& file,
                              const std::map<std::string, std::string>& expected,
                              const std::vector<double>& slips, const std::string& field) {
  for (const auto& [key, want] : expected) {
    const auto found = file.configuration.find(key);
    if (found == file.configuration.end()) {
      throw InputError(field, "the curve file does not say its " + key);
    }
    const std::string& have = found->second;
    double a = 0, b = 0;
    const bool same = ParseNumber(have, a) && ParseNumber(want, b)
                          ? std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b))
                          : have == want;
    if (!same) {
      const std::string asked = key + "=" + want;
      throw InputError(
          field, "the curve was run with " + key + "=" + have + ", this comparison needs " + asked);
    }
  }
  bool same_slips = file.points.size() == slips.size();
  for (std::size_t k = 0; same_slips && k < slips.size(); ++k) {
    same_slips = std::abs(file.points[k].slip - slips[k]) <= 1e-9;
  }
  if (!same_slips) {
    const auto join = [](const std::vector<double>& values) {
      std::string text;
      for (double value : values) {
        char word[32];
        std::snprintf(word, sizeof word, "%s%g", text.empty() ? "" : " ", value);
        text += word;
      }
      return text;
    };
    std::vector<double> have;
    for (const TractionPoint& p : file.points) have.push_back(p.slip);
    throw InputError(field, "the curve's slips are " + join(have) + "; this comparison needs " +
                                join(slips) +
                                " (each slip a mean over a window as wide as their spacing)");
  }
}

}  // namespace gonogo::tiers
