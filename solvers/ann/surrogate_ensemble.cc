#include "solvers/ann/surrogate_ensemble.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "solvers/common/byte_stream.h"
#include "solvers/common/errors.h"

namespace gonogo::ann {
namespace {

constexpr int kInputs = 18;  // without carried internal variables
constexpr char kEnvelopeTag[9] = "GNGENV03";
constexpr char kEnvelopeTagWithoutCone[9] = "GNGENV02";  // read only: cap, no cone
constexpr char kEnvelopeTagWithoutCap[9] = "GNGENV01";   // read only: neither

Eigen::VectorXd Raw(const SurrogateInput& input) {
  Eigen::VectorXd x(kInputs + input.internal_variables.size());
  x << input.strain_increment, input.stress_pa, input.accumulated_strain,
      input.internal_variables;
  return x;
}

double StressScale(const SurrogateInput& input, const Vector6& increment, double floor_pa) {
  return std::max({material::VoigtToStress(input.stress_pa).norm(),
                   material::VoigtToStress(increment).norm(), floor_pa});
}

void PutVector(ByteWriter& out, const Eigen::VectorXd& values) {
  out.Put(static_cast<std::uint64_t>(values.size()));
  for (Eigen::Index k = 0; k < values.size(); ++k) out.Put(values[k]);
}

// A vector of the envelope's inputs: 18, and up to 16 carried internal variables.
Eigen::VectorXd GetVector(ByteReader& in) {
  std::uint64_t size = 0;
  in.Get(size);
  if (size < kInputs || size > kInputs + 16) {
    throw InputError("model", "envelope of another input size");
  }
  Eigen::VectorXd values(static_cast<Eigen::Index>(size));
  for (Eigen::Index k = 0; k < values.size(); ++k) in.Get(values[k]);
  return values;
}

}  // namespace

double InputEnvelope::Distance(const SurrogateInput& input) const {
  if (kInputs + input.internal_variables.size() != offset.size()) {
    throw InputError("inputs", "a point carries " + std::to_string(input.internal_variables.size()) +
                                   " internal variables, the envelope " +
                                   std::to_string(offset.size() - kInputs));
  }
  const Eigen::VectorXd z = (Raw(input) - offset).cwiseQuotient(scale) - mean;
  return std::sqrt(std::max(0.0, z.dot(inverse_covariance * z)));
}

InputEnvelope FitEnvelope(const std::vector<SurrogateInput>& training_inputs) {
  if (training_inputs.size() < 2) {
    throw InputError("histories", "an envelope needs two training steps at least");
  }
  const Eigen::Index n = static_cast<Eigen::Index>(training_inputs.size());
  const Eigen::Index columns = Raw(training_inputs.front()).size();
  Eigen::MatrixXd raw(n, columns);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::VectorXd x = Raw(training_inputs[k]);
    if (x.size() != columns) {
      throw InputError("histories", "the training inputs carry different internal variables");
    }
    raw.row(k) = x.transpose();
  }
  InputEnvelope envelope;
  envelope.offset = raw.colwise().mean().transpose();
  const Eigen::MatrixXd centred = raw.rowwise() - envelope.offset.transpose();
  envelope.scale = (centred.colwise().squaredNorm() / static_cast<double>(n)).cwiseSqrt().transpose();
  for (Eigen::Index c = 0; c < columns; ++c) {
    if (!(envelope.scale[c] > 0)) envelope.scale[c] = 1;  // never moved: any move is far
  }
  const Eigen::MatrixXd z = centred.array().rowwise() / envelope.scale.transpose().array();
  envelope.mean = z.colwise().mean().transpose();
  const Eigen::MatrixXd zc = z.rowwise() - envelope.mean.transpose();
  Eigen::MatrixXd covariance = zc.transpose() * zc / static_cast<double>(n);
  covariance.diagonal().array() += 1e-6;
  envelope.inverse_covariance =
      covariance.ldlt().solve(Eigen::MatrixXd::Identity(columns, columns));
  double stress_sum = 0;
  for (const SurrogateInput& input : training_inputs) {
    stress_sum += material::VoigtToStress(input.stress_pa).norm();
  }
  envelope.stress_floor_pa = std::max(0.1 * stress_sum / static_cast<double>(n), 1.0);
  for (const SurrogateInput& input : training_inputs) {
    envelope.largest_training_distance =
        std::max(envelope.largest_training_distance, envelope.Distance(input));
  }
  return envelope;
}

