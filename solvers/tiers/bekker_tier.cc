#include "solvers/tiers/bekker_tier.h"

#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::tiers {

using namespace terramech;

namespace {

std::string KnownSoils(const BekkerSoilLibrary& library) {
  std::string list;
  for (const std::string& name : library.Names()) list += (list.empty() ? "" : ", ") + name;
  return list;
}

}  // namespace

BekkerTier::BekkerTier() : BekkerTier(BekkerSoilLibrary::Builtin()) {}

BekkerTier::BekkerTier(BekkerSoilLibrary library, WongReeceOptions options)
    : library_(std::move(library)), options_(options) {
  options_.Validate("options.");
}

BekkerParameters BekkerTier::ResolveSoil(const SoilState& soil, const std::string& field) const {
  if (soil.parameters) {
    Require(soil.parameters->model == "bekker", field + ".parameters.model",
            "the bekker tier reads parameters of the bekker soil model, not '" +
                soil.parameters->model + "'");
    return BekkerParameters::FromSoilModel(
        SoilModels().Validate(*soil.parameters, field + ".parameters"));
  }
  if (const BekkerSoil* entry = library_.Find(soil.soil_name)) return entry->parameters;
  throw InputError(field,
                   (soil.soil_name.empty()
                        ? std::string("the bekker tier needs Bekker parameters or a soil name")
                        : "unknown soil name '" + soil.soil_name + "'") +
                       "; known soils: " + KnownSoils(library_));
}

void BekkerTier::ValidateSoil(const SoilState& soil, const std::string& field) const {
  ResolveSoil(soil, field);
}

namespace {
// The curve point of a solved wheel state (rigid or flexible: both carry these fields).
template <typename WheelState>
TractionPoint PointOf(double slip, const WheelState& s) {
  return TractionPoint{slip,
                       s.drawbar_pull_n,
                       s.torque_nm,
                       s.sinkage_m,
                       s.tractive_efficiency,
                       s.gross_traction_n,
                       s.motion_resistance_n};
}
}  // namespace

TierDescription BekkerTier::Describe() const {
  return {"Bekker-Wong pressure-sinkage, Janosi-Hanamoto shear; Wong-Reece rigid wheel or Wong's "
          "elastic tyre",
          "soil name (bekker soil library) or explicit Bekker parameters; tyre diameter, width, "
          "inflation pressure, deflection; wheel load",
          "about 5 ms for 100 slips",
          {"bekker"}};
}

TractionCurve BekkerTier::ComputeCurve(const TractionRequest& request,
                                       const ComputeContext& context) const {
  request.Validate();
  const BekkerParameters soil = ResolveSoil(request.soil, "soil");
  const TyreGeometry& tyre = request.tyre;
  const double load_n = request.wheel_load_n;
  // Rigid or elastic mode [W08] 2.7.2: p_i + p_c against the critical ground pressure, p_c = 0.
  const double inflation_pa = tyre.inflation_pressure_pa;
  const bool rigid =
      inflation_pa <= 0 ||
      inflation_pa >= CriticalGroundPressurePa(soil, tyre.diameter_m, tyre.width_m, load_n);
  const double radius_m = 0.5 * tyre.diameter_m;

  TractionCurve curve;
  curve.tier = Name();
  curve.tier_version = Version();
  curve.points.reserve(request.slips.size());
  double entry_angle_rad = 0;  // previous slip's theta_1: narrows the next bracket
  try {
    for (double slip : request.slips) {
      if (context.Cancelled()) throw CancelledError();
      if (rigid) {
        const RigidWheelState s =
            SolveRigidWheel(soil, radius_m, tyre.width_m, load_n, slip, options_, entry_angle_rad);
        entry_angle_rad = s.entry_angle_rad;
        curve.points.push_back(PointOf(slip, s));
      } else {
        curve.points.push_back(
            PointOf(slip, SolveFlexibleTyre(soil, tyre, inflation_pa, load_n, slip)));
      }
    }
  } catch (const CannotCarryError& e) {
    // Sinkage grows with slip, so one slip the soil cannot carry makes the wheel immobile.
    curve.points.clear();
    curve.immobile_reason = e.what();
  }
  return curve;
}

}  // namespace gonogo::tiers
