// The stress surrogate's MLP evaluated with Eigen instead of the TorchScript interpreter: the same
// weights and the same arithmetic (standardise, tanh layers, linear output, the at-rest anchor,
// back to Pa; stress_surrogate.h), batched with the points as columns, and the tangent
// d(d_sigma)/d(d_eps) by the chain rule through the layers,
//   J = diag(out_scale) W_L D_{L-1} W_{L-1} ... D_1 W_1 diag(1 / in_scale)[:, 0:6],
//   D_k = diag(1 - h_k^2),
// which is what autograd computes on the module (the anchor's at-rest branch does not depend on
// d_eps). An FE step asks for a few hundred points at a time, where the interpreter's cost per call
// is most of the work; StressSurrogate answers with this kernel and keeps the module for saving
// (tested equal to the module's answers).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "solvers/material/constitutive.h"

namespace gonogo::ann {

using material::Voigt6x6;

struct FusedMlp {
  std::vector<Eigen::MatrixXd> weights;  // layer k: outputs x inputs
  std::vector<Eigen::VectorXd> biases;
  Eigen::VectorXd in_mean, in_scale, out_mean, out_scale;
  bool anchored = true;
  // MlpArchitecture::pressure_reference_pa: > 0, the network's inputs are the raw inputs' scaled
  // features and its stress outputs (and their tangent) are multiplied back by each point's
  // s = max(p_n, 0) + p_ref (stress_surrogate.h).
  double pressure_reference_pa = 0;
  // MlpArchitecture::homogeneous_term: the second network's weights (empty: none), its inputs'
  // standardisation, h_ref and delta.
  std::vector<Eigen::MatrixXd> direction_weights;
  std::vector<Eigen::VectorXd> direction_biases;
  Eigen::VectorXd direction_in_mean, direction_in_scale;
  double step_reference = 1, step_delta = 0;

  // raw_inputs: (18 + V) x N (one point per column, V carried internal variables last; then the
  // previous direction's 6 for MlpArchitecture::previous_direction, read as the rest); returns
  // (6 + V) x N: d_sigma (Pa), then the carried variables' increments; with `tangents`, one 6 x 6
  // d(d_sigma)/d(d_eps) per point (the stress rows).
  Eigen::MatrixXd Evaluate(const Eigen::MatrixXd& raw_inputs,
                           std::vector<Voigt6x6>* tangents = nullptr) const;
};

}  // namespace gonogo::ann
