// The only translation unit that includes libtorch (a <torch/torch.h> unit compiles for about
// 30 s here; PLATFORM-NOTES).
#include "solvers/ann/stress_surrogate.h"

#include <torch/script.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "solvers/ann/fused_mlp.h"
#include "solvers/common/errors.h"

namespace gonogo::ann {
namespace {

constexpr int kInputs = 18;  // without carried internal variables
constexpr int kOutputs = 6;  // d_sigma; the carried variables' increments follow
// MlpArchitecture::homogeneous_term's delta: far below an FE point's increment (2e-6 on the rig).
constexpr double kStepDelta = 1e-7;

std::string Joined(const std::vector<std::string>& names, const std::string& separator) {
  std::string joined;
  for (std::size_t k = 0; k < names.size(); ++k) joined += (k ? separator : "") + names[k];
  return joined;
}

// Every input carries `carried` internal variables; InputError("inputs", ...) otherwise.
void RequireCarried(const std::vector<SurrogateInput>& inputs,
                    const std::vector<std::string>& carried) {
  for (const SurrogateInput& input : inputs) {
    if (input.internal_variables.size() != static_cast<Eigen::Index>(carried.size())) {
      throw InputError("inputs", "each point must carry the network's " +
                                     std::to_string(carried.size()) + " internal variables (" +
                                     Joined(carried, ", ") + "), one carries " +
                                     std::to_string(input.internal_variables.size()));
    }
  }
}

// The raw inputs, one row per point: [d_eps, sigma_n, eps_n, the carried internal variables]
// (18 + V columns), then the previous step's direction with `previous_direction` (24 + V), or
// [d_eps, sigma_n] (12, the recurrent surrogate's, whose hidden state stands in for the rest).
torch::Tensor InputTensor(const std::vector<SurrogateInput>& inputs, bool previous_direction,
                          bool recurrent = false) {
  const int carried =
      recurrent || inputs.empty() ? 0 : static_cast<int>(inputs.front().internal_variables.size());
  const int columns = recurrent ? 12 : kInputs + carried + (previous_direction ? 6 : 0);
  torch::Tensor x = torch::empty({static_cast<std::int64_t>(inputs.size()), columns},
                                 torch::kFloat64);
  double* data = x.data_ptr<double>();
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    for (int c = 0; c < 6; ++c) {
      data[n * columns + c] = inputs[n].strain_increment[c];
      data[n * columns + 6 + c] = inputs[n].stress_pa[c];
      if (!recurrent) data[n * columns + 12 + c] = inputs[n].accumulated_strain[c];
    }
    for (int v = 0; v < carried; ++v) data[n * columns + kInputs + v] = inputs[n].internal_variables[v];
    for (int c = 0; c < 6 && previous_direction; ++c) {
      data[n * columns + kInputs + carried + c] = inputs[n].previous_direction[c];
    }
  }
  return x;
}

// Each carried variable's column in the history's internal variables; InputError("histories", ...)
// when the history does not record it, or not its initial value.
std::vector<std::size_t> CarriedColumns(const StrainHistory& history,
                                        const std::vector<std::string>& carried) {
  std::vector<std::size_t> columns;
  const std::vector<std::string>& names = history.internal_variable_names;
  for (const std::string& name : carried) {
    const auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end()) {
      throw InputError("histories", "a history does not record the carried internal variable '" +
                                        name + "' (record the RVE's: gonogo-ann --record-fabric)");
    }
    columns.push_back(static_cast<std::size_t>(found - names.begin()));
  }
  if (!carried.empty() && history.initial_internal_variables.size() != names.size()) {
    throw InputError("histories", "a history does not record its initial internal variables "
                                  "(recorded before they were), so a network cannot carry them");
  }
  return columns;
}

// The carried variables of the state before step `step` (0: the path's start).
Eigen::VectorXd CarriedBefore(const StrainHistory& history, const std::vector<std::size_t>& columns,
                              std::size_t step) {
  if (columns.empty()) return Eigen::VectorXd();
  const std::vector<double>& values =
      step == 0 ? history.initial_internal_variables : history.internal_variables[step - 1];
  Eigen::VectorXd carried(static_cast<Eigen::Index>(columns.size()));
  for (std::size_t v = 0; v < columns.size(); ++v) carried[v] = values.at(columns[v]);
  return carried;
}

// Adam's learning rate halved at 50, 75 and 90 % of the epochs.
void HalveLearningRateAtMilestones(torch::optim::Adam& optimizer, int epoch, int epochs) {
  for (double milestone : {0.5, 0.75, 0.9}) {
    if (epoch == static_cast<int>(milestone * epochs) && epoch > 0) {
      for (auto& group : optimizer.param_groups()) {
        auto& adam = static_cast<torch::optim::AdamOptions&>(group.options());
        adam.lr(adam.lr() * 0.5);
      }
    }
  }
}

void SaveModule(torch::jit::Module& module, const std::string& path) {
  try {
    module.save(path);
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot write the surrogate to " + path + ": " +
                             e.what_without_backtrace());
  }
}

// The loss weight of each step: its history's weight (TrainingOptions::history_weights) times its
// path's mean |sigma| to the power -2 x (TrainingOptions::path_stress_weighting), scaled to
// average 1; undefined when every step weighs alike. Paths at rest (mean |sigma| under 1 Pa) are
// weighed as at 1 Pa.
torch::Tensor StepWeights(const std::vector<double>& path_stress_pa,
                          const std::vector<double>& history_weight,
                          const TrainingOptions& options) {
  if (options.path_stress_weighting == 0 && options.history_weights.empty()) return {};
  torch::Tensor weights =
      torch::empty({static_cast<std::int64_t>(path_stress_pa.size())}, torch::kFloat64);
  double* data = weights.data_ptr<double>();
  for (std::size_t n = 0; n < path_stress_pa.size(); ++n) {
    data[n] = history_weight[n] *
              std::pow(std::max(path_stress_pa[n], 1.0), -2 * options.path_stress_weighting);
  }
  return weights / weights.mean();
}

// The map of a stress's Voigt components under the rotation R (sigma -> R sigma R^T), as a matrix.
Eigen::Matrix<double, 6, 6> StressRotationMap(const Matrix3& rotation) {
  Eigen::Matrix<double, 6, 6> map;
  for (int j = 0; j < 6; ++j) {
    const Matrix3 unit = material::VoigtToStress(Vector6::Unit(j));
    map.col(j) = material::StressToVoigt(rotation * unit * rotation.transpose());
  }
  return map;
}

// What the rollout term of the loss (TrainingOptions::rollout_steps) replays windows with: per
// sample, its step's stress rotation map, the recorded stress and carried variables after it,
// and its path's mean |sigma|; and the first sample of every window of K steps in one history.
// The training noise (TrainingOptions::stress_noise) takes the rotation maps and the paths' mean
// |sigma| alone.
struct RolloutData {
  torch::Tensor rotation_maps;   // (N, 6, 6)
  torch::Tensor stress_after;    // (N, 6), Pa
  torch::Tensor carried_after;   // (N, V)
  torch::Tensor path_stress_pa;  // (N, 1), at least 1 Pa
  torch::Tensor window_starts;   // (W)
  torch::Tensor window_weights;  // (W): 1 / its history's windows, so every history alike
};

// Column means and standard deviations; a constant column gets scale 1 (it carries nothing).
std::pair<torch::Tensor, torch::Tensor> Standardisation(const torch::Tensor& values) {
  torch::Tensor mean = values.mean(0);
  torch::Tensor scale = values.std(0, /*unbiased=*/false);
  scale = torch::where(scale > 1e-12 * (mean.abs() + 1e-300), scale, torch::ones_like(scale));
  return {mean, scale};
}

