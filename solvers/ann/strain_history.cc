#include "solvers/ann/strain_history.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <random>
#include <stdexcept>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"

namespace gonogo::ann {
namespace {

constexpr char kHistoryTag[9] = "GNGHIS01";
constexpr char kHistoryTagWithInitialVariables[9] = "GNGHIS02";

void RequireHistory(bool condition, const std::string& reason) {
  if (!condition) throw InputError("history", reason);
}

std::vector<std::vector<double>> Rows(const std::vector<StrainHistory>& histories) {
  std::vector<std::vector<double>> rows;
  for (std::size_t h = 0; h < histories.size(); ++h) {
    const StrainHistory& history = histories[h];
    if (history.internal_variable_names != histories.front().internal_variable_names) {
      throw InputError("histories", "history " + std::to_string(h) +
                                        " carries other internal variables than history 0");
    }
    for (std::size_t s = 0; s < history.steps(); ++s) {
      std::vector<double> row = {static_cast<double>(h), static_cast<double>(s)};
      const Matrix3& dh = history.increments[s];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) row.push_back(dh(i, j));
      }
      for (int c = 0; c < 6; ++c) row.push_back(history.stresses_pa[s][c]);
      if (!history.internal_variable_names.empty()) {
        row.insert(row.end(), history.internal_variables[s].begin(),
                   history.internal_variables[s].end());
      }
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

void WriteAll(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace

std::string SerializeHistory(const StrainHistory& history) {
  const std::size_t variables = history.internal_variable_names.size();
  RequireHistory(history.stresses_pa.size() == history.steps(),
                 "one stress per step is needed");
  RequireHistory(variables == 0 || history.internal_variables.size() == history.steps(),
                 "one set of internal variables per step is needed");
  const bool with_initial = !history.initial_internal_variables.empty();
  RequireHistory(!with_initial || history.initial_internal_variables.size() == variables,
                 "the initial internal variables must be one per name");
  ByteWriter out;
  out.PutTag(with_initial ? kHistoryTagWithInitialVariables : kHistoryTag);
  out.Put(history.initial_stress_pa);
  out.Put(static_cast<std::uint64_t>(variables));
  for (const std::string& name : history.internal_variable_names) out.PutBlob(name);
  for (double value : history.initial_internal_variables) out.Put(value);
  out.PutBlob(history.stopped_reason);
  out.Put(static_cast<std::uint64_t>(history.steps()));
  for (std::size_t s = 0; s < history.steps(); ++s) {
    out.Put(history.increments[s]);
    for (int c = 0; c < 6; ++c) out.Put(history.stresses_pa[s][c]);
    if (variables == 0) continue;
    RequireHistory(history.internal_variables[s].size() == variables,
                   "step " + std::to_string(s) + " has the wrong number of internal variables");
    for (double value : history.internal_variables[s]) out.Put(value);
  }
  return out.Take();
}

StrainHistory ParseHistory(const std::string& bytes) {
  try {
    ByteReader in(bytes);
    const bool with_initial = bytes.compare(0, 8, kHistoryTagWithInitialVariables) == 0;
    in.ExpectTag(with_initial ? kHistoryTagWithInitialVariables : kHistoryTag);
    StrainHistory history;
    in.Get(history.initial_stress_pa);
    std::uint64_t variables = 0;
    in.Get(variables);
    RequireHistory(variables < 1000, "implausible internal-variable count");
    history.internal_variable_names.resize(variables);
    for (std::string& name : history.internal_variable_names) in.GetBlob(name);
    if (with_initial) {
      history.initial_internal_variables.resize(variables);
      for (double& value : history.initial_internal_variables) in.Get(value);
    }
    in.GetBlob(history.stopped_reason);
    std::uint64_t steps = 0;
    in.Get(steps);
    const std::uint64_t per_step = 8 * (9 + 6 + variables);
    RequireHistory(steps <= bytes.size() / per_step, "step count larger than the buffer holds");
    history.increments.resize(steps);
    history.stresses_pa.resize(steps);
    if (variables > 0) history.internal_variables.assign(steps, std::vector<double>(variables));
    for (std::uint64_t s = 0; s < steps; ++s) {
      in.Get(history.increments[s]);
      for (int c = 0; c < 6; ++c) in.Get(history.stresses_pa[s][c]);
      for (std::uint64_t v = 0; v < variables; ++v) in.Get(history.internal_variables[s][v]);
    }
    RequireHistory(in.AtEnd(), "trailing bytes after the last step");
    return history;
  } catch (const InputError& e) {
    if (e.field() == "history") throw;
    throw InputError("history", e.what());
  }
}

std::vector<std::string> HistoryColumns(const std::vector<std::string>& internal_variable_names) {
  std::vector<std::string> columns = {"history", "step"};
  const char* axes = "xyz";
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) columns.push_back(std::string("dH_") + axes[i] + axes[j]);
  }
  for (const char* name : {"sigma_xx_pa", "sigma_yy_pa", "sigma_zz_pa", "sigma_yz_pa",
                           "sigma_xz_pa", "sigma_xy_pa"}) {
    columns.push_back(name);
  }
  columns.insert(columns.end(), internal_variable_names.begin(), internal_variable_names.end());
  return columns;
}

void WriteHistoriesNpy(const std::string& path, const std::vector<StrainHistory>& histories) {
  const std::vector<std::string> columns = HistoryColumns(
      histories.empty() ? std::vector<std::string>{} : histories.front().internal_variable_names);
  const std::vector<std::vector<double>> rows = Rows(histories);
  // NPY format 1.0: magic, version, little-endian header length, a Python dict literal padded
  // with spaces and ended by a newline so that the data starts on a 64-byte boundary.
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" +
                       std::to_string(rows.size()) + ", " + std::to_string(columns.size()) +
                       "), }";
  const std::size_t preamble = 10;
  const std::size_t total = (preamble + header.size() + 1 + 63) / 64 * 64;
  header.append(total - preamble - header.size() - 1, ' ');
  header += '\n';
  std::string bytes = "\x93NUMPY";
  bytes += '\x01';
  bytes += '\x00';
  bytes += static_cast<char>(header.size() & 0xff);
  bytes += static_cast<char>((header.size() >> 8) & 0xff);
  bytes += header;
  ByteWriter data;
  for (const std::vector<double>& row : rows) {
    for (double value : row) data.Put(value);
  }
  bytes += data.Take();
  WriteAll(path, bytes);
  std::string names;
  for (const std::string& column : columns) names += column + "\n";
  WriteAll(path + ".columns.txt", names);
}

void WriteHistoriesCsv(const std::string& path, const std::vector<StrainHistory>& histories) {
  const std::vector<std::string> columns = HistoryColumns(
      histories.empty() ? std::vector<std::string>{} : histories.front().internal_variable_names);
  std::string text;
  for (std::size_t c = 0; c < columns.size(); ++c) text += (c ? "," : "") + columns[c];
  text += "\n";
  char number[32];
  for (const std::vector<double>& row : Rows(histories)) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      std::snprintf(number, sizeof(number), c < 2 ? "%.0f" : "%.17g", row[c]);
      text += (c ? "," : "") + std::string(number);
    }
    text += "\n";
  }
  WriteAll(path, text);
}

