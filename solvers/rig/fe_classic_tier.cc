#include "solvers/rig/fe_classic_tier.h"

#include "solvers/common/errors.h"

namespace gonogo::rig {

const FeSoil& FeClassicTier::ResolveSoil(const SoilState& soil, const std::string& field) const {
  Require(!soil.bekker.has_value(), field + ".bekker",
          "the fe-classic tier reads a soil library name, not Bekker parameters");
  const FeSoil* found = library_.Find(soil.soil_name);
  if (found == nullptr) {
    std::string known;
    for (const std::string& name : library_.Names()) known += (known.empty() ? "" : ", ") + name;
    throw InputError(field + ".soil_name",
                     (soil.soil_name.empty() ? std::string("is missing")
                                             : "unknown fe-classic soil '" + soil.soil_name + "'") +
                         "; known: " + known);
  }
  return *found;
}

void FeClassicTier::ValidateSoil(const SoilState& soil, const std::string& field) const {
  ResolveSoil(soil, field);
}

TierDescription FeClassicTier::Describe() const {
  return {"explicit FE soil bin (hex8, total Lagrangian) with a Drucker-Prager closure; rigid "
          "wheel through seed 001's drawbar-pull procedure",
          "soil name (fe-classic soil library); tyre diameter and width; wheel load",
          "minutes on one core"};
}

TierNeeds FeClassicTier::Needs(const TractionRequest& /*request*/) const {
  TierNeeds needs;
  needs.threads = options_.threads;
  needs.expected_seconds = 300;
  return needs;
}

TractionCurve FeClassicTier::ComputeCurve(const TractionRequest& request,
                                          const ComputeContext& context) const {
  request.Validate();
  const FeSoil& soil = ResolveSoil(request.soil, "soil");
  RigWheel wheel;
  wheel.radius_m = 0.5 * request.tyre.diameter_m;
  wheel.width_m = request.tyre.width_m;
  wheel.load_n = request.wheel_load_n;
  RigOptions options;
  options.elements_per_radius = options_.elements_per_radius;
  options.threads = options_.threads;
  options.cancelled = context.cancelled;
  options.progress = context.progress;
  TractionCurve curve;
  curve.tier = Name();
  curve.tier_version = Version();
  try {
    const RigRun run = RunDrawbarPullTest(soil, wheel, DrawbarPullProcedure{}, options);
    curve.points = CurveFromRun(run, request.slips, wheel.radius_m);
  } catch (const CannotCarryError& e) {
    curve.points.clear();
    curve.immobile_reason = e.what();
  }
  return curve;
}

}  // namespace gonogo::rig