// Each point's s = max(p_n, 0) + p_ref of a block of stresses (N, 6; Pa, tension positive), as
// (N, 1) (MlpArchitecture::pressure_reference_pa).
torch::Tensor PressureScale(const torch::Tensor& stress_pa, double reference_pa) {
  return (-stress_pa.slice(1, 0, 3).sum(1, /*keepdim=*/true) / 3).clamp_min(0) + reference_pa;
}

// What the network sees of raw input rows (N, 18 + V, or 24 + V with the previous direction): the
// rows themselves unscaled; scaled (reference_pa > 0), the stress columns over s and log(s / p_ref)
// appended (one column more).
torch::Tensor Features(const torch::Tensor& raw, double reference_pa) {
  if (reference_pa <= 0) return raw;
  const torch::Tensor scale = PressureScale(raw.slice(1, 6, 12), reference_pa);
  return torch::cat({raw.slice(1, 0, 6), raw.slice(1, 6, 12) / scale, raw.slice(1, 12),
                     torch::log(scale / reference_pa)},
                    1);
}

// r = sqrt(|d_eps|^2 + delta^2) of raw input rows, (N, 1); |d_eps|^2 the normal components'
// squares plus half the engineering shears' (MlpArchitecture::homogeneous_term).
torch::Tensor IncrementRadius(const torch::Tensor& raw, double delta) {
  return (raw.slice(1, 0, 3).pow(2).sum(1, /*keepdim=*/true) +
          0.5 * raw.slice(1, 3, 6).pow(2).sum(1, /*keepdim=*/true) + delta * delta)
      .sqrt();
}

// What the homogeneous term's network sees: Features with the increment's direction d_eps / r in
// place of the increment.
torch::Tensor DirectionFeatures(const torch::Tensor& raw, double reference_pa, double delta) {
  return torch::cat(
      {raw.slice(1, 0, 6) / IncrementRadius(raw, delta), Features(raw, reference_pa).slice(1, 6)},
      1);
}

// tanh layers of `hidden_widths` from `inputs` columns and a linear layer to `outputs`, in
// double precision; the linear layers in `layers`, in order.
torch::nn::Sequential TanhNetwork(int inputs, const std::vector<int>& hidden_widths, int outputs,
                                  std::vector<torch::nn::Linear>* layers) {
  torch::nn::Sequential network;
  int width = inputs;
  for (int hidden : hidden_widths) {
    layers->push_back(torch::nn::Linear(width, hidden));
    network->push_back(layers->back());
    network->push_back(torch::nn::Tanh());
    width = hidden;
  }
  layers->push_back(torch::nn::Linear(width, outputs));
  network->push_back(layers->back());
  network->to(torch::kFloat64);
  return network;
}

// Registers a tanh network's layers in `module` as <weight_prefix>k, <bias_prefix>k and writes
// its TorchScript method `name`: standardised by the buffers <standardisation>mean and
// <standardisation>scale, the tanh layers, the linear output.
void AddNetworkMethod(torch::jit::Module& module, std::ostringstream& source,
                      const std::string& name, const std::string& standardisation,
                      const std::string& weight_prefix, const std::string& bias_prefix,
                      const std::vector<torch::Tensor>& weights,
                      const std::vector<torch::Tensor>& biases) {
  source << "def " << name << "(self, x):\n"
         << "    h = (x - self." << standardisation << "mean) / self." << standardisation
         << "scale\n";
  for (std::size_t layer = 0; layer < weights.size(); ++layer) {
    const std::string w = weight_prefix + std::to_string(layer);
    const std::string b = bias_prefix + std::to_string(layer);
    module.register_parameter(w, weights[layer].detach().clone(), false);
    module.register_parameter(b, biases[layer].detach().clone(), false);
    const bool last = layer + 1 == weights.size();
    source << "    h = " << (last ? "" : "torch.tanh(") << "torch.matmul(h, self." << w
           << ".t()) + self." << b << (last ? "" : ")") << "\n";
  }
  source << "    return h\n";
}

// The homogeneous term's second network, for ScriptModule (empty weights: none).
struct DirectionNetwork {
  std::vector<torch::Tensor> weights, biases;
  torch::Tensor in_mean, in_scale;
  double step_reference = 1;
};

// The TorchScript module: standardise, the tanh layers, the linear output, back to Pa. Anchored:
// the same network at rest (the strain increment zeroed) subtracted, so that d_sigma(0) = 0.
// Pressure-scaled (reference_pa > 0): the network sees Features and its stress outputs are
// multiplied by s; the module still takes raw inputs and answers raw outputs.
torch::jit::Module ScriptModule(const std::vector<torch::Tensor>& weights,
                                const std::vector<torch::Tensor>& biases,
                                const torch::Tensor& in_mean, const torch::Tensor& in_scale,
                                const torch::Tensor& out_mean, const torch::Tensor& out_scale,
                                const std::string& architecture, bool anchored,
                                const std::vector<std::string>& carried, double reference_pa,
                                bool previous_direction, const DirectionNetwork& direction = {}) {
  torch::jit::Module module("StressSurrogate");
  module.register_attribute("carried_variables", c10::StringType::get(), Joined(carried, ","));
  // MlpArchitecture::previous_direction: the raw rows end with its 6 columns (forward and the
  // networks read them as they read the carried variables, among the columns after 12).
  module.register_attribute("previous_direction", c10::BoolType::get(), previous_direction);
  module.register_buffer("in_mean", in_mean.detach().clone());
  module.register_buffer("in_scale", in_scale.detach().clone());
  module.register_buffer("out_mean", out_mean.detach().clone());
  module.register_buffer("out_scale", out_scale.detach().clone());
  module.register_attribute("architecture", c10::StringType::get(), architecture);
  std::ostringstream source;
  AddNetworkMethod(module, source, "network", "in_", "w", "b", weights, biases);
  const bool hybrid = !direction.weights.empty();
  if (hybrid) {
    module.register_buffer("direction_in_mean", direction.in_mean.detach().clone());
    module.register_buffer("direction_in_scale", direction.in_scale.detach().clone());
    module.register_attribute("step_reference", c10::FloatType::get(), direction.step_reference);
    module.register_attribute("step_delta", c10::FloatType::get(), kStepDelta);
    AddNetworkMethod(module, source, "direction_network", "direction_in_", "v", "c",
                     direction.weights, direction.biases);
  }
  const bool scaled = reference_pa > 0;
  if (scaled) {
    module.register_attribute("pressure_reference_pa", c10::FloatType::get(), reference_pa);
    source << "def scale(self, x):\n"
           << "    return torch.clamp(-(x[:, 6:7] + x[:, 7:8] + x[:, 8:9]) / 3, min=0.0) + "
              "self.pressure_reference_pa\n"
           << "def forward(self, raw):\n"
           << "    s = self.scale(raw)\n"
           << "    x = torch.cat([raw[:, 0:6], raw[:, 6:12] / s, raw[:, 12:], "
              "torch.log(s / self.pressure_reference_pa)], 1)\n";
  } else {
    source << "def forward(self, x):\n";
  }
  if (anchored && hybrid) {
    // The increment's radius from the raw rows (x holds them unchanged in its first six columns).
    source << "    rest = torch.cat([torch.zeros_like(x[:, 0:6]), x[:, 6:]], 1)\n"
           << "    r = torch.sqrt((x[:, 0:3] * x[:, 0:3]).sum(1, keepdim=True) + 0.5 * "
              "(x[:, 3:6] * x[:, 3:6]).sum(1, keepdim=True) + self.step_delta * "
              "self.step_delta)\n"
           << "    direction = torch.cat([x[:, 0:6] / r, x[:, 6:]], 1)\n"
           << "    y = (self.network(x) - self.network(rest) + (r - self.step_delta) / "
              "self.step_reference * self.direction_network(direction)) * self.out_scale\n";
  } else if (anchored) {
    source << "    rest = torch.cat([torch.zeros_like(x[:, 0:6]), x[:, 6:]], 1)\n"
           << "    y = (self.network(x) - self.network(rest)) * self.out_scale\n";
  } else {
    source << "    y = self.network(x) * self.out_scale + self.out_mean\n";
  }
  source << (scaled ? "    return torch.cat([y[:, 0:6] * s, y[:, 6:]], 1)\n" : "    return y\n");
  module.define(source.str());
  module.eval();
  return module;
}

}  // namespace

