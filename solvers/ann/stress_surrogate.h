// A neural surrogate of a material point's stress update, trained on StrainHistory records
// (strain_history.h) with libtorch (Debian's libtorch-dev, the PyTorch 1.13 C++ API) and kept as
// a TorchScript module that Python's torch.jit.load reads.
//
// What the network sees and answers (one step of one point, Voigt order xx yy zz yz xz xy):
//   inputs   the strain increment d_eps (engineering shears) of the step's Hughes-Winget split,
//            the stress before the step sigma_n (Pa, tension positive) and the strain accumulated
//            since the path's start eps_n: 18 numbers. The stress alone cannot tell a dense
//            packing from a loose one at the same stress; the accumulated strain is the history
//            variable that can (its trace is the change of the void ratio), and the FE point can
//            carry it exactly.
//   output   d_sigma, so that sigma_{n+1} = R sigma_n R^T + d_sigma (R the step's rotation: the
//            update is objective by construction, as every model at the seam).
// A network may also carry internal variables of the RVE's state that are invariants of the frame
// (MlpArchitecture::carried_variables, e.g. the coordination number Z): their values before the
// step are further inputs and their increments over the step further outputs, so that a point
// carries them as it carries its stress. The fabric study (README) found that the packing's
// state beyond its stress and strain is what random walks and the rig's paths disagree about.
// Inputs and outputs are standardised (mean, standard deviation of the training set) inside the
// module, so the saved file is the whole map from raw inputs to raw outputs.
// The tangent d sigma_{n+1} / d eps (6 x 6, engineering shears) is the network's own derivative
// by automatic differentiation, not a separate output.
#pragma once

#include <cstdint>
#include <functional>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/ann/strain_history.h"

