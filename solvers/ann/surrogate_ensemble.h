// An ensemble of stress surrogates (stress_surrogate.h) that knows when not to trust itself.
//
// Members are trained on the same histories from different seeds (initial weights and batch
// order: a deep ensemble); the answer is their mean, its spread their disagreement. A point is
// out of distribution when either
//   - its inputs are far from the training inputs: the Mahalanobis distance
//       d(x) = sqrt((z - mu)^T S^-1 (z - mu)),  z the standardised inputs, mu and S the mean and
//     covariance of the training set's z (with 1e-6 added to S's diagonal, so that a direction
//     the training never moved in is far, not undefined), exceeds `distance_threshold`; by
//     default the largest distance of any training input (outside the cloud the network has
//     seen, by that measure), or
//   - the members disagree: the spread, the largest standard deviation over the members of a
//     d_sigma component, relative to the point's stress scale max(|sigma_n|, |d_sigma|, s_0),
//     exceeds `spread_threshold`; by default kSpreadThresholdFactor x the largest relative
//     spread over the training inputs. s_0 is a tenth of the training stresses' mean |sigma|: near
//     zero stress the members disagree by a few Pa, which is nothing, not a large fraction of
//     nothing.
//   - its mean compression p = -tr(sigma)/3 before the step is below `pressure_floor_pa` (0,
//     the default: no floor). Both measures above judge one step by what the members say of it,
//     and where the members drift alike along a path (a point near the surface, its stress a few
//     kPa, where a step's error is tens of per cent of the stress) neither sees it; a floor says
//     where the model's held-out errors show it is not to be trusted (solvers/ann/README.md,
//     "A pressure floor").
// The thresholds and the floor can be set; the ensemble only flags, the material
// (ann_material.h) decides what a flag does.
//
// Admissible stresses: a stress the ensemble's answers build (sigma_{n+1} = R sigma_n R^T +
// d_sigma) is capped, principal stress by principal stress, at the most tensile principal stress
// of the training data, and at no less than zero (a point that has lost every contact carries
// nothing). For a DE RVE of cohesionless grains that cap is zero: contacts only push, so the
// packing carries no tension, and a network left alone does answer tension (up to 36 kPa at
// points near the surface of the fe-ann tier's test rig, where the RVEs' stresses stay near
// zero), which stiffens the soil. A soil whose data carries tension (a cohesive continuum) keeps
// it up to what the data showed.
// A capped stress is still one no packing holds: with one principal stress zero and the others
// compressive it lies beyond any friction angle, and the network, which has never seen such a
// state, answers the next increment from outside its training data. So the stress is then
// returned onto the cone the data spans: with c_i the principal compressions measured from the
// tensile limit, min c / max c >= k, k the least ratio of the training stresses above the
// stress floor. The return is radial in the deviatoric plane at constant mean compression m,
// c <- m + alpha (c - m), alpha = min(1, (1 - k) m / (k d_max - d_min)), d = c - m: the
// Mohr-Coulomb return of a cohesionless soil, whose criterion is this ratio,
// k = (1 - sin phi) / (1 + sin phi).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/ann/stress_surrogate.h"

namespace gonogo::ann {

// The default spread threshold over the largest relative spread of the training inputs. 1.5, not
// 3: along a rig's 900 steps a wide network's answers drift further than one step's spread says,
// and at 1.5 the six curves of three 128 x 128 networks (96 walks and four rig paths, carrying
// the coordination number) came 0.8-1.9 % of W closer to fe-de's for at most one more fallback,
// while two 64 x 64 networks' curves did not change (solvers/ann/README.md, "A tighter guard").
// Above 1, so no training input is flagged.
constexpr double kSpreadThresholdFactor = 1.5;

struct InputEnvelope {
  Eigen::VectorXd mean;               // of the standardised training inputs (18 + carried)
  Eigen::VectorXd scale;              // standardisation: standard deviations of the raw inputs
  Eigen::VectorXd offset;             // and their means
  Eigen::MatrixXd inverse_covariance;
  double largest_training_distance = 0;
  double stress_floor_pa = 1;  // s_0 above
  // The cap on principal stresses (tension positive, Pa): the largest principal stress of the
  // training stresses, at least 0; infinite for an envelope saved before the cap existed.
  double tensile_limit_pa = 0;
  // The cone: the least ratio k of least to most compressive principal stress (measured from the
  // tensile limit) of the training stresses above stress_floor_pa; 0 (no cone) for an envelope
  // saved before it existed.
  double least_principal_ratio = 0;
  // Mahalanobis distance of one input from the training inputs.
  double Distance(const SurrogateInput& input) const;
};

InputEnvelope FitEnvelope(const std::vector<SurrogateInput>& training_inputs);

struct EnsembleAnswer {
  Vector6 stress_increment_pa = Vector6::Zero();  // mean over the members
  Voigt6x6 tangent_pa = Voigt6x6::Zero();         // mean, when asked
  Eigen::VectorXd internal_variable_increments;   // mean, of the carried variables
  double distance = 0;                            // from the training inputs
  double relative_spread = 0;                     // see above
  double mean_pressure_pa = 0;                    // -tr(sigma)/3 before the step
  bool below_pressure_floor = false;              // of a floor that is set (see above)
  // Which of the guard's tests flagged the input (any may, together): the envelope's distance
  // beyond its threshold, the members' spread beyond its threshold, the pressure floor.
  bool beyond_distance = false;
  bool beyond_spread = false;
  bool out_of_distribution = false;  // flagged by any of the three
};

class SurrogateEnsemble {
 public:
  // Trains `members` (at least 3) surrogates with seeds options.seed, +1, ... and fits the
  // envelope and the default thresholds on the histories' inputs.
  // `reports` (if given) receives each member's training figures.
  static SurrogateEnsemble Train(const std::vector<StrainHistory>& histories,
                                 const MlpArchitecture& architecture,
                                 const TrainingOptions& options, int members = 3,
                                 std::vector<TrainingReport>* reports = nullptr);