struct StressSurrogate::Impl {
  mutable torch::jit::Module module;
  std::string architecture;
  FusedMlp fused;  // the module's weights, for evaluation (fused_mlp.h)
  std::vector<std::string> carried;  // MlpArchitecture::carried_variables
  bool previous_direction = false;   // MlpArchitecture::previous_direction
};

namespace {

Eigen::VectorXd VectorOf(const torch::Tensor& tensor) {
  const torch::Tensor t = tensor.detach().to(torch::kFloat64).contiguous().reshape({-1});
  return Eigen::Map<const Eigen::VectorXd>(t.data_ptr<double>(), t.numel());
}

// The module's layers <weight_prefix>0, <bias_prefix>0, ... as Eigen matrices and vectors.
void FusedLayers(const torch::jit::Module& module, const std::string& weight_prefix,
                 const std::string& bias_prefix, std::vector<Eigen::MatrixXd>* weights,
                 std::vector<Eigen::VectorXd>* biases) {
  for (int layer = 0; module.hasattr(weight_prefix + std::to_string(layer)); ++layer) {
    const torch::Tensor w = module.attr(weight_prefix + std::to_string(layer))
                                .toTensor()
                                .detach()
                                .to(torch::kFloat64)
                                .contiguous();
    // Row-major (out, in) into a column-major matrix of the same shape.
    Eigen::MatrixXd matrix(w.size(0), w.size(1));
    const double* data = w.data_ptr<double>();
    for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
      for (Eigen::Index c = 0; c < matrix.cols(); ++c) matrix(r, c) = data[r * matrix.cols() + c];
    }
    weights->push_back(std::move(matrix));
    biases->push_back(VectorOf(module.attr(bias_prefix + std::to_string(layer)).toTensor()));
  }
}

// The module's weights as the fused kernel's; throws c10::Error for a module without them.
FusedMlp FusedOf(const torch::jit::Module& module, const std::string& architecture) {
  FusedMlp fused;
  FusedLayers(module, "w", "b", &fused.weights, &fused.biases);
  fused.in_mean = VectorOf(module.attr("in_mean").toTensor());
  fused.in_scale = VectorOf(module.attr("in_scale").toTensor());
  fused.out_mean = VectorOf(module.attr("out_mean").toTensor());
  fused.out_scale = VectorOf(module.attr("out_scale").toTensor());
  fused.anchored = architecture.find("-anchored") != std::string::npos;
  fused.pressure_reference_pa =
      module.hasattr("pressure_reference_pa") ? module.attr("pressure_reference_pa").toDouble() : 0;
  FusedLayers(module, "v", "c", &fused.direction_weights, &fused.direction_biases);
  if (!fused.direction_weights.empty()) {
    fused.direction_in_mean = VectorOf(module.attr("direction_in_mean").toTensor());
    fused.direction_in_scale = VectorOf(module.attr("direction_in_scale").toTensor());
    fused.step_reference = module.attr("step_reference").toDouble();
    fused.step_delta = module.attr("step_delta").toDouble();
  }
  return fused;
}

// The module's carried variables (none for a module saved before networks carried any).
std::vector<std::string> CarriedOf(const torch::jit::Module& module) {
  std::vector<std::string> carried;
  if (!module.hasattr("carried_variables")) return carried;
  std::stringstream names(module.attr("carried_variables").toStringRef());
  for (std::string name; std::getline(names, name, ',');) carried.push_back(name);
  return carried;
}

}  // namespace

void MlpArchitecture::Validate(const std::string& field_prefix) const {
  if (hidden_widths.empty() || hidden_widths.size() > 16) {
    throw InputError(field_prefix + "hidden_widths", "needs 1 to 16 hidden layers");
  }
  for (int width : hidden_widths) {
    if (width < 1 || width > 4096) {
      throw InputError(field_prefix + "hidden_widths", "each layer 1 to 4096 wide");
    }
  }
  if (!(pressure_reference_pa == 0 ||
        (pressure_reference_pa >= 1 && pressure_reference_pa <= 1e7))) {
    throw InputError(field_prefix + "pressure_reference_pa",
                     "must be 0 (no scaling) or in [1, 1e7] Pa");
  }
  if (homogeneous_term && !anchored) {
    throw InputError(field_prefix + "homogeneous_term", "needs the anchored network");
  }
  if (carried_variables.size() > 16) {
    throw InputError(field_prefix + "carried_variables", "at most 16");
  }
  for (std::size_t k = 0; k < carried_variables.size(); ++k) {
    const std::string& name = carried_variables[k];
    if (name.empty() || name.find_first_of(",+ ") != std::string::npos) {
      throw InputError(field_prefix + "carried_variables",
                       "'" + name + "' is not a recorded variable's name");
    }
    for (const char* component : {"_xx", "_yy", "_zz", "_yz", "_xz", "_xy"}) {
      if (name.size() > 3 && name.compare(name.size() - 3, 3, component) == 0) {
        throw InputError(field_prefix + "carried_variables",
                         "'" + name + "' is a tensor's component; only invariants are carried "
                         "(a tensor would have to turn with each step's rotation)");
      }
    }
    if (std::find(carried_variables.begin(), carried_variables.begin() + k, name) !=
        carried_variables.begin() + k) {
      throw InputError(field_prefix + "carried_variables", "'" + name + "' twice");
    }
  }
}

std::string MlpArchitecture::Describe() const {
  std::string name = "mlp-";
  for (std::size_t k = 0; k < hidden_widths.size(); ++k) {
    name += (k ? "x" : "") + std::to_string(hidden_widths[k]);
  }
  name += anchored ? "-tanh-anchored" : "-tanh";
  if (homogeneous_term) name += "-hybrid";
  if (pressure_reference_pa > 0) {
    std::ostringstream reference;
    reference << pressure_reference_pa;
    name += "-pressure-scaled-" + reference.str() + "pa";
  }
  if (!carried_variables.empty()) name += "-carrying-" + Joined(carried_variables, "+");
  if (previous_direction) name += "-previous-direction";
  return name;
}

void TrainingOptions::Validate(const std::string& field_prefix) const {
  if (epochs < 1 || epochs > 100000) throw InputError(field_prefix + "epochs", "must be in [1, 100000]");
  if (batch_size < 1) throw InputError(field_prefix + "batch_size", "must be at least 1");
  if (!(learning_rate > 0 && learning_rate < 1)) {
    throw InputError(field_prefix + "learning_rate", "must be in (0, 1)");
  }
  if (threads < 1) throw InputError(field_prefix + "threads", "must be at least 1");
  if (!(path_stress_weighting >= 0 && path_stress_weighting <= 1)) {
    throw InputError(field_prefix + "path_stress_weighting", "must be in [0, 1]");
  }
  if (rollout_steps < 0 || rollout_steps > 1000) {
    throw InputError(field_prefix + "rollout_steps", "must be in [0, 1000]");
  }
  if (!(rollout_weight >= 0 && std::isfinite(rollout_weight))) {
    throw InputError(field_prefix + "rollout_weight", "must be finite and not negative");
  }
  if (!(stress_noise >= 0 && stress_noise <= 1)) {
    throw InputError(field_prefix + "stress_noise", "must be in [0, 1]");
  }
  if (!(noise_correction >= 0 && noise_correction <= 1)) {
    throw InputError(field_prefix + "noise_correction", "must be in [0, 1]");
  }
  for (double weight : history_weights) {
    if (!(weight >= 0 && std::isfinite(weight))) {
      throw InputError(field_prefix + "history_weights", "must be finite and not negative");
    }
  }
  if (!history_weights.empty() &&
      std::none_of(history_weights.begin(), history_weights.end(),
                   [](double weight) { return weight > 0; })) {
    throw InputError(field_prefix + "history_weights", "must not all be 0 (nothing to learn)");
  }
}

