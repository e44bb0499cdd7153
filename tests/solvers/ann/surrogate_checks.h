// Checks that every kind of stress surrogate must pass, shared by the surrogate's tests: its
// autograd tangent against central differences, the fused kernel against the TorchScript module
// and nothing at rest, saved and loaded alike in C++ and in Python's torch, and the field an
// InputError names.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "solvers/ann/stress_surrogate.h"
#include "solvers/common/errors.h"

namespace gonogo::ann::testing {

// The surrogate's tangents at the first 20 inputs against central differences of its d_sigma
// (h 1e-7): the largest difference, and in `largest_entry` the largest tangent entry.
inline double LargestTangentError(const StressSurrogate& surrogate,
                                  std::vector<SurrogateInput> inputs, double* largest_entry) {
  inputs.resize(std::min<std::size_t>(inputs.size(), 20));
  std::vector<Voigt6x6> tangents;
  surrogate.StressIncrements(inputs, &tangents);
  EXPECT_EQ(tangents.size(), inputs.size());
  const double h = 1e-7;
  double largest_error = 0;
  *largest_entry = 0;
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    for (int column = 0; column < 6; ++column) {
      SurrogateInput up = inputs[n], down = inputs[n];
      up.strain_increment[column] += h;
      down.strain_increment[column] -= h;
      const Vector6 difference =
          (surrogate.StressIncrements({up})[0] - surrogate.StressIncrements({down})[0]) / (2 * h);
      largest_error =
          std::max(largest_error, (difference - tangents[n].col(column)).cwiseAbs().maxCoeff());
      *largest_entry = std::max(*largest_entry, tangents[n].col(column).cwiseAbs().maxCoeff());
    }
  }
  return largest_error;
}

// The autograd tangent of `surrogate` on `inputs` against central differences of its answers.
inline void ExpectTangentIsItsDerivative(const StressSurrogate& surrogate,
                                         const std::vector<SurrogateInput>& inputs) {
  double largest_entry = 0;
  const double tangent_error = LargestTangentError(surrogate, inputs, &largest_entry);
  std::cout << "  " << surrogate.architecture() << " tangent: largest entry " << largest_entry
            << " Pa, " << tangent_error << " Pa from central differences\n";
  EXPECT_GT(largest_entry, 1e6);  // the soil's stiffness order (E 20 MPa)
  EXPECT_LT(tangent_error, 1e-5 * largest_entry);
}

// The fused kernel's answers against the module's on the same inputs: the largest of each and the
// largest difference (the carried increments' zero for a network that carries nothing).
struct FusedAgainstModule {
  double largest_stress = 0, stress_error = 0;
  double largest_entry = 0, tangent_error = 0;
  double largest_carried = 0, carried_error = 0;
};

inline FusedAgainstModule CompareFusedWithModule(const StressSurrogate& surrogate,
                                                 const std::vector<SurrogateInput>& inputs) {
  std::vector<Voigt6x6> fused_tangents, module_tangents;
  std::vector<Eigen::VectorXd> fused_carried, module_carried;
  const std::vector<Vector6> fused =
      surrogate.StressIncrements(inputs, &fused_tangents, &fused_carried);
  const std::vector<Vector6> module =
      surrogate.StressIncrementsByModule(inputs, &module_tangents, &module_carried);
  EXPECT_EQ(fused.size(), module.size());
  FusedAgainstModule c;
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    c.largest_stress = std::max(c.largest_stress, module[n].cwiseAbs().maxCoeff());
    c.stress_error = std::max(c.stress_error, (fused[n] - module[n]).cwiseAbs().maxCoeff());
    c.largest_entry = std::max(c.largest_entry, module_tangents[n].cwiseAbs().maxCoeff());
    c.tangent_error =
        std::max(c.tangent_error, (fused_tangents[n] - module_tangents[n]).cwiseAbs().maxCoeff());
    EXPECT_EQ(module_carried[n].size(), fused_carried[n].size());
    if (module_carried[n].size() == 0) continue;
    c.largest_carried = std::max(c.largest_carried, module_carried[n].cwiseAbs().maxCoeff());
    c.carried_error =
        std::max(c.carried_error, (fused_carried[n] - module_carried[n]).cwiseAbs().maxCoeff());
  }
  return c;
}

