#include "solvers/ann/rve_point_studies.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "solvers/ann/point_driver.h"
#include "solvers/common/errors.h"

namespace gonogo::ann {
namespace {

// The mean stress p (compression positive) and the deviatoric stress q (von Mises) of a
// tension-positive Cauchy stress, Pa.
struct MeanAndDeviatoric {
  double p = 0, q = 0;
};
MeanAndDeviatoric StressInvariants(const Matrix3& sigma) {
  const double p = -sigma.trace() / 3;
  const Matrix3 deviator = sigma + p * Matrix3::Identity();
  return {p, std::sqrt(1.5 * deviator.squaredNorm())};
}

}  // namespace

void RunRestTest(const dem::rve::RveMaterial& rve, const RestTestOptions& options,
                 const std::string& label) {
  dem::rve::Rve settled = rve.initial();
  settled.SettleIsotropic(options.pressure_kpa * 1e3);
  std::unique_ptr<material::MaterialState> state = rve.RestoreState(settled.Save());
  std::printf(
      "# rest test, %s: settled at %g kPa, compressed by %g along z (lateral strains "
      "held), then %d zero increments\n",
      label.c_str(), options.pressure_kpa, options.axial_strain, options.zero_increments);
  const auto step_once = [&](const Matrix3& increment, const std::string& what) {
    material::PointIncrement point;
    point.committed = state.get();
    point.displacement_gradient_increment = increment;
    std::vector<material::PointResponse> answer = rve.Update({point}, false);
    if (answer.at(0).status != material::UpdateStatus::kOk) {
      throw NumericalError(what + ": " + answer.at(0).reason);
    }
    state = std::move(answer.at(0).state);
    return answer.at(0).stress_pa;
  };
  constexpr int kLoadingSteps = 20;
  Matrix3 compression = Matrix3::Zero();
  compression(2, 2) = -options.axial_strain / kLoadingSteps;
  if (options.axial_strain > 0) {
    for (int step = 0; step < kLoadingSteps; ++step) {
      step_once(compression, "loading step " + std::to_string(step));
    }
  }
  std::printf("step,p_pa,q_pa,p_change_pct,q_change_pct\n");
  double first_p = 0, first_q = 0;
  for (int step = 0; step <= options.zero_increments; ++step) {
    const auto [p, q] =
        StressInvariants(step_once(Matrix3::Zero(), "rest step " + std::to_string(step)));
    if (step == 0) first_p = p, first_q = q;
    if (step % 10 == 0 || step == options.zero_increments) {
      std::printf("%d,%.1f,%.1f,%.3f,%.3f\n", step, p, q, 100 * (p - first_p) / first_p,
                  first_q > 0 ? 100 * (q - first_q) / first_q : 0.0);
    }
  }
}

void RunIncrementStudy(const dem::rve::RveMaterial& rve, const IncrementStudyOptions& options,
                       const std::string& label) {
  LabPathSpec spec;
  spec.path = options.path;
  spec.pressure_pa = options.pressure_kpa * 1e3;
  spec.max_strain = spec.path == LabPath::kSimpleShear ? 0.1 : 0.05;
  for (int steps : options.step_counts) {  // every count refused before any path runs
    spec.steps = steps;
    spec.Validate("--increment-steps.");
  }
  std::printf("# increment study, %s: %s at %g kPa to %g strain\n", label.c_str(),
              LabPathName(spec.path).c_str(), options.pressure_kpa, spec.max_strain);
  std::printf("steps,fraction,strain,p_pa,q_pa,seconds\n");
  DriverOptions driver;
  driver.relative_tolerance = 0.02;  // as the training paths (tiers::RunLabPaths)
  for (int steps : options.step_counts) {
    spec.steps = steps;
    const auto start = std::chrono::steady_clock::now();
    const StrainHistory history = RunLabPath(rve, spec, driver);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!history.stopped_reason.empty()) {
      std::printf("# %d steps stopped: %s\n", steps, history.stopped_reason.c_str());
    }
    const int settle = spec.settle_steps;  // recorded first
    for (double fraction : {0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0}) {
      const int step = settle + static_cast<int>(std::lround(fraction * steps)) - 1;
      if (step < 0 || step >= static_cast<int>(history.stresses_pa.size())) continue;
      const auto [p, q] = StressInvariants(
          material::VoigtToStress(history.stresses_pa[static_cast<std::size_t>(step)]));
      std::printf("%d,%.2f,%.4f,%.1f,%.1f,%.2f\n", steps, fraction, fraction * spec.max_strain, p,
                  q, seconds);
    }
  }
}

}  // namespace gonogo::ann