StressSurrogate::StressSurrogate(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
StressSurrogate::StressSurrogate(StressSurrogate&&) noexcept = default;
StressSurrogate& StressSurrogate::operator=(StressSurrogate&&) noexcept = default;
StressSurrogate::~StressSurrogate() = default;

std::string StressSurrogate::architecture() const { return impl_->architecture; }

const std::vector<std::string>& StressSurrogate::carried_variables() const {
  return impl_->carried;
}

bool StressSurrogate::reads_previous_direction() const { return impl_->previous_direction; }

Vector6 IncrementDirection(const Vector6& strain_increment) {
  const double size = std::sqrt(strain_increment.head<3>().squaredNorm() +
                                0.5 * strain_increment.tail<3>().squaredNorm());
  return size > 0 ? Vector6(strain_increment / size) : Vector6::Zero();
}

std::vector<SurrogateInput> InputsOf(const StrainHistory& history,
                                     const std::vector<std::string>& carried) {
  const std::vector<std::size_t> columns = CarriedColumns(history, carried);
  std::vector<SurrogateInput> inputs;
  inputs.reserve(history.steps());
  Vector6 stress = material::StressToVoigt(history.initial_stress_pa);
  Vector6 accumulated = Vector6::Zero();
  for (std::size_t s = 0; s < history.steps(); ++s) {
    const material::IncrementKinematics kinematics = material::HughesWinget(history.increments[s]);
    SurrogateInput input;
    input.strain_increment = material::StrainToVoigt(kinematics.strain_increment);
    input.stress_pa = stress;
    input.accumulated_strain = accumulated;
    input.internal_variables = CarriedBefore(history, columns, s);
    if (s > 0) input.previous_direction = IncrementDirection(inputs.back().strain_increment);
    inputs.push_back(input);
    accumulated += input.strain_increment;
    stress = history.stresses_pa[s];
  }
  return inputs;
}

StressSurrogate StressSurrogate::Train(const std::vector<StrainHistory>& histories,
                                       const MlpArchitecture& architecture,
                                       const TrainingOptions& options, TrainingReport* report) {
  return TrainFrom(histories, architecture, options, report, nullptr);
}

StressSurrogate StressSurrogate::FineTune(const StressSurrogate& base,
                                          const std::vector<StrainHistory>& histories,
                                          const TrainingOptions& options, TrainingReport* report) {
  if (base.impl_->fused.weights.empty()) {
    throw InputError("model", "the model to fine-tune from is not an MLP surrogate");
  }
  MlpArchitecture architecture;
  architecture.hidden_widths.clear();
  for (std::size_t k = 0; k + 1 < base.impl_->fused.weights.size(); ++k) {
    architecture.hidden_widths.push_back(static_cast<int>(base.impl_->fused.weights[k].rows()));
  }
  architecture.anchored = base.impl_->fused.anchored;
  architecture.pressure_reference_pa = base.impl_->fused.pressure_reference_pa;
  architecture.carried_variables = base.impl_->carried;
  architecture.homogeneous_term = !base.impl_->fused.direction_weights.empty();
  architecture.previous_direction = base.impl_->previous_direction;
  return TrainFrom(histories, architecture, options, report, &base);
}

StressSurrogate StressSurrogate::TrainFrom(const std::vector<StrainHistory>& histories,
                                           const MlpArchitecture& architecture,
                                           const TrainingOptions& options, TrainingReport* report,
                                           const StressSurrogate* base) {
  architecture.Validate("architecture.");
  options.Validate("training.");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<std::string>& carried = architecture.carried_variables;
  const int outputs = kOutputs + static_cast<int>(carried.size());
  std::vector<SurrogateInput> inputs;
  std::vector<Eigen::VectorXd> targets;  // d_sigma, then the carried variables' increments
  if (!options.history_weights.empty() && options.history_weights.size() != histories.size()) {
    throw InputError("training.history_weights", "must hold one weight per history (" +
                                                     std::to_string(histories.size()) + ")");
  }
  std::vector<double> path_stress_pa;  // per step: its path's mean |sigma|
  std::vector<double> history_weight;   // per step: its history's weight
  const int rollout_steps = options.rollout_steps;
  const bool noisy = options.stress_noise > 0;
  // Per step, for the rollout term and the noise's target.
  const bool keeps_rotation_maps = rollout_steps > 0 || noisy;
  std::vector<Eigen::Matrix<double, 6, 6>> rotation_maps;
  std::vector<std::int64_t> window_starts;
  std::vector<double> window_weights;
  for (std::size_t h = 0; h < histories.size(); ++h) {
    const StrainHistory& history = histories[h];
    const std::vector<SurrogateInput> steps = InputsOf(history, carried);
    const std::vector<std::size_t> columns = CarriedColumns(history, carried);
    double stress_sum = 0;
    for (const Vector6& stress : history.stresses_pa) {
      stress_sum += material::VoigtToStress(stress).norm();
    }
    const double mean_stress =
        history.steps() > 0 ? stress_sum / static_cast<double>(history.steps()) : 0;
    path_stress_pa.insert(path_stress_pa.end(), steps.size(), mean_stress);
    history_weight.insert(history_weight.end(), steps.size(),
                          options.history_weights.empty() ? 1.0 : options.history_weights[h]);
    if (rollout_steps > 0 && steps.size() >= static_cast<std::size_t>(rollout_steps)) {
      const std::size_t windows = steps.size() - rollout_steps + 1;
      for (std::size_t s = 0; s < windows; ++s) {
        window_starts.push_back(static_cast<std::int64_t>(inputs.size() + s));
        window_weights.push_back(1.0 / static_cast<double>(windows));
      }
    }
    for (std::size_t s = 0; s < steps.size(); ++s) {
      const Matrix3 rotation = material::HughesWinget(history.increments[s]).rotation;
      const Matrix3 before = material::VoigtToStress(steps[s].stress_pa);
      Eigen::VectorXd target(outputs);
      target << history.stresses_pa[s] -
                    material::StressToVoigt(rotation * before * rotation.transpose()),
          CarriedBefore(history, columns, s + 1) - steps[s].internal_variables;
      targets.push_back(std::move(target));
      inputs.push_back(steps[s]);
      if (keeps_rotation_maps) rotation_maps.push_back(StressRotationMap(rotation));
    }
  }
  if (inputs.empty()) throw InputError("histories", "no steps to train on");
  if (rollout_steps > 0 && window_starts.empty()) {
    throw InputError("training.rollout_steps",
                     "every history is shorter than " + std::to_string(rollout_steps) + " steps");
  }
  const torch::Tensor x = InputTensor(inputs, architecture.previous_direction);
  torch::Tensor y = torch::empty({static_cast<std::int64_t>(targets.size()), outputs},
                                 torch::kFloat64);
  for (std::size_t n = 0; n < targets.size(); ++n) {
    for (int c = 0; c < outputs; ++c) y[n][c] = targets[n][c];
  }
  if (!torch::isfinite(x).all().item<bool>() || !torch::isfinite(y).all().item<bool>()) {
    throw InputError("histories", "a step holds a value that is not finite");
  }
  // What the network sees and answers (MlpArchitecture::pressure_reference_pa): x and y
  // themselves, or scaled.
  const double reference_pa = architecture.pressure_reference_pa;
  const torch::Tensor features = Features(x, reference_pa);
  torch::Tensor answers = y;
  if (reference_pa > 0) {
    answers = y.clone();
    answers.slice(1, 0, 6).div_(PressureScale(x.slice(1, 6, 12), reference_pa));
  }
  auto [in_mean, in_scale] = Standardisation(features);
  auto [out_mean, out_scale] = Standardisation(answers);
  // Anchored, the output has no offset: d_sigma is the difference of two network answers.
  if (architecture.anchored) out_mean = torch::zeros_like(out_mean);
  if (base != nullptr) {
    if (base->impl_->carried != carried) {
      throw InputError("model", "the base model carries other internal variables");
    }
    // Fine-tuning keeps the base's standardisation, which its weights were learnt in.
    const torch::jit::Module& module = base->impl_->module;
    in_mean = module.attr("in_mean").toTensor().detach().clone();
    in_scale = module.attr("in_scale").toTensor().detach().clone();
    out_mean = module.attr("out_mean").toTensor().detach().clone();
    out_scale = module.attr("out_scale").toTensor().detach().clone();
  }
  const torch::Tensor xs = (features - in_mean) / in_scale;
  const torch::Tensor ys = (answers - out_mean) / out_scale;
  torch::Tensor rest = features.clone();
  rest.slice(1, 0, 6).zero_();
  const torch::Tensor xs_rest = (rest - in_mean) / in_scale;
  // MlpArchitecture::homogeneous_term: the second network's standardised inputs, and each step's
  // gain (r - delta) / h_ref.
  const bool hybrid = architecture.homogeneous_term;
  DirectionNetwork direction;
  torch::Tensor direction_inputs, gain;
  if (hybrid) {
    if (rollout_steps > 0 || noisy) {
      throw InputError("architecture.homogeneous_term",
                       "is not trained with the rollout term or training noise");
    }
    if (base != nullptr) {
      throw InputError("model", "a network with the homogeneous term is not fine-tuned yet");
    }
    const torch::Tensor radius = IncrementRadius(x, kStepDelta);
    direction.step_reference =
        (radius.pow(2) - kStepDelta * kStepDelta).clamp_min(0).sqrt().median().item<double>();
    if (!(direction.step_reference > 0)) {
      throw InputError("histories", "half the steps or more have no strain increment");
    }
    const torch::Tensor direction_features = DirectionFeatures(x, reference_pa, kStepDelta);
    std::tie(direction.in_mean, direction.in_scale) = Standardisation(direction_features);
    direction_inputs = (direction_features - direction.in_mean) / direction.in_scale;
    gain = (radius - kStepDelta) / direction.step_reference;
  }

  const torch::Tensor step_weights = StepWeights(path_stress_pa, history_weight, options);
  const int carried_count = static_cast<int>(carried.size());
  RolloutData rollout;
  if (keeps_rotation_maps) {
    const auto count = static_cast<std::int64_t>(inputs.size());
    rollout.rotation_maps = torch::empty({count, 6, 6}, torch::kFloat64);
    rollout.path_stress_pa = torch::empty({count, 1}, torch::kFloat64);
    double* maps = rollout.rotation_maps.data_ptr<double>();
    double* scales = rollout.path_stress_pa.data_ptr<double>();
    for (std::int64_t n = 0; n < count; ++n) {
      for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 6; ++c) maps[36 * n + 6 * r + c] = rotation_maps[n](r, c);
      }
      scales[n] = std::max(path_stress_pa[n], 1.0);
    }
  }
  if (rollout_steps > 0) {
    // The state after each step: the state before it plus the recorded change.
    const torch::Tensor before = x.slice(1, 6, 12).unsqueeze(2);
    rollout.stress_after = torch::bmm(rollout.rotation_maps, before).squeeze(2) + y.slice(1, 0, 6);
    rollout.carried_after = x.slice(1, kInputs, kInputs + carried_count) +
                            y.slice(1, kOutputs, kOutputs + carried_count);
    rollout.window_starts = torch::tensor(window_starts, torch::kInt64);
    rollout.window_weights = torch::tensor(window_weights, torch::kFloat64);
  }

  torch::set_num_threads(options.threads);
  torch::manual_seed(options.seed);
  const int network_inputs = kInputs + static_cast<int>(carried.size()) +
                             (architecture.previous_direction ? 6 : 0) + (reference_pa > 0 ? 1 : 0);
  std::vector<torch::nn::Linear> layers;
  torch::nn::Sequential net =
      TanhNetwork(network_inputs, architecture.hidden_widths, outputs, &layers);
  torch::nn::Sequential direction_net;  // MlpArchitecture::homogeneous_term's M, N's widths
  std::vector<torch::nn::Linear> direction_layers;
  std::vector<torch::Tensor> parameters = net->parameters();
  if (hybrid) {
    direction_net =
        TanhNetwork(network_inputs, architecture.hidden_widths, outputs, &direction_layers);
    for (const torch::Tensor& parameter : direction_net->parameters()) {
      parameters.push_back(parameter);
    }
  }
  if (base != nullptr) {  // start from the base's weights
    torch::NoGradGuard no_grad;
    const torch::jit::Module& module = base->impl_->module;
    for (std::size_t k = 0; k < layers.size(); ++k) {
      layers[k]->weight.copy_(module.attr("w" + std::to_string(k)).toTensor());
      layers[k]->bias.copy_(module.attr("b" + std::to_string(k)).toTensor());
    }
  }

  torch::optim::Adam optimizer(parameters, torch::optim::AdamOptions(options.learning_rate));
  const std::int64_t samples = xs.size(0);
  TrainingReport figures;
  figures.samples = samples;
  // The rollout term: windows replayed from their first recorded state on the network's own
  // answers, as ReplayError replays a path (the same objective update and carried variables).
  const std::int64_t windows_per_batch =
      std::max(1, options.batch_size / std::max(1, rollout_steps));
  const auto rollout_loss = [&]() {
    const torch::Tensor starts = rollout.window_starts.index_select(
        0, torch::multinomial(rollout.window_weights, windows_per_batch, /*replacement=*/true));
    const torch::Tensor first = x.index_select(0, starts);
    torch::Tensor stress = first.slice(1, 6, 12);
    torch::Tensor carried_now = first.slice(1, kInputs, kInputs + carried_count);
    const torch::Tensor carried_scale = in_scale.slice(0, kInputs, kInputs + carried_count);
    torch::Tensor squared_error_sum = torch::zeros({}, torch::kFloat64);
    for (int k = 0; k < rollout_steps; ++k) {
      const torch::Tensor step = starts + k;
      const torch::Tensor recorded = x.index_select(0, step);
      const torch::Tensor strain_increment = recorded.slice(1, 0, 6);
      const torch::Tensor accumulated = recorded.slice(1, 12, kInputs);
      // The previous direction (MlpArchitecture::previous_direction; no columns without it) is
      // the recorded one: the window's increments are given.
      const torch::Tensor state = torch::cat(
          {stress, accumulated, carried_now, recorded.slice(1, kInputs + carried_count)}, 1);
      torch::Tensor raw = torch::cat({strain_increment, state}, 1);
      // Anchored: the answer at rest from the same forward pass, the two stacked.
      if (architecture.anchored) {
        raw = torch::cat({raw, torch::cat({torch::zeros_like(strain_increment), state}, 1)}, 0);
      }
      torch::Tensor answer = net->forward((Features(raw, reference_pa) - in_mean) / in_scale);
      if (architecture.anchored) {
        answer = answer.slice(0, 0, windows_per_batch) -
                 answer.slice(0, windows_per_batch, 2 * windows_per_batch);
      }
      answer = answer * out_scale + out_mean;
      torch::Tensor stress_increment = answer.slice(1, 0, 6);
      if (reference_pa > 0) {
        stress_increment = stress_increment * PressureScale(stress, reference_pa);
      }
      stress =
          torch::bmm(rollout.rotation_maps.index_select(0, step), stress.unsqueeze(2)).squeeze(2) +
          stress_increment;
      squared_error_sum =
          squared_error_sum + ((stress - rollout.stress_after.index_select(0, step)) /
                               rollout.path_stress_pa.index_select(0, step))
                                  .pow(2)
                                  .sum();
      if (carried_count > 0) {
        carried_now = carried_now + answer.slice(1, kOutputs, kOutputs + carried_count);
        squared_error_sum =
            squared_error_sum +
            ((carried_now - rollout.carried_after.index_select(0, step)) / carried_scale)
                .pow(2)
                .sum();
      }
    }
    return squared_error_sum /
           static_cast<double>(windows_per_batch * rollout_steps * (kOutputs + carried_count));
  };
  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    if (options.stop && options.stop()) throw CancelledError();
    HalveLearningRateAtMilestones(optimizer, epoch, options.epochs);
    const torch::Tensor order = torch::randperm(samples, torch::kInt64);
    double loss_sum = 0;
    double rollout_sum = 0;
    std::int64_t batches = 0;
    for (std::int64_t begin = 0; begin < samples; begin += options.batch_size) {
      const torch::Tensor batch =
          order.slice(0, begin, std::min<std::int64_t>(begin + options.batch_size, samples));
      optimizer.zero_grad();
      torch::Tensor batch_inputs, batch_inputs_at_rest, batch_answers;
      if (noisy) {
        // TrainingOptions::stress_noise: the stresses before the step perturbed, the targets
        // taking back noise_correction of the perturbation, turned by the step's rotation.
        torch::Tensor raw = x.index_select(0, batch);
        torch::Tensor recorded = y.index_select(0, batch);
        const torch::Tensor noise =
            torch::randn({batch.size(0), 6}, torch::kFloat64) *
            (options.stress_noise * rollout.path_stress_pa.index_select(0, batch));
        raw.slice(1, 6, 12).add_(noise);
        recorded.slice(1, 0, 6).sub_(
            options.noise_correction *
            torch::bmm(rollout.rotation_maps.index_select(0, batch), noise.unsqueeze(2))
                .squeeze(2));
        const torch::Tensor batch_features = Features(raw, reference_pa);
        if (reference_pa > 0) {
          recorded.slice(1, 0, 6).div_(PressureScale(raw.slice(1, 6, 12), reference_pa));
        }
        torch::Tensor batch_rest = batch_features.clone();
        batch_rest.slice(1, 0, 6).zero_();
        batch_inputs = (batch_features - in_mean) / in_scale;
        batch_inputs_at_rest = (batch_rest - in_mean) / in_scale;
        batch_answers = (recorded - out_mean) / out_scale;
      } else {
        batch_inputs = xs.index_select(0, batch);
        batch_inputs_at_rest = xs_rest.index_select(0, batch);
        batch_answers = ys.index_select(0, batch);
      }
      torch::Tensor predicted = net->forward(batch_inputs);
      if (architecture.anchored) predicted = predicted - net->forward(batch_inputs_at_rest);
      if (hybrid) {
        predicted = predicted + gain.index_select(0, batch) *
                                    direction_net->forward(direction_inputs.index_select(0, batch));
      }
      torch::Tensor loss = step_weights.defined()
                               ? ((predicted - batch_answers).pow(2) *
                                  step_weights.index_select(0, batch).unsqueeze(1))
                                     .mean()
                               : torch::mse_loss(predicted, batch_answers);
      loss_sum += loss.item<double>() * static_cast<double>(batch.size(0));
      if (rollout_steps > 0) {
        const torch::Tensor term = rollout_loss();
        rollout_sum += term.item<double>();
        ++batches;
        loss = loss + options.rollout_weight * term;
      }
      loss.backward();
      optimizer.step();
    }
    const double mean_loss = loss_sum / static_cast<double>(samples);
    if (epoch == 0) figures.first_loss = mean_loss;
    figures.final_loss = mean_loss;
    if (batches > 0) figures.final_rollout_loss = rollout_sum / static_cast<double>(batches);
  }
  std::vector<torch::Tensor> weights, biases;
  for (const torch::nn::Linear& layer : layers) {
    weights.push_back(layer->weight);
    biases.push_back(layer->bias);
  }
  for (const torch::nn::Linear& layer : direction_layers) {
    direction.weights.push_back(layer->weight);
    direction.biases.push_back(layer->bias);
  }
  auto impl = std::make_unique<Impl>(
      Impl{ScriptModule(weights, biases, in_mean, in_scale, out_mean, out_scale,
                        architecture.Describe(), architecture.anchored, carried, reference_pa,
                        architecture.previous_direction, direction),
           architecture.Describe(), FusedMlp{}, carried, architecture.previous_direction});
  impl->fused = FusedOf(impl->module, impl->architecture);
  figures.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (report != nullptr) *report = figures;
  return StressSurrogate(std::move(impl));
}

