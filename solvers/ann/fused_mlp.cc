#include "solvers/ann/fused_mlp.h"

#include <cmath>

namespace gonogo::ann {

using Vector6 = Eigen::Matrix<double, 6, 1>;

namespace {

// The network's raw output for standardised inputs `h` (columns are points); `activations`
// (if given) receives each hidden layer's tanh output.
Eigen::MatrixXd Forward(const std::vector<Eigen::MatrixXd>& weights,
                        const std::vector<Eigen::VectorXd>& biases, Eigen::MatrixXd h,
                        std::vector<Eigen::MatrixXd>* activations) {
  const std::size_t layers = weights.size();
  for (std::size_t k = 0; k < layers; ++k) {
    Eigen::MatrixXd z = weights[k] * h;
    z.colwise() += biases[k];
    if (k + 1 < layers) {
      h = z.array().tanh().matrix();
      if (activations != nullptr) activations->push_back(h);
    } else {
      h = std::move(z);
    }
  }
  return h;
}

Eigen::MatrixXd Standardised(const Eigen::VectorXd& mean, const Eigen::VectorXd& scale,
                             Eigen::MatrixXd x) {
  x.colwise() -= mean;
  return scale.cwiseInverse().asDiagonal() * x;
}

// d (network output) / d (its first 6 raw inputs) of one point, by the chain rule through the
// tanh layers: W_L D_{L-1} W_{L-1} ... D_1 W_1 diag(1 / scale)[:, 0:6].
Eigen::MatrixXd InputJacobian(const std::vector<Eigen::MatrixXd>& weights,
                              const Eigen::VectorXd& in_scale,
                              const std::vector<Eigen::MatrixXd>& activations, Eigen::Index point) {
  Eigen::MatrixXd g = weights.front().leftCols(6) * in_scale.head(6).cwiseInverse().asDiagonal();
  for (std::size_t k = 0; k + 1 < weights.size(); ++k) {
    const Eigen::VectorXd slope = 1.0 - activations[k].col(point).array().square();
    g = weights[k + 1] * (slope.asDiagonal() * g);
  }
  return g;
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
  Eigen::MatrixXd y = Forward(weights, biases, Standardised(in_mean, in_scale, inputs),
                              tangents != nullptr ? &activations : nullptr);
  if (anchored) {
    Eigen::MatrixXd rest = inputs;
    rest.topRows(6).setZero();
    y -= Forward(weights, biases, Standardised(in_mean, in_scale, rest), nullptr);
    y = out_scale.asDiagonal() * y;
  } else {
    y = out_scale.asDiagonal() * y;
    y.colwise() += out_mean;
  }
  // The homogeneous term (MlpArchitecture::homogeneous_term): g M(n) in the standardised outputs'
  // units, r = sqrt(|d_eps|^2 + delta^2), g = (r - delta) / h_ref, n = d_eps / r.
  const bool hybrid = !direction_weights.empty();
  const Eigen::Index points = inputs.cols();
  Eigen::RowVectorXd radius(points);
  Eigen::MatrixXd direction_answer;
  std::vector<Eigen::MatrixXd> direction_activations;
  if (hybrid) {
    for (Eigen::Index n = 0; n < points; ++n) {
      const auto d = raw_inputs.col(n).head(6);
      radius[n] = std::sqrt(d.head(3).squaredNorm() + 0.5 * d.tail(3).squaredNorm() +
                            step_delta * step_delta);
    }
    Eigen::MatrixXd direction = inputs;
    direction.topRows(6) = raw_inputs.topRows(6) * radius.cwiseInverse().asDiagonal();
    direction_answer = Forward(direction_weights, direction_biases,
                               Standardised(direction_in_mean, direction_in_scale, direction),
                               tangents != nullptr ? &direction_activations : nullptr);
    const Eigen::RowVectorXd gain = (radius.array() - step_delta) / step_reference;
    y += out_scale.asDiagonal() * direction_answer * gain.asDiagonal();
  }
  // Scaled: the stress rows are d_sigma / s; s does not depend on d_eps, so the tangent is s
  // times the network's.
  if (scaled) y.topRows(6) = y.topRows(6) * scale.asDiagonal();
  if (tangents != nullptr) {
    tangents->assign(static_cast<std::size_t>(points), Voigt6x6::Zero());
    for (Eigen::Index n = 0; n < points; ++n) {
      // The stress rows only: a carried internal variable's increment is an output, not a stress.
      Voigt6x6 tangent = InputJacobian(weights, in_scale, activations, n).topRows(6);
      if (hybrid) {
        // d(g M(n))/d d_eps = M dg/dd^T + g dM/dn dn/dd, with dg/dd = G d / (r h_ref) and
        // dn/dd = I / r - d (G d)^T / r^3, G d the increment with its shears halved.
        const Vector6 d = raw_inputs.col(n).head(6);
        Vector6 metric_d = d;
        metric_d.tail(3) *= 0.5;
        const double r = radius[n];
        const Voigt6x6 direction_slope =
            Voigt6x6::Identity() / r - d * metric_d.transpose() / (r * r * r);
        const double gain = (r - step_delta) / step_reference;
        tangent +=
            direction_answer.col(n).head(6) * metric_d.transpose() / (r * step_reference) +
            gain *
                InputJacobian(direction_weights, direction_in_scale, direction_activations, n)
                    .topRows(6) *
                direction_slope;
      }
      (*tangents)[static_cast<std::size_t>(n)] =
          (scaled ? scale[n] : 1.0) * out_scale.head(6).asDiagonal() * tangent;
    }
  }
  return y;
}

}  // namespace gonogo::ann