SurrogateEnsemble SurrogateEnsemble::Train(const std::vector<StrainHistory>& histories,
                                           const MlpArchitecture& architecture,
                                           const TrainingOptions& options, int members,
                                           std::vector<TrainingReport>* reports) {
  if (members < 3 || members > 64) throw InputError("members", "must be in [3, 64]");
  SurrogateEnsemble ensemble;
  for (int k = 0; k < members; ++k) {
    TrainingOptions member_options = options;
    member_options.seed = options.seed + static_cast<std::uint64_t>(k);
    TrainingReport report;
    ensemble.members_.push_back(
        StressSurrogate::Train(histories, architecture, member_options, &report));
    if (reports != nullptr) reports->push_back(report);
  }
  ensemble.FitEnvelopeAndThresholds(histories);
  return ensemble;
}

SurrogateEnsemble SurrogateEnsemble::FineTune(const SurrogateEnsemble& base,
                                              const std::vector<StrainHistory>& histories,
                                              const TrainingOptions& options,
                                              std::vector<TrainingReport>* reports) {
  if (base.members_.size() < 3) throw InputError("model", "the base ensemble has no members");
  SurrogateEnsemble ensemble;
  for (std::size_t k = 0; k < base.members_.size(); ++k) {
    TrainingOptions member_options = options;
    member_options.seed = options.seed + static_cast<std::uint64_t>(k);
    TrainingReport report;
    ensemble.members_.push_back(
        StressSurrogate::FineTune(base.members_[k], histories, member_options, &report));
    if (reports != nullptr) reports->push_back(report);
  }
  ensemble.FitEnvelopeAndThresholds(histories);
  return ensemble;
}

SurrogateEnsemble SurrogateEnsemble::Assemble(std::vector<StressSurrogate> members,
                                              const std::vector<StrainHistory>& histories) {
  if (members.size() < 3 || members.size() > 64) {
    throw InputError("members", "must be 3 to 64 surrogates, not " + std::to_string(members.size()));
  }
  for (const StressSurrogate& member : members) {
    if (member.architecture() != members.front().architecture()) {
      throw InputError("members", "mix architectures (" + members.front().architecture() + ", " +
                                      member.architecture() + ")");
    }
  }
  SurrogateEnsemble ensemble;
  ensemble.members_ = std::move(members);
  ensemble.FitEnvelopeAndThresholds(histories);
  return ensemble;
}