std::vector<Vector6> StressSurrogate::StressIncrements(
    const std::vector<SurrogateInput>& inputs, std::vector<Voigt6x6>* tangents,
    std::vector<Eigen::VectorXd>* internal_increments) const {
  RequireCarried(inputs, impl_->carried);
  const Eigen::Index carried = static_cast<Eigen::Index>(impl_->carried.size());
  const Eigen::Index previous = impl_->previous_direction ? 6 : 0;
  Eigen::MatrixXd x(kInputs + carried + previous, static_cast<Eigen::Index>(inputs.size()));
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    const auto column = static_cast<Eigen::Index>(n);
    x.col(column).segment<6>(0) = inputs[n].strain_increment;
    x.col(column).segment<6>(6) = inputs[n].stress_pa;
    x.col(column).segment<6>(12) = inputs[n].accumulated_strain;
    x.col(column).segment(kInputs, carried) = inputs[n].internal_variables;
    x.col(column).tail(previous) = inputs[n].previous_direction;
  }
  const Eigen::MatrixXd y = impl_->fused.Evaluate(x, tangents);
  std::vector<Vector6> increments(inputs.size());
  if (internal_increments != nullptr) internal_increments->resize(inputs.size());
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    increments[n] = y.col(static_cast<Eigen::Index>(n)).head<6>();
    if (internal_increments != nullptr) {
      (*internal_increments)[n] = y.col(static_cast<Eigen::Index>(n)).tail(carried);
    }
  }
  return increments;
}