namespace gonogo::ann {

using Voigt6x6 = material::Voigt6x6;

struct MlpArchitecture {
  std::vector<int> hidden_widths = {64, 64};  // tanh layers; the seed's network: 7 x 600
  // d_sigma = N(d_eps, sigma_n, eps_n) - N(0, sigma_n, eps_n): no stress change without a strain
  // increment, by construction. An FE point takes hundreds of increments far smaller than a
  // laboratory step; a network whose answer at rest is a small nonzero error adds that error at
  // every one of them.
  bool anchored = true;
  // Internal variables the network carries, by the names the histories record them under
  // (tiers::RveFabricVariables: "coordination_number", "solid_fraction"). Invariants only: a
  // tensor's components would have to turn with the step's rotation.
  std::vector<std::string> carried_variables = {};
  // Pressure scaling, 0: none. A granular soil's stiffness grows with its mean stress p (about
  // as p^0.5 for Hertzian contacts), so a network that answers d_sigma in Pa learns the
  // high-pressure paths, whose increments are large, and leaves a point near the surface, whose
  // stress is a few kPa, tens of per cent off. With a reference pressure p_ref > 0 the network
  // sees the stress relative to s = max(p_n, 0) + p_ref, and log(s / p_ref) as a further input,
  // and answers d_sigma / s:
  //   inputs  [d_eps, sigma_n / s, eps_n, carried variables, log(s / p_ref)]
  //   output  d_sigma = s N(...), the carried variables' increments as they are,
  // so that its error is an error relative to the point's own stress level, at every level (the
  // held-out metric's scale). p_ref keeps s away from 0 at a point with no stress. The saved
  // module takes and answers the raw inputs and outputs all the same.
  double pressure_reference_pa = 0;
  // A second network's term, homogeneous of degree one in the increment (the hybrid; off by
  // default):
  //   d_sigma = s (N(d_eps, x) - N(0, x) + g M(n, x)),
  //   r = sqrt(|d_eps|^2 + delta^2), g = (r - delta) / h_ref, n = d_eps / r,
  // |d_eps| the strain increment's tensor norm (engineering shears halved), h_ref the training
  // steps' median |d_eps|, delta 1e-7 (far below an FE point's increment), M a network of N's
  // widths that sees n in place of d_eps. A smooth network answers an increment far smaller than
  // its training steps linearly, a step and its reverse alike but for the sign; the term may
  // answer them otherwise at any size, as a packing unloads more stiffly than it loads. delta
  // makes it differentiable at a zero increment, where its tangent is 0. README: "A rig step is
  // answered linearly".
  bool homogeneous_term = false;
  // The previous step's increment direction n_{n-1} = d_eps_{n-1} / |d_eps_{n-1}| (zero at a
  // path's first step and after a step that did not move) as six further inputs, after the
  // carried variables (off by default). A history variable a point carries exactly: along a rig
  // path consecutive steps turn little (their directions' cosine has median 0.999), so at a rig
  // step's size, where the network answers linearly, d_sigma = J(state, n_{n-1}) d_eps may
  // differ between a step that goes on loading and one that goes on unloading, which a network
  // of the present state alone answers alike but for the sign; along a random walk the steps are
  // uncorrelated, so the walks teach the response to a step after any other. README: "The
  // previous step's direction".
  bool previous_direction = false;
  void Validate(const std::string& field_prefix) const;
  // "mlp-64x64-tanh-anchored" ("mlp-64x64-tanh" unanchored), then "-hybrid" with the homogeneous
  // term, then "-pressure-scaled-<p_ref>pa"
  // when scaled, then "-carrying-" and the carried variables joined by "+" when there are any,
  // then "-previous-direction" with that input.
  std::string Describe() const;
};

struct TrainingOptions {
  int epochs = 200;
  int batch_size = 256;
  double learning_rate = 3e-3;  // Adam; halved at 50 %, 75 % and 90 % of the epochs
  std::uint64_t seed = 1;       // weights and batch order
  int threads = 1;              // torch intra-op threads (1: bit-reproducible training)
  // How the loss weighs the paths, in [0, 1]. Each step's squared error (of the standardised
  // d_sigma) is multiplied by s^(-2 x), s the mean |sigma| of its path (Frobenius), the weights
  // scaled to average 1. 0: every step alike, so a path at 80 kPa, whose increments are large,
  // outweighs one at 2.5 kPa; 1: the error relative to the path's own stress, the scale of the
  // held-out metric (ReplayError).
  double path_stress_weighting = 0;
  // Each history's own weight in the loss, in the order of the histories (multiplying the above);
  // empty: 1 each. E.g. to give the laboratory paths the share of the loss they would have beside
  // fewer random walks.
  std::vector<double> history_weights;
  // A multi-step (rollout) term in the loss, 0: none. The held-out error replays a whole path on
  // the network's own stresses, where one step's error feeds the next; a loss of single steps,
  // each from the recorded stress, does not see how its errors compound. With K > 0, each batch
  // also replays windows of K consecutive steps of the histories (batch_size / K windows, at
  // least one) from their recorded first state on the network's own stress and carried
  // variables, the stress objectively turned by each step's rotation as a point turns it, and
  // adds rollout_weight times the mean squared stress error over the windows' steps, relative to
  // the path's mean |sigma| (the held-out metric's scale; carried variables relative to their
  // standard deviation). Windows are drawn so that every history weighs alike, as every held-out
  // path counts alike, however long; histories shorter than K give none.
  int rollout_steps = 0;
  double rollout_weight = 1;
  // Training noise on the stress before the step, 0: none (Sanchez-Gonzalez et al. 2020,
  // "Learning to simulate complex physics with graph networks", sec. 4.1: a model rolled out on
  // its own answers meets states off the recorded trajectory, which a model trained on the
  // recorded states alone has never seen). Each batch's stresses before the step are perturbed by
  // e, Gaussian of standard deviation stress_noise times the path's mean |sigma| per Voigt
  // component, drawn afresh every epoch, and the target takes back noise_correction of it:
  //   d_sigma' = d_sigma - c R e R^T,
  // so that at c = 1 the step ends on the recorded stress after it (asking the network to pull a
  // drifted stress back towards the path), at c = 0 as far off as it began. Measured, neither
  // helps a network of stress increments (solvers/ann/README.md, "Training noise").
  double stress_noise = 0;
  double noise_correction = 1;
  // Asked before each epoch; true stops the training with CancelledError (a cancelled job).
  std::function<bool()> stop;
  void Validate(const std::string& field_prefix) const;
};

struct TrainingReport {
  std::int64_t samples = 0;
  double first_loss = 0;   // mean squared error of the standardised d_sigma, first epoch
  double final_loss = 0;   // last epoch
  double final_rollout_loss = 0;  // last epoch's rollout term (TrainingOptions::rollout_steps)
  double seconds = 0;
};

// One step of one point, as the network sees it (see above).
struct SurrogateInput {
  Vector6 strain_increment = Vector6::Zero();  // engineering shears
  Vector6 stress_pa = Vector6::Zero();          // before the step
  Vector6 accumulated_strain = Vector6::Zero();  // since the path's start, engineering shears
  // The carried internal variables before the step, in the network's order (empty: none).
  Eigen::VectorXd internal_variables;
  // The previous step's increment direction (IncrementDirection of its strain increment; zero at
  // the first step), read by a network with MlpArchitecture::previous_direction only.
  Vector6 previous_direction = Vector6::Zero();
};

// d_eps / |d_eps| of a strain increment (engineering shears; |d_eps| the tensor norm, the shears
// halved in its square), zero for a zero increment.
Vector6 IncrementDirection(const Vector6& strain_increment);

class StressSurrogate {
 public:
  StressSurrogate(StressSurrogate&&) noexcept;
  StressSurrogate& operator=(StressSurrogate&&) noexcept;
  ~StressSurrogate();

