#include "solvers/tiers/diagnostic_tiers.h"

#include <chrono>
#include <memory>
#include <thread>

#include "solvers/tiers/empirical_tier.h"

namespace gonogo {

namespace tiers {
namespace {

// Holds for `hold_ms` in 10 ms steps, polling cancellation and reporting progress at each, then
// answers with the empirical tier's curve under `tier`'s name and version.
TractionCurve HoldThenAnswer(const TractionTier& tier, const TractionRequest& request,
                             const ComputeContext& context, int hold_ms) {
  for (int waited = 0; waited < hold_ms; waited += 10) {
    if (context.Cancelled()) throw CancelledError();
    context.Report(static_cast<double>(waited) / hold_ms);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  TractionCurve curve = EmpiricalTier().Compute(request);
  curve.tier = tier.Name();
  curve.tier_version = tier.Version();
  return curve;
}

class RankGroupProbeTier : public TractionTier {
 public:
  std::string Name() const override { return "diagnostic-rank-group"; }
  std::string Version() const override { return "diagnostic-rank-group-1"; }
  TierDescription Describe() const override {
    return {"diagnostic: runs collectively on a 2-rank group and answers with the empirical curve",
            "cone index; tyre; wheel load", "about 2 s on 2 ranks", {}};
  }
  TierNeeds Needs(const TractionRequest&) const override {
    TierNeeds needs;
    needs.ranks = 2;
    needs.expected_seconds = kGroupHoldMs / 1000.0;
    return needs;
  }

 protected:
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override {
    if (context.communicator != MPI_COMM_NULL) {
      int size = 0, ones = 0, one = 1;
      MPI_Comm_size(context.communicator, &size);
      MPI_Allreduce(&one, &ones, 1, MPI_INT, MPI_SUM, context.communicator);
      if (size != 2 || ones != size) {
        throw std::logic_error("rank group of " + std::to_string(size) + " ranks, all-reduce " +
                               std::to_string(ones));
      }
    }
    // Every member makes the same number of (collective) cancellation checks.
    return HoldThenAnswer(*this, request, context, kGroupHoldMs);
  }
};

class NumericalFailureProbeTier : public TractionTier {
 public:
  std::string Name() const override { return "diagnostic-numerical-failure"; }
  std::string Version() const override { return "diagnostic-numerical-failure-1"; }
  TierDescription Describe() const override {
    return {"diagnostic: fails as a solver that cannot converge does", "nothing", "none", {}};
  }

 protected:
  TractionCurve ComputeCurve(const TractionRequest&, const ComputeContext&) const override {
    throw NumericalError("diagnostic: the solver did not converge (by design of this tier)");
  }
};

class SlowCurveProbeTier : public TractionTier {
 public:
  std::string Name() const override { return "diagnostic-slow-curve"; }
  std::string Version() const override { return "diagnostic-slow-curve-1"; }
  TierDescription Describe() const override {
    return {"diagnostic: declares an hour a curve, takes 1.5 s, answers with the empirical curve",
            "cone index; tyre; wheel load", "declared 1 h, really 1.5 s", {}};
  }
  TierNeeds Needs(const TractionRequest&) const override {
    TierNeeds needs;
    needs.expected_seconds = 3600;
    return needs;
  }

 protected:
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override {
    return HoldThenAnswer(*this, request, context, kSlowCurveMs);
  }
};

}  // namespace
}  // namespace tiers

void RegisterDiagnosticTiers(TierRegistry& registry) {
  registry.Register(std::make_unique<tiers::RankGroupProbeTier>());
  registry.Register(std::make_unique<tiers::NumericalFailureProbeTier>());
  registry.Register(std::make_unique<tiers::SlowCurveProbeTier>());
}

}  // namespace gonogo