std::vector<Vector6> StressSurrogate::StressIncrementsByModule(
    const std::vector<SurrogateInput>& inputs, std::vector<Voigt6x6>* tangents,
    std::vector<Eigen::VectorXd>* internal_increments) const {
  RequireCarried(inputs, impl_->carried);
  const int outputs = kOutputs + static_cast<int>(impl_->carried.size());
  std::vector<Vector6> increments(inputs.size());
  if (internal_increments != nullptr) internal_increments->assign(inputs.size(), {});
  if (inputs.empty()) {
    if (tangents != nullptr) tangents->clear();
    return increments;
  }
  torch::Tensor x = InputTensor(inputs, impl_->previous_direction);
  torch::Tensor y;
  if (tangents == nullptr) {
    torch::NoGradGuard no_grad;
    y = impl_->module.forward({x}).toTensor();
  } else {
    x.requires_grad_(true);
    y = impl_->module.forward({x}).toTensor();
    tangents->assign(inputs.size(), Voigt6x6::Zero());
    for (int row = 0; row < kOutputs; ++row) {
      // Points are independent, so the gradient of the column's sum is each point's own row.
      const torch::Tensor gradient =
          torch::autograd::grad({y.select(1, row).sum()}, {x}, {}, /*retain_graph=*/true)[0];
      const torch::Tensor block = gradient.slice(1, 0, 6).contiguous();
      const double* data = block.data_ptr<double>();
      for (std::size_t n = 0; n < inputs.size(); ++n) {
        for (int column = 0; column < 6; ++column) {
          (*tangents)[n](row, column) = data[n * 6 + column];
        }
      }
    }
    y = y.detach();
  }
  y = y.contiguous();
  const double* data = y.data_ptr<double>();
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    for (int c = 0; c < kOutputs; ++c) increments[n][c] = data[n * outputs + c];
    if (internal_increments != nullptr) {
      (*internal_increments)[n] =
          Eigen::Map<const Eigen::VectorXd>(data + n * outputs + kOutputs, outputs - kOutputs);
    }
  }
  return increments;
}

