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

}  // namespace

Eigen::MatrixXd FusedMlp::Evaluate(const Eigen::MatrixXd& inputs,
                                   std::vector<Voigt6x6>* tangents) const {
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
      (*tangents)[static_cast<std::size_t>(n)] = out_scale.head(6).asDiagonal() * g.topRows(6);
    }
  }
  return y;
}

}  // namespace gonogo::ann