// The fused Eigen kernel that answers (fused_mlp.h) against the TorchScript module's forward and
// autograd on `inputs`, the same weights: equal to rounding. And the anchor: no strain, no
// stress change, by either.
inline void ExpectFusedEqualsModuleAndNothingAtRest(const StressSurrogate& surrogate,
                                                    std::vector<SurrogateInput> inputs) {
  const FusedAgainstModule c = CompareFusedWithModule(surrogate, inputs);
  std::cout << "  " << surrogate.architecture() << ", fused against module: d_sigma "
            << c.stress_error << " Pa off (largest " << c.largest_stress << " Pa), tangent "
            << c.tangent_error << " Pa off (largest " << c.largest_entry << " Pa)\n";
  EXPECT_GT(c.largest_stress, 1);
  EXPECT_LE(c.stress_error, 1e-9 * c.largest_stress);
  EXPECT_LE(c.tangent_error, 1e-9 * c.largest_entry);
  for (SurrogateInput& input : inputs) input.strain_increment.setZero();
  for (const std::vector<Vector6>& at_rest :
       {surrogate.StressIncrements(inputs), surrogate.StressIncrementsByModule(inputs)}) {
    for (const Vector6& increment : at_rest) EXPECT_EQ(increment.cwiseAbs().maxCoeff(), 0.0);
  }
}

// Python's torch (Debian's python3-torch) runs the TorchScript file `model_path` on `inputs` (their
// 18 raw columns, and the previous direction's 6 for a model that reads it, written to a CSV in
// `directory`): the largest difference of its d_sigma from
// `expected`, Pa; the architecture attribute it reads in `architecture`. Fails the test when
// Python does not run.
inline double LargestPythonDifference(const std::filesystem::path& directory,
                                      const std::string& model_path,
                                      const std::vector<SurrogateInput>& inputs,
                                      const std::vector<Vector6>& expected,
                                      std::string* architecture, bool previous_direction = false) {
  {
    std::ofstream table(directory / "inputs.csv");
    table.precision(17);
    for (const SurrogateInput& input : inputs) {
      std::string separator;
      std::vector<const Vector6*> parts = {&input.strain_increment, &input.stress_pa,
                                           &input.accumulated_strain};
      if (previous_direction) parts.push_back(&input.previous_direction);
      for (const Vector6* part : parts) {
        for (int c = 0; c < 6; ++c) {
          table << separator << (*part)[c];
          separator = ",";
        }
      }
      table << "\n";
    }
  }
  std::ofstream(directory / "run.py")
      << "import sys, numpy, torch\n"
         "model = torch.jit.load(sys.argv[1])\n"
         "x = torch.from_numpy(numpy.loadtxt(sys.argv[2], delimiter=',', ndmin=2))\n"
         "y = model(x).detach().numpy()\n"
         "numpy.savetxt(sys.argv[3], y, fmt='%.17g', delimiter=',')\n"
         "print(model.architecture)\n";
  const std::string command = "/usr/bin/python3 " + (directory / "run.py").string() + " " +
                              model_path + " " + (directory / "inputs.csv").string() + " " +
                              (directory / "outputs.csv").string() + " > " +
                              (directory / "python.out").string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream printed(directory / "python.out");
  std::getline(printed, *architecture);
  EXPECT_EQ(status, 0) << *architecture;
  std::ifstream outputs(directory / "outputs.csv");
  std::size_t rows = 0;
  double largest_difference = status == 0 ? 0 : INFINITY;
  for (std::string line; std::getline(outputs, line) && rows < inputs.size(); ++rows) {
    std::stringstream cells(line);
    std::string cell;
    for (int c = 0; c < 6 && std::getline(cells, cell, ','); ++c) {
      largest_difference =
          std::max(largest_difference, std::abs(std::stod(cell) - expected[rows][c]));
    }
  }
  EXPECT_EQ(rows, inputs.size());
  return largest_difference;
}

// `surrogate` saved as TorchScript and loaded again, in C++ and in Python's torch: its
// architecture and the same answers to the raw `inputs`.
inline void ExpectSavedAndLoadedAlikeInCppAndPython(const StressSurrogate& surrogate,
                                                    const std::vector<SurrogateInput>& inputs,
                                                    const std::string& directory_name) {
  const std::filesystem::path directory =
      std::filesystem::temp_directory_path() / (directory_name + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(directory);
  const std::string model_path = (directory / "model.pt").string();
  surrogate.Save(model_path);
  const StressSurrogate loaded = StressSurrogate::Load(model_path);
  EXPECT_EQ(loaded.architecture(), surrogate.architecture());
  const std::vector<Vector6> answers = surrogate.StressIncrements(inputs);
  const std::vector<Vector6> loaded_answers = loaded.StressIncrements(inputs);
  for (std::size_t n = 0; n < inputs.size(); ++n) EXPECT_EQ(answers[n], loaded_answers[n]) << n;
  std::string python_architecture;
  EXPECT_LT(LargestPythonDifference(directory, model_path, inputs, answers, &python_architecture,
                                    surrogate.reads_previous_direction()),
            1e-9)
      << "Pa, Python against C++";
  EXPECT_EQ(python_architecture, surrogate.architecture());
  std::filesystem::remove_all(directory);
}

// The field of the InputError `train` throws, or "(accepted)".
inline std::string RefusedField(const std::function<void()>& train) {
  try {
    train();
  } catch (const InputError& e) {
    return e.field();
  }
  return "(accepted)";
}

}  // namespace gonogo::ann::testing