void SurrogateEnsemble::FitEnvelopeAndThresholds(const std::vector<StrainHistory>& histories) {
  std::vector<SurrogateInput> inputs;
  for (const StrainHistory& history : histories) {
    const std::vector<SurrogateInput> steps = InputsOf(history, carried_variables());
    inputs.insert(inputs.end(), steps.begin(), steps.end());
  }
  envelope_ = FitEnvelope(inputs);
  double most_tensile = 0;  // a point with no contact left carries nothing: zero is admissible
  for (const StrainHistory& history : histories) {
    const auto principal = [](const Matrix3& stress) {
      return Eigen::SelfAdjointEigenSolver<Matrix3>(stress, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .maxCoeff();
    };
    most_tensile = std::max(most_tensile, principal(history.initial_stress_pa));
    for (const Vector6& stress : history.stresses_pa) {
      most_tensile = std::max(most_tensile, principal(material::VoigtToStress(stress)));
    }
  }
  envelope_.tensile_limit_pa = most_tensile;
  // The cone: the least ratio of least to most compressive principal stress, measured from the
  // tensile limit, over training stresses above the stress floor (below it a packing's few
  // contacts make any ratio: noise, not strength).
  double least_ratio = 1;
  const auto ratio_of = [&](const Matrix3& stress) {
    if (stress.norm() < envelope_.stress_floor_pa) return;
    const Eigen::Vector3d compression =
        most_tensile -
        Eigen::SelfAdjointEigenSolver<Matrix3>(stress, Eigen::EigenvaluesOnly).eigenvalues().array();
    if (compression.maxCoeff() > 0) {
      least_ratio = std::min(least_ratio, std::max(0.0, compression.minCoeff()) / compression.maxCoeff());
    }
  };
  for (const StrainHistory& history : histories) {
    ratio_of(history.initial_stress_pa);
    for (const Vector6& stress : history.stresses_pa) ratio_of(material::VoigtToStress(stress));
  }
  envelope_.least_principal_ratio = least_ratio;
  distance_threshold_ = envelope_.largest_training_distance;
  spread_threshold_ = 1.0;  // no flag while the training spread is measured
  double largest_spread = 0;
  for (const EnsembleAnswer& answer : Answer(inputs, false)) {
    largest_spread = std::max(largest_spread, answer.relative_spread);
  }
  spread_threshold_ = std::max(kSpreadThresholdFactor * largest_spread, 1e-12);
}

Matrix3 SurrogateEnsemble::Admissible(const Matrix3& stress_pa, bool* capped) const {
  if (capped != nullptr) *capped = false;
  const double limit = envelope_.tensile_limit_pa;
  if (!std::isfinite(limit)) return stress_pa;
  const Eigen::SelfAdjointEigenSolver<Matrix3> principal(stress_pa);
  // Compressions measured from the apex (the tensile limit), the tensile cap applied.
  Eigen::Vector3d compression = (limit - principal.eigenvalues().array()).cwiseMax(0.0);
  bool changed = principal.eigenvalues().maxCoeff() > limit;
  // The cone: min c / max c >= k. A radial return in the deviatoric plane at constant mean
  // compression m: c = m + alpha (c - m) with the largest alpha in [0, 1] that satisfies it,
  // alpha = (1 - k) m / (k d_max - d_min), d the deviator (the Mohr-Coulomb return of a
  // cohesionless soil, whose criterion is exactly this ratio: k = (1 - sin phi) / (1 + sin phi)).
  const double k = envelope_.least_principal_ratio;
  const double mean = compression.mean();
  if (k > 0 && mean > 0 && compression.minCoeff() < k * compression.maxCoeff()) {
    const Eigen::Vector3d deviator = compression.array() - mean;
    const double alpha = (1 - k) * mean / (k * deviator.maxCoeff() - deviator.minCoeff());
    compression = (mean + std::clamp(alpha, 0.0, 1.0) * deviator.array()).matrix();
    changed = true;
  }
  if (!changed) return stress_pa;
  if (capped != nullptr) *capped = true;
  const Eigen::Vector3d values = (limit - compression.array()).matrix();
  return principal.eigenvectors() * values.asDiagonal() * principal.eigenvectors().transpose();
}

void SurrogateEnsemble::SetThresholds(double distance_threshold, double spread_threshold) {
  if (!(distance_threshold > 0)) throw InputError("distance_threshold", "must be positive");
  if (!(spread_threshold > 0)) throw InputError("spread_threshold", "must be positive");
  distance_threshold_ = distance_threshold;
  spread_threshold_ = spread_threshold;
}

void SurrogateEnsemble::SetPressureFloor(double pressure_floor_pa) {
  if (!(std::isfinite(pressure_floor_pa) && pressure_floor_pa >= 0)) {
    throw InputError("pressure_floor_pa", "must be >= 0 Pa (0: no floor)");
  }
  pressure_floor_pa_ = pressure_floor_pa;
}

std::vector<EnsembleAnswer> SurrogateEnsemble::Answer(const std::vector<SurrogateInput>& inputs,
                                                      bool want_tangent) const {
  std::vector<EnsembleAnswer> answers(inputs.size());
  std::vector<std::vector<Vector6>> increments;
  const double members = static_cast<double>(members_.size());
  const Eigen::Index carried = static_cast<Eigen::Index>(carried_variables().size());
  for (EnsembleAnswer& answer : answers) {
    answer.internal_variable_increments = Eigen::VectorXd::Zero(carried);
  }
  for (const StressSurrogate& member : members_) {
    std::vector<Voigt6x6> tangents;
    std::vector<Eigen::VectorXd> internal;
    increments.push_back(member.StressIncrements(inputs, want_tangent ? &tangents : nullptr,
                                                 carried > 0 ? &internal : nullptr));
    for (std::size_t n = 0; n < inputs.size() && want_tangent; ++n) {
      answers[n].tangent_pa += tangents[n] / members;
    }
    for (std::size_t n = 0; n < inputs.size() && carried > 0; ++n) {
      answers[n].internal_variable_increments += internal[n] / members;
    }
  }
  for (std::size_t n = 0; n < inputs.size(); ++n) {
    EnsembleAnswer& answer = answers[n];
    for (const std::vector<Vector6>& member : increments) {
      answer.stress_increment_pa += member[n] / members;
    }
    Vector6 variance = Vector6::Zero();
    for (const std::vector<Vector6>& member : increments) {
      variance += (member[n] - answer.stress_increment_pa).cwiseAbs2() / members;
    }
    answer.relative_spread =
        variance.cwiseSqrt().maxCoeff() /
        StressScale(inputs[n], answer.stress_increment_pa, envelope_.stress_floor_pa);
    answer.distance = envelope_.Distance(inputs[n]);
    answer.mean_pressure_pa = -inputs[n].stress_pa.head<3>().mean();
    answer.below_pressure_floor =
        pressure_floor_pa_ > 0 && answer.mean_pressure_pa < pressure_floor_pa_;
    answer.beyond_distance = answer.distance > distance_threshold_;
    answer.beyond_spread = answer.relative_spread > spread_threshold_;
    answer.out_of_distribution =
        answer.beyond_distance || answer.beyond_spread || answer.below_pressure_floor;
  }
  return answers;
}

void SurrogateEnsemble::Save(const std::string& directory) const {
  std::filesystem::create_directories(directory);
  for (std::size_t k = 0; k < members_.size(); ++k) {
    members_[k].Save((std::filesystem::path(directory) / ("member_" + std::to_string(k) + ".pt"))
                         .string());
  }
  ByteWriter out;
  out.PutTag(kEnvelopeTag);
  out.Put(static_cast<std::uint64_t>(members_.size()));
  PutVector(out, envelope_.offset);
  PutVector(out, envelope_.scale);
  PutVector(out, envelope_.mean);
  for (Eigen::Index i = 0; i < envelope_.offset.size(); ++i) {
    for (Eigen::Index j = 0; j < envelope_.offset.size(); ++j) {
      out.Put(envelope_.inverse_covariance(i, j));
    }
  }
  out.Put(envelope_.largest_training_distance);
  out.Put(envelope_.stress_floor_pa);
  out.Put(envelope_.tensile_limit_pa);
  out.Put(envelope_.least_principal_ratio);
  out.Put(distance_threshold_);
  out.Put(spread_threshold_);
  const std::string path = (std::filesystem::path(directory) / "envelope.bin").string();
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  const std::string bytes = out.Take();
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.close();
  if (!file) throw std::runtime_error("cannot write " + path);
}

SurrogateEnsemble SurrogateEnsemble::Load(const std::string& directory) {
  const std::string path = (std::filesystem::path(directory) / "envelope.bin").string();
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("model", "no ensemble in " + directory + " (no envelope.bin)");
  std::stringstream buffer;
  buffer << file.rdbuf();
  const std::string bytes = buffer.str();
  SurrogateEnsemble ensemble;
  try {
    ByteReader in(bytes);
    const bool without_cap = bytes.compare(0, 8, kEnvelopeTagWithoutCap) == 0;
    const bool without_cone = without_cap || bytes.compare(0, 8, kEnvelopeTagWithoutCone) == 0;
    in.ExpectTag(without_cap ? kEnvelopeTagWithoutCap
                             : without_cone ? kEnvelopeTagWithoutCone : kEnvelopeTag);
    std::uint64_t members = 0;
    in.Get(members);
    if (members < 3 || members > 64) throw InputError("model", "implausible member count");
    ensemble.envelope_.offset = GetVector(in);
    ensemble.envelope_.scale = GetVector(in);
    ensemble.envelope_.mean = GetVector(in);
    const Eigen::Index inputs = ensemble.envelope_.offset.size();
    if (ensemble.envelope_.scale.size() != inputs || ensemble.envelope_.mean.size() != inputs) {
      throw InputError("model", "envelope vectors of different sizes");
    }
    ensemble.envelope_.inverse_covariance.resize(inputs, inputs);
    for (Eigen::Index i = 0; i < inputs; ++i) {
      for (Eigen::Index j = 0; j < inputs; ++j) in.Get(ensemble.envelope_.inverse_covariance(i, j));
    }
    in.Get(ensemble.envelope_.largest_training_distance);
    in.Get(ensemble.envelope_.stress_floor_pa);
    ensemble.envelope_.tensile_limit_pa = std::numeric_limits<double>::infinity();
    if (!without_cap) in.Get(ensemble.envelope_.tensile_limit_pa);
    ensemble.envelope_.least_principal_ratio = 0;
    if (!without_cone) in.Get(ensemble.envelope_.least_principal_ratio);
    in.Get(ensemble.distance_threshold_);
    in.Get(ensemble.spread_threshold_);
    if (!in.AtEnd()) throw InputError("model", "trailing bytes in envelope.bin");
    for (std::uint64_t k = 0; k < members; ++k) {
      ensemble.members_.push_back(StressSurrogate::Load(
          (std::filesystem::path(directory) / ("member_" + std::to_string(k) + ".pt")).string()));
      if (ensemble.members_.back().architecture() != ensemble.members_.front().architecture()) {
        throw InputError("model", "members of different architectures");
      }
    }
    if (static_cast<std::size_t>(inputs - kInputs) != ensemble.carried_variables().size()) {
      throw InputError("model", "the envelope's inputs are not the members'");
    }
  } catch (const InputError& e) {
    if (e.field() == "model") throw;
    throw InputError("model", std::string("envelope.bin: ") + e.what());
  }
  return ensemble;
}

std::vector<Vector6> Replay(const SurrogateEnsemble& ensemble, const StrainHistory& history) {
  return Replay(
      [&](const SurrogateInput& input) {
        const EnsembleAnswer answer = ensemble.Answer({input}, false)[0];
        return SurrogateOutput{answer.stress_increment_pa, answer.internal_variable_increments};
      },
      history, ensemble.carried_variables(),
      [&](const Matrix3& stress_pa) { return ensemble.Admissible(stress_pa); });
}

double ReplayError(const SurrogateEnsemble& ensemble, const StrainHistory& history) {
  return ReplayError(Replay(ensemble, history), history);
}

}  // namespace gonogo::ann
