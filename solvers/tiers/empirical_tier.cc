#include "solvers/tiers/empirical_tier.h"

namespace gonogo::tiers {

using namespace terramech;

TierDescription EmpiricalTier::Describe() const {
  return {"Brixius (1987) WES mobility-number traction equations; NRMM soft-soil test per vehicle",
          "cone index; tyre diameter, width, section height, deflection; wheel load",
          "microseconds",
          {}};
}

TractionCurve EmpiricalTier::ComputeCurve(const TractionRequest& request,
                                          const ComputeContext& /*context*/) const {
  request.Validate();
  const double load_n = request.wheel_load_n;
  const TyreGeometry& tyre = request.tyre;
  // Brixius is dimensionless: CI in Pa with b, d in m and W in N gives Bn directly.
  const double mobility_number = MobilityNumber(request.soil.cone_index_pa, tyre, load_n);
  const double sinkage_m = PoweredSinkage(request.soil.cone_index_pa, tyre, load_n);
  const double rolling_radius_m = tyre.RollingRadius();

  TractionCurve curve;
  curve.tier = Name();
  curve.tier_version = Version();
  curve.points.reserve(request.slips.size());
  for (double slip : request.slips) {
    const BrixiusRatios ratios = EvaluateBrixius(mobility_number, slip);
    TractionPoint p;
    p.slip = slip;
    p.gross_traction_n = ratios.gross_traction * load_n;
    p.motion_resistance_n = ratios.motion_resistance * load_n;
    p.drawbar_pull_n = ratios.net_traction * load_n;
    p.torque_nm = p.gross_traction_n * rolling_radius_m;
    p.tractive_efficiency = ratios.tractive_efficiency;
    p.sinkage_m = sinkage_m;
    curve.points.push_back(p);
  }
  return curve;
}

}  // namespace gonogo::tiers