  // Trains on every step of `histories`. Throws InputError("histories", ...) when there are no
  // steps or a value is not finite.
  static StressSurrogate Train(const std::vector<StrainHistory>& histories,
                               const MlpArchitecture& architecture,
                               const TrainingOptions& options, TrainingReport* report = nullptr);

  // Transfer learning (seed 000's future work): a surrogate of another material started from
  // `base`'s weights and standardisation (its architecture, anchored, scaled or not), trained on
  // `histories` with `options` (fewer epochs and a smaller learning rate than from scratch, as a
  // rule). Throws as Train, and InputError("model", ...) for a base that is not an MLP.
  static StressSurrogate FineTune(const StressSurrogate& base,
                                  const std::vector<StrainHistory>& histories,
                                  const TrainingOptions& options, TrainingReport* report = nullptr);

  // d_sigma for each input, batched; with `tangents`, also d(d_sigma)/d(d_eps) per point; with
  // `internal_increments`, the carried internal variables' increments per point. By the fused
  // Eigen kernel (fused_mlp.h) on the module's weights. Throws InputError("inputs", ...) for an
  // input that does not carry the network's internal variables.
  std::vector<Vector6> StressIncrements(const std::vector<SurrogateInput>& inputs,
                                        std::vector<Voigt6x6>* tangents = nullptr,
                                        std::vector<Eigen::VectorXd>* internal_increments =
                                            nullptr) const;
  // The same by the TorchScript module itself (its forward, and autograd for the tangent): what
  // the fused kernel is checked against, and what Python's torch runs.
  std::vector<Vector6> StressIncrementsByModule(const std::vector<SurrogateInput>& inputs,
                                                std::vector<Voigt6x6>* tangents = nullptr,
                                                std::vector<Eigen::VectorXd>*
                                                    internal_increments = nullptr) const;

  // TorchScript (torch.jit.load in Python: forward takes an (N, 18 + V) float64 tensor of the
  // inputs above, V carried variables last (then the previous direction's 6 with
  // MlpArchitecture::previous_direction; the module's attribute previous_direction says so), and
  // gives (N, 6 + V): d_sigma, then the carried
  // variables' increments; the module's attribute carried_variables names them, comma-separated).
  // Load throws InputError("model", ...) for a file that is not such a module.
  void Save(const std::string& path) const;
  static StressSurrogate Load(const std::string& path);
  // The same TorchScript file as bytes (a trained member crossing ranks); FromBytes throws as Load.
  std::string Bytes() const;
  static StressSurrogate FromBytes(const std::string& bytes);

  std::string architecture() const;
  const std::vector<std::string>& carried_variables() const;
  bool reads_previous_direction() const;  // MlpArchitecture::previous_direction