  // Transfer learning: each member of `base` fine-tuned (StressSurrogate::FineTune) on
  // `histories`, member k with seed options.seed + k; the envelope and the default thresholds
  // fitted on `histories` (the new material's), as Train does.
  static SurrogateEnsemble FineTune(const SurrogateEnsemble& base,
                                    const std::vector<StrainHistory>& histories,
                                    const TrainingOptions& options,
                                    std::vector<TrainingReport>* reports = nullptr);

  // Members trained elsewhere (one per pool task, say), put together: the envelope and the default
  // thresholds fitted on `histories`, their training data, as Train does. Throws
  // InputError("members", ...) for fewer than 3 or members of different architectures.
  static SurrogateEnsemble Assemble(std::vector<StressSurrogate> members,
                                    const std::vector<StrainHistory>& histories);

  std::vector<EnsembleAnswer> Answer(const std::vector<SurrogateInput>& inputs,
                                     bool want_tangent) const;

  // `stress_pa` with every principal stress above envelope().tensile_limit_pa brought down to it,
  // then returned radially onto the cone if outside it (eigenvectors kept); `capped` (if given)
  // says whether either changed it.
  Matrix3 Admissible(const Matrix3& stress_pa, bool* capped = nullptr) const;

  double distance_threshold() const { return distance_threshold_; }
  double spread_threshold() const { return spread_threshold_; }
  // Throws InputError(field, ...) for a threshold that is not positive.
  void SetThresholds(double distance_threshold, double spread_threshold);
  double pressure_floor_pa() const { return pressure_floor_pa_; }
  // Throws InputError("pressure_floor_pa", ...) for a floor that is negative or not finite.
  void SetPressureFloor(double pressure_floor_pa);
  const InputEnvelope& envelope() const { return envelope_; }
  std::size_t size() const { return members_.size(); }
  const StressSurrogate& member(std::size_t k) const { return members_.at(k); }
  // The internal variables the members carry (stress_surrogate.h), each input's last.
  const std::vector<std::string>& carried_variables() const {
    return members_.front().carried_variables();
  }
  // Whether the members read SurrogateInput::previous_direction (one architecture for all).
  bool reads_previous_direction() const { return members_.front().reads_previous_direction(); }

  // A directory: member_<k>.pt (TorchScript, each loadable alone) and envelope.bin (the envelope
  // and thresholds, tagged little-endian doubles; GNGENV02, and GNGENV01 read with no cap). Load throws InputError("model", ...) for a
  // directory that does not hold a whole ensemble.
  void Save(const std::string& directory) const;
  static SurrogateEnsemble Load(const std::string& directory);

 private:
  // Fits the envelope and the default thresholds on the histories' inputs.
  void FitEnvelopeAndThresholds(const std::vector<StrainHistory>& histories);

  std::vector<StressSurrogate> members_;
  InputEnvelope envelope_;
  double distance_threshold_ = 0;
  double spread_threshold_ = 0;
  double pressure_floor_pa_ = 0;
};

// The ensemble's mean run along a history (Replay of stress_surrogate.h), its stresses kept
// admissible as an FE point's are (AnnMaterial), and its error.
std::vector<Vector6> Replay(const SurrogateEnsemble& ensemble, const StrainHistory& history);
double ReplayError(const SurrogateEnsemble& ensemble, const StrainHistory& history);

}  // namespace gonogo::ann
