#include "solvers/tiers/fe_classic_tier.h"

#include "solvers/common/errors.h"

namespace gonogo::tiers {

using rig::CurveFromRun;
using rig::DrawbarPullProcedure;
using rig::FeSoil;
using rig::RigOptions;
using rig::RigRun;
using rig::RigWheel;
using rig::RunDrawbarPullTest;

FeSoil FeClassicTier::ResolveSoil(const SoilState& soil, const std::string& field) const {
  if (soil.parameters) {
    Require(soil.parameters->model == "drucker-prager", field + ".parameters.model",
            "the fe-classic tier reads parameters of the drucker-prager soil model, not '" +
                soil.parameters->model + "'");
    const SoilParameters p = SoilModels().Validate(*soil.parameters, field + ".parameters");
    FeSoil explicit_soil;
    explicit_soil.name = CanonicalText(p);
    explicit_soil.density_kg_m3 = p.Get("density_kg_m3");
    explicit_soil.strength.young_pa = p.Get("young_pa");
    explicit_soil.strength.poisson = p.Get("poisson");
    explicit_soil.strength.cohesion_pa = p.Get("cohesion_pa");
    explicit_soil.strength.friction_angle_deg = p.Get("friction_angle_deg");
    explicit_soil.strength.dilation_angle_deg = p.Get("dilation_angle_deg");
    explicit_soil.source = "explicit parameters";
    explicit_soil.Validate(field + ".parameters.");
    return explicit_soil;
  }
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
          "soil name (fe-classic soil library) or drucker-prager parameters; tyre diameter and "
          "width; wheel load",
          "minutes on one core",
          {"drucker-prager"}};
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
  const FeSoil soil = ResolveSoil(request.soil, "soil");
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

}  // namespace gonogo::tiers