StrainHistory Rotated(const StrainHistory& history, const Matrix3& rotation) {
  StrainHistory rotated = history;
  const auto turn = [&](const Matrix3& tensor) -> Matrix3 {
    return rotation * tensor * rotation.transpose();
  };
  rotated.initial_stress_pa = turn(history.initial_stress_pa);
  for (Matrix3& increment : rotated.increments) increment = turn(increment);
  for (Vector6& stress : rotated.stresses_pa) {
    stress = material::StressToVoigt(turn(material::VoigtToStress(stress)));
  }
  // A tensor recorded as six internal variables <name>_xx ... <name>_xy (a fabric) turns as the
  // stress does; the others are scalars of the state and stay.
  const std::vector<std::string>& names = history.internal_variable_names;
  static const char* const kComponents[6] = {"_xx", "_yy", "_zz", "_yz", "_xz", "_xy"};
  for (const std::string& name : names) {
    if (name.size() < 3 || name.compare(name.size() - 3, 3, "_xx") != 0) continue;
    const std::string base = name.substr(0, name.size() - 3);
    std::array<std::size_t, 6> column{};
    bool whole = true;
    for (int c = 0; c < 6 && whole; ++c) {
      const auto found = std::find(names.begin(), names.end(), base + kComponents[c]);
      whole = found != names.end();
      column[c] = static_cast<std::size_t>(found - names.begin());
    }
    if (!whole) continue;
    std::vector<std::vector<double>*> states;
    for (std::vector<double>& values : rotated.internal_variables) states.push_back(&values);
    if (!rotated.initial_internal_variables.empty()) {
      states.push_back(&rotated.initial_internal_variables);
    }
    for (std::vector<double>* state : states) {
      std::vector<double>& values = *state;
      Vector6 tensor;
      for (int c = 0; c < 6; ++c) tensor[c] = values.at(column[c]);
      tensor = material::StressToVoigt(turn(material::VoigtToStress(tensor)));
      for (int c = 0; c < 6; ++c) values[column[c]] = tensor[c];
    }
  }
  return rotated;
}

std::vector<StrainHistory> WithRotatedCopies(const std::vector<StrainHistory>& histories,
                                             int copies, std::uint64_t seed) {
  if (copies < 0 || copies > 64) throw InputError("rotated_copies", "must be in [0, 64]");
  std::vector<StrainHistory> augmented = histories;
  augmented.reserve(histories.size() * static_cast<std::size_t>(copies + 1));
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int copy = 0; copy < copies; ++copy) {
    for (const StrainHistory& history : histories) {
      Eigen::Quaterniond turn(normal(random), normal(random), normal(random), normal(random));
      turn.normalize();  // a normalised 4-D Gaussian: uniform on the rotations
      augmented.push_back(Rotated(history, turn.toRotationMatrix()));
    }
  }
  return augmented;
}

}  // namespace gonogo::ann
