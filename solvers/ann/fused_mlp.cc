#include "solvers/ann/fused_mlp.h"

namespace gonogo::ann {

namespace {

// The network's raw output for standardised inputs `h` (columns are points); `activations`
// (if given) receives each hidden layer's tanh output.
Eigen::MatrixXd Forward(const FusedMlp& mlp, Eigen::MatrixXd h,
                        std::vector<Eigen::MatrixXd>* activations) {
  const std::size_t layers = mlp.weights.size();
  for (std::size_t k = 0; k < layers; ++k) {
    Eigen::MatrixXd z = mlp.weights[k] * h;
    z.colwise() += mlp.biases[k];
    if (k + 1 < layers) {
      h = z.array().tanh().matrix();
      if (activations != nullptr) activations->push_back(h);
    } else {
      h = std::move(z);
    }
  }
  return h;
}

Eigen::MatrixXd Standardised(const FusedMlp& mlp, Eigen::MatrixXd x) {
  x.colwise() -= mlp.in_mean;
  return mlp.in_scale.cwiseInverse().asDiagonal() * x;
}

// The pressure-scaled features of raw inputs (stress_surrogate.h, MlpArchitecture::
// pressure_reference_pa): the stress rows divided by each point's s, log(s / p_ref) appended;
// `scale` receives s per point.
Eigen::MatrixXd ScaledFeatures(const Eigen::MatrixXd& inputs, double reference_pa,
                               Eigen::RowVectorXd* scale) {
  *scale =
      ((-inputs.middleRows(6, 3).colwise().sum() / 3).array().max(0.0) + reference_pa).matrix();
  Eigen::MatrixXd features(inputs.rows() + 1, inputs.cols());
  features.topRows(inputs.rows()) = inputs;
  features.middleRows(6, 6) = inputs.middleRows(6, 6) * scale->cwiseInverse().asDiagonal();
  features.bottomRows(1) = (scale->array() / reference_pa).log().matrix();
  return features;
}

}  // namespace

Eigen::MatrixXd FusedMlp::Evaluate(const Eigen::MatrixXd& raw_inputs,
                                   std::vector<Voigt6x6>* tangents) const {
  Eigen::RowVectorXd scale;
  const bool scaled = pressure_reference_pa > 0;
  const Eigen::MatrixXd inputs =
      scaled ? ScaledFeatures(raw_inputs, pressure_reference_pa, &scale) : raw_inputs;
  std::vector<Eigen::MatrixXd> activations;
  Eigen::MatrixXd y =
      Forward(*this, Standardised(*this, inputs), tangents != nullptr ? &activations : nullptr);
  if (anchored) {
    Eigen::MatrixXd rest = inputs;
    rest.topRows(6).setZero();
    y -= Forward(*this, Standardised(*this, rest), nullptr);
    y = out_scale.asDiagonal() * y;
  } else {
    y = out_scale.asDiagonal() * y;
    y.colwise() += out_mean;
  }
  // Scaled: the stress rows are d_sigma / s; s does not depend on d_eps, so the tangent is s
  // times the network's.
  if (scaled) y.topRows(6) = y.topRows(6) * scale.asDiagonal();
  if (tangents != nullptr) {
    const Eigen::Index points = inputs.cols();
    tangents->assign(static_cast<std::size_t>(points), Voigt6x6::Zero());
    const Eigen::MatrixXd first =
        weights.front().leftCols(6) * in_scale.head(6).cwiseInverse().asDiagonal();
    for (Eigen::Index n = 0; n < points; ++n) {
      Eigen::MatrixXd g = first;  // d z_1 / d d_eps
      for (std::size_t k = 0; k + 1 < weights.size(); ++k) {
        const Eigen::VectorXd slope = 1.0 - activations[k].col(n).array().square();
        g = weights[k + 1] * (slope.asDiagonal() * g);
      }
      // The stress rows only: a carried internal variable's increment is an output, not a stress.
      (*tangents)[static_cast<std::size_t>(n)] =
          (scaled ? scale[n] : 1.0) * out_scale.head(6).asDiagonal() * g.topRows(6);
    }
  }
  return y;
}

}  // namespace gonogo::ann