void StressSurrogate::Save(const std::string& path) const { SaveModule(impl_->module, path); }

StressSurrogate StressSurrogate::Load(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("model", "not a gonogo stress surrogate (" + path + "): unreadable");
  return FromStream(file, path);
}

StressSurrogate StressSurrogate::FromBytes(const std::string& bytes) {
  std::istringstream in(bytes);
  return FromStream(in, std::to_string(bytes.size()) + " bytes");
}

StressSurrogate StressSurrogate::FromStream(std::istream& in, const std::string& what) {
  auto impl = std::make_unique<Impl>();
  try {
    impl->module = torch::jit::load(in);
    impl->architecture = impl->module.attr("architecture").toStringRef();
    impl->module.eval();
    impl->fused = FusedOf(impl->module, impl->architecture);
    impl->carried = CarriedOf(impl->module);
    // A module saved before the input existed has no such attribute: it reads no direction.
    impl->previous_direction = impl->module.hasattr("previous_direction") &&
                               impl->module.attr("previous_direction").toBool();
  } catch (const c10::Error& e) {
    throw InputError("model", "not a gonogo stress surrogate (" + what + "): " +
                                  e.what_without_backtrace());
  }
  return StressSurrogate(std::move(impl));
}

std::string StressSurrogate::Bytes() const {
  std::ostringstream out;
  try {
    impl_->module.save(out);
  } catch (const c10::Error& e) {
    throw std::runtime_error(std::string("cannot serialise the surrogate: ") +
                             e.what_without_backtrace());
  }
  return out.str();
}

namespace {

constexpr int kRecurrentInputs = 12;

torch::Tensor RecurrentInputTensor(const std::vector<SurrogateInput>& inputs) {
  return InputTensor(inputs, /*previous_direction=*/false, /*recurrent=*/true);
}

// d_sigma = sigma_{n+1} - R sigma_n R^T of every step of a history.
torch::Tensor StressIncrementTargets(const StrainHistory& history,
                                     const std::vector<SurrogateInput>& inputs) {
  torch::Tensor y = torch::empty({static_cast<std::int64_t>(inputs.size()), kOutputs},
                                 torch::kFloat64);
  double* data = y.data_ptr<double>();
  for (std::size_t s = 0; s < inputs.size(); ++s) {
    const Matrix3 rotation = material::HughesWinget(history.increments[s]).rotation;
    const Matrix3 before = material::VoigtToStress(inputs[s].stress_pa);
    const Vector6 target = history.stresses_pa[s] -
                           material::StressToVoigt(rotation * before * rotation.transpose());
    for (int c = 0; c < kOutputs; ++c) data[s * kOutputs + c] = target[c];
  }
  return y;
}

}  // namespace

struct RecurrentStressSurrogate::Impl {
  mutable torch::jit::Module module;
  int hidden_width = 0;
  std::string architecture;
};

RecurrentStressSurrogate::RecurrentStressSurrogate(std::unique_ptr<Impl> impl)
    : impl_(std::move(impl)) {}
RecurrentStressSurrogate::RecurrentStressSurrogate(RecurrentStressSurrogate&&) noexcept = default;
RecurrentStressSurrogate& RecurrentStressSurrogate::operator=(RecurrentStressSurrogate&&) noexcept =
    default;
RecurrentStressSurrogate::~RecurrentStressSurrogate() = default;
int RecurrentStressSurrogate::hidden_width() const { return impl_->hidden_width; }
std::string RecurrentStressSurrogate::architecture() const { return impl_->architecture; }

RecurrentStressSurrogate RecurrentStressSurrogate::Train(const std::vector<StrainHistory>& histories,
                                                         int hidden_width,
                                                         const TrainingOptions& options,
                                                         TrainingReport* report) {
  if (hidden_width < 1 || hidden_width > 1024) {
    throw InputError("hidden_width", "must be in [1, 1024]");
  }
  options.Validate("training.");
  if (options.path_stress_weighting != 0 || !options.history_weights.empty()) {
    throw InputError(options.history_weights.empty() ? "training.path_stress_weighting"
                                                     : "training.history_weights",
                     "the recurrent surrogate weighs every step alike (the weights are for MLPs)");
  }
  if (options.rollout_steps != 0) {
    throw InputError("training.rollout_steps",
                     "the recurrent surrogate is trained on whole histories already (the rollout "
                     "term is for MLPs)");
  }
  if (options.stress_noise != 0) {
    throw InputError("training.stress_noise",
                     "the recurrent surrogate is trained on its recorded stresses (the training "
                     "noise is for MLPs)");
  }
  const auto start = std::chrono::steady_clock::now();
  // Histories of equal length make one batch of sequences (time, batch, feature).
  std::map<std::size_t, std::vector<std::pair<torch::Tensor, torch::Tensor>>> by_length;
  std::vector<torch::Tensor> all_x, all_y;
  for (const StrainHistory& history : histories) {
    if (history.steps() == 0) continue;
    const std::vector<SurrogateInput> inputs = InputsOf(history);
    torch::Tensor x = RecurrentInputTensor(inputs);
    torch::Tensor y = StressIncrementTargets(history, inputs);
    all_x.push_back(x);
    all_y.push_back(y);
    by_length[history.steps()].emplace_back(x, y);
  }
  if (all_x.empty()) throw InputError("histories", "no steps to train on");
  const torch::Tensor x_all = torch::cat(all_x), y_all = torch::cat(all_y);
  if (!torch::isfinite(x_all).all().item<bool>() || !torch::isfinite(y_all).all().item<bool>()) {
    throw InputError("histories", "a step holds a value that is not finite");
  }
  const auto [in_mean, in_scale] = Standardisation(x_all);
  const auto [out_mean, out_scale] = Standardisation(y_all);
  std::vector<std::pair<torch::Tensor, torch::Tensor>> batches;
  for (const auto& [length, sequences] : by_length) {
    std::vector<torch::Tensor> xs, ys;
    for (const auto& [x, y] : sequences) {
      xs.push_back(((x - in_mean) / in_scale).unsqueeze(1));
      ys.push_back(((y - out_mean) / out_scale).unsqueeze(1));
    }
    batches.emplace_back(torch::cat(xs, 1), torch::cat(ys, 1));
  }

  torch::set_num_threads(options.threads);
  torch::manual_seed(options.seed);
  torch::nn::GRU gru(torch::nn::GRUOptions(kRecurrentInputs, hidden_width));
  torch::nn::Linear head(hidden_width, kOutputs);
  gru->to(torch::kFloat64);
  head->to(torch::kFloat64);
  std::vector<torch::Tensor> parameters = gru->parameters();
  for (const torch::Tensor& p : head->parameters()) parameters.push_back(p);
  torch::optim::Adam optimizer(parameters, torch::optim::AdamOptions(options.learning_rate));
  TrainingReport figures;
  figures.samples = x_all.size(0);
  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    if (options.stop && options.stop()) throw CancelledError();
    HalveLearningRateAtMilestones(optimizer, epoch, options.epochs);
    double loss_sum = 0, count = 0;
    for (const auto& [x, y] : batches) {
      optimizer.zero_grad();
      const torch::Tensor hidden = std::get<0>(gru->forward(x));
      const torch::Tensor loss = torch::mse_loss(head->forward(hidden), y);
      loss.backward();
      optimizer.step();
      const double steps = static_cast<double>(x.size(0) * x.size(1));
      loss_sum += loss.item<double>() * steps;
      count += steps;
    }
    if (epoch == 0) figures.first_loss = loss_sum / count;
    figures.final_loss = loss_sum / count;
  }

  auto impl = std::make_unique<Impl>();
  impl->hidden_width = hidden_width;
  impl->architecture = "gru-" + std::to_string(hidden_width);
  torch::jit::Module module("RecurrentStressSurrogate");
  auto gru_parameters = gru->named_parameters();
  module.register_buffer("in_mean", in_mean.detach().clone());
  module.register_buffer("in_scale", in_scale.detach().clone());
  module.register_buffer("out_mean", out_mean.detach().clone());
  module.register_buffer("out_scale", out_scale.detach().clone());
  module.register_parameter("w_ih", gru_parameters["weight_ih_l0"].detach().clone(), false);
  module.register_parameter("w_hh", gru_parameters["weight_hh_l0"].detach().clone(), false);
  module.register_parameter("b_ih", gru_parameters["bias_ih_l0"].detach().clone(), false);
  module.register_parameter("b_hh", gru_parameters["bias_hh_l0"].detach().clone(), false);
  module.register_parameter("w_o", head->weight.detach().clone(), false);
  module.register_parameter("b_o", head->bias.detach().clone(), false);
  module.register_attribute("architecture", c10::StringType::get(), impl->architecture);
  // PyTorch's GRU (gates r, z, n in that order in the stacked weights).
  const std::string h = std::to_string(hidden_width), h2 = std::to_string(2 * hidden_width),
                    h3 = std::to_string(3 * hidden_width);
  module.define(
      "def forward(self, x, h):\n"
      "    z = (x - self.in_mean) / self.in_scale\n"
      "    gi = torch.matmul(z, self.w_ih.t()) + self.b_ih\n"
      "    gh = torch.matmul(h, self.w_hh.t()) + self.b_hh\n"
      "    r = torch.sigmoid(gi[:, 0:" + h + "] + gh[:, 0:" + h + "])\n"
      "    u = torch.sigmoid(gi[:, " + h + ":" + h2 + "] + gh[:, " + h + ":" + h2 + "])\n"
      "    n = torch.tanh(gi[:, " + h2 + ":" + h3 + "] + r * gh[:, " + h2 + ":" + h3 + "])\n"
      "    h_next = (1.0 - u) * n + u * h\n"
      "    y = torch.matmul(h_next, self.w_o.t()) + self.b_o\n"
      "    return y * self.out_scale + self.out_mean, h_next\n");
  module.eval();
  impl->module = std::move(module);
  figures.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (report != nullptr) *report = figures;
  return RecurrentStressSurrogate(std::move(impl));
}

