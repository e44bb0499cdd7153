#include "solvers/material/constitutive.h"

#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>

#include "solvers/common/errors.h"
#include "solvers/material/point_store.h"

namespace gonogo::material {

ElasticModuli ConstitutiveModel::InitialElasticModuli() const {
  const std::unique_ptr<MaterialState> fresh = InitialState();
  std::vector<PointIncrement> zero(1);  // displacement_gradient_increment is zero by default
  zero[0].committed = fresh.get();
  const std::vector<PointResponse> responses = Update(zero, /*want_tangent=*/true);
  if (responses.size() != 1 || responses[0].status != UpdateStatus::kOk ||
      !responses[0].has_tangent) {
    throw std::logic_error(Name() + ": a zero increment on a fresh point gave no tangent" +
                           (responses.empty() ? std::string() : ": " + responses[0].reason));
  }
  const Voigt6x6& tangent = responses[0].tangent_pa;
  ElasticModuli moduli;
  // Isotropic D: upper-left block = K 1 1^T + 2G (I - 1 1^T / 3), whose entries sum to 9K.
  moduli.bulk_pa = tangent.topLeftCorner<3, 3>().sum() / 9.0;
  // Shear block with engineering shear strains: D(3,3) = D(4,4) = D(5,5) = G.
  moduli.shear_pa = tangent.diagonal().tail<3>().mean();
  return moduli;
}

std::unique_ptr<MaterialPointStore> ConstitutiveModel::MakePointStore() const {
  return std::make_unique<LocalPointStore>(*this);
}

Matrix3 StressOfState(const ConstitutiveModel& model, const MaterialState& state,
                      const std::string& what) {
  PointIncrement zero;  // displacement_gradient_increment is zero by default
  zero.committed = &state;
  const std::vector<PointResponse> responses = model.Update({zero}, /*want_tangent=*/false);
  if (responses.size() != 1 || responses[0].status != UpdateStatus::kOk) {
    throw NumericalError(what + ": a zero increment failed" +
                         (responses.empty() ? std::string() : ": " + responses[0].reason));
  }
  return responses[0].stress_pa;
}

std::vector<PointResponse> UpdateEachPoint(
    const std::vector<PointIncrement>& increments,
    const std::function<PointResponse(const PointIncrement&)>& update_one) {
  const int count = static_cast<int>(increments.size());
  std::vector<PointResponse> responses(increments.size());
#pragma omp parallel for schedule(static)
  for (int i = 0; i < count; ++i) {
    // No exception may leave an OpenMP region.
    try {
      responses[i] = update_one(increments[i]);
    } catch (const std::exception& error) {
      responses[i] = PointResponse();
      responses[i].reason = error.what();
    }
  }
  return responses;
}

std::string PackDoubles(const double* values, std::size_t count) {
  return std::string(reinterpret_cast<const char*>(values), count * sizeof(double));
}

std::vector<double> UnpackDoubles(const std::string& bytes, std::size_t count,
                                  const std::string& field) {
  Require(bytes.size() == count * sizeof(double), field,
          "expected " + std::to_string(count * sizeof(double)) + " bytes (" +
              std::to_string(count) + " doubles), got " + std::to_string(bytes.size()));
  std::vector<double> values(count);
  std::memcpy(values.data(), bytes.data(), bytes.size());
  for (double value : values) Require(std::isfinite(value), field, "holds a non-finite value");
  return values;
}

}  // namespace gonogo::material