 private:
  struct Impl;
  // Load and FromBytes: `what` names the source in errors.
  static StressSurrogate FromStream(std::istream& in, const std::string& what);
  explicit StressSurrogate(std::unique_ptr<Impl> impl);
  // Train and FineTune: from random (seeded) weights and the data's standardisation, or from
  // `base`'s.
  static StressSurrogate TrainFrom(const std::vector<StrainHistory>& histories,
                                   const MlpArchitecture& architecture,
                                   const TrainingOptions& options, TrainingReport* report,
                                   const StressSurrogate* base);
  std::unique_ptr<Impl> impl_;
};

// A recurrent surrogate: a GRU whose hidden state h (hidden_width numbers per point) is what the
// point carries instead of the accumulated strain, so that it can learn whatever of its history
// matters (a packing's fabric as well as its density):
//   h_{n+1} = GRU([d_eps, sigma_n], h_n),   d_sigma = W h_{n+1} + b,   h_0 = 0,
// standardised inputs and outputs as StressSurrogate's. Trained on whole histories (teacher forcing:
// sigma_n the recorded stress), all steps of a history in one sequence, histories of equal length
// batched together. Saved as TorchScript with forward(x (N, 12), h (N, H)) -> (d_sigma, h_next).
class RecurrentStressSurrogate {
 public:
  RecurrentStressSurrogate(RecurrentStressSurrogate&&) noexcept;
  RecurrentStressSurrogate& operator=(RecurrentStressSurrogate&&) noexcept;
  ~RecurrentStressSurrogate();

  // Throws InputError("hidden_width", ...) outside [1, 1024] and as StressSurrogate::Train.
  static RecurrentStressSurrogate Train(const std::vector<StrainHistory>& histories,
                                        int hidden_width, const TrainingOptions& options,
                                        TrainingReport* report = nullptr);
  int hidden_width() const;
  // One step of a batch of points: d_sigma, and each point's hidden state advanced in place.
  std::vector<Vector6> Step(const std::vector<SurrogateInput>& inputs,
                            std::vector<std::vector<double>>* hidden) const;
  void Save(const std::string& path) const;
  std::string architecture() const;  // "gru-32"

 private:
  struct Impl;
  explicit RecurrentStressSurrogate(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The GRU run along a history from h_0 = 0, feeding back its own stresses; and its error.
std::vector<Vector6> Replay(const RecurrentStressSurrogate& surrogate,
                            const StrainHistory& history);

// The inputs a history gives, step by step, with the true stresses (for training and checks), and
// the `carried` internal variables recorded before each step. Throws InputError("histories", ...)
// for a history that does not record one of them, or not its initial value.
std::vector<SurrogateInput> InputsOf(const StrainHistory& history,
                                     const std::vector<std::string>& carried = {});

// A surrogate's answer to one step: d_sigma and the carried internal variables' increments.
struct SurrogateOutput {
  Vector6 stress_increment_pa = Vector6::Zero();
  Eigen::VectorXd internal_variable_increments;
};

// A surrogate (or an ensemble's mean) run along a history's increments from its initial stress
// and its initial `carried` internal variables, feeding back its own stresses and internal
// variables (as it runs in an FE point): the predicted stress after each step, each passed through
// `admissible` when given (SurrogateEnsemble::Admissible).
using SurrogateStepFunction = std::function<SurrogateOutput(const SurrogateInput&)>;
using AdmissibleStressFunction = std::function<Matrix3(const Matrix3&)>;
std::vector<Vector6> Replay(const SurrogateStepFunction& step, const StrainHistory& history,
                            const std::vector<std::string>& carried = {},
                            const AdmissibleStressFunction& admissible = nullptr);
std::vector<Vector6> Replay(const StressSurrogate& surrogate, const StrainHistory& history);

// The replayed path's error relative to the path's own stress: mean over steps of
// |sigma_predicted - sigma_true| over the mean over steps of |sigma_true| (Frobenius norms of
// the tensors).
double ReplayError(const std::vector<Vector6>& replayed, const StrainHistory& history);
double ReplayError(const StressSurrogate& surrogate, const StrainHistory& history);
// The same path run on another RVE (`other`: another packing of the soil) against `reference`,
// measured as a replay is (ReplayError), over the steps both reached (a stress-controlled step
// can stop either): how far two answers the surrogate cannot tell apart lie from each other.
double HistoryDifference(const StrainHistory& other, const StrainHistory& reference);

}  // namespace gonogo::ann