std::vector<Vector6> RecurrentStressSurrogate::Step(const std::vector<SurrogateInput>& inputs,
                                                    std::vector<std::vector<double>>* hidden) const {
  const std::int64_t n = static_cast<std::int64_t>(inputs.size());
  const int width = impl_->hidden_width;
  if (hidden->size() != inputs.size()) hidden->assign(inputs.size(), std::vector<double>(width, 0.0));
  torch::Tensor h = torch::empty({n, width}, torch::kFloat64);
  for (std::int64_t k = 0; k < n; ++k) {
    if (static_cast<int>((*hidden)[k].size()) != width) (*hidden)[k].assign(width, 0.0);
    std::copy((*hidden)[k].begin(), (*hidden)[k].end(), h.data_ptr<double>() + k * width);
  }
  torch::NoGradGuard no_grad;
  const auto outputs =
      impl_->module.forward({RecurrentInputTensor(inputs), h}).toTuple()->elements();
  const torch::Tensor y = outputs[0].toTensor().contiguous();
  const torch::Tensor h_next = outputs[1].toTensor().contiguous();
  std::vector<Vector6> increments(inputs.size());
  for (std::int64_t k = 0; k < n; ++k) {
    for (int c = 0; c < kOutputs; ++c) increments[k][c] = y.data_ptr<double>()[k * kOutputs + c];
    std::copy(h_next.data_ptr<double>() + k * width, h_next.data_ptr<double>() + (k + 1) * width,
              (*hidden)[k].begin());
  }
  return increments;
}

void RecurrentStressSurrogate::Save(const std::string& path) const {
  SaveModule(impl_->module, path);
}

std::vector<Vector6> Replay(const RecurrentStressSurrogate& surrogate,
                            const StrainHistory& history) {
  std::vector<std::vector<double>> hidden;
  return Replay(
      [&](const SurrogateInput& input) {
        return SurrogateOutput{surrogate.Step({input}, &hidden)[0], {}};
      },
      history);
}

std::vector<Vector6> Replay(const SurrogateStepFunction& step, const StrainHistory& history,
                            const std::vector<std::string>& carried,
                            const AdmissibleStressFunction& admissible) {
  std::vector<Vector6> stresses;
  stresses.reserve(history.steps());
  SurrogateInput input;
  input.stress_pa = material::StressToVoigt(history.initial_stress_pa);
  input.internal_variables = CarriedBefore(history, CarriedColumns(history, carried), 0);
  for (std::size_t s = 0; s < history.steps(); ++s) {
    const material::IncrementKinematics kinematics = material::HughesWinget(history.increments[s]);
    input.strain_increment = material::StrainToVoigt(kinematics.strain_increment);
    const Matrix3 before = material::VoigtToStress(input.stress_pa);
    const SurrogateOutput output = step(input);
    Vector6 after =
        material::StressToVoigt(kinematics.rotation * before * kinematics.rotation.transpose()) +
        output.stress_increment_pa;
    if (admissible) after = material::StressToVoigt(admissible(material::VoigtToStress(after)));
    stresses.push_back(after);
    input.accumulated_strain += input.strain_increment;
    input.previous_direction = IncrementDirection(input.strain_increment);
    input.stress_pa = after;
    if (input.internal_variables.size() > 0) {
      input.internal_variables += output.internal_variable_increments;
    }
  }
  return stresses;
}

std::vector<Vector6> Replay(const StressSurrogate& surrogate, const StrainHistory& history) {
  return Replay(
      [&](const SurrogateInput& input) {
        SurrogateOutput output;
        std::vector<Eigen::VectorXd> internal;
        output.stress_increment_pa = surrogate.StressIncrements({input}, nullptr, &internal)[0];
        output.internal_variable_increments = internal[0];
        return output;
      },
      history, surrogate.carried_variables());
}

double ReplayError(const std::vector<Vector6>& replayed, const StrainHistory& history) {
  double error = 0, size = 0;
  for (std::size_t s = 0; s < replayed.size(); ++s) {
    error += (material::VoigtToStress(replayed[s]) -
              material::VoigtToStress(history.stresses_pa[s])).norm();
    size += material::VoigtToStress(history.stresses_pa[s]).norm();
  }
  return size > 0 ? error / size : 0;
}

double ReplayError(const StressSurrogate& surrogate, const StrainHistory& history) {
  return ReplayError(Replay(surrogate, history), history);
}

double HistoryDifference(const StrainHistory& other, const StrainHistory& reference) {
  const std::size_t steps = std::min(other.steps(), reference.steps());
  return ReplayError(std::vector<Vector6>(other.stresses_pa.begin(),
                                          other.stresses_pa.begin() + static_cast<long>(steps)),
                     reference);
}

}  // namespace gonogo::ann
