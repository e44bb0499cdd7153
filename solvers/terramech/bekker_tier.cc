#include "solvers/terramech/bekker_tier.h"

#include <utility>

#include "solvers/common/errors.h"

namespace gonogo::terramech {

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
  if (soil.bekker) {
    soil.bekker->Validate(field + ".bekker.");
    return *soil.bekker;
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

TractionCurve BekkerTier::Compute(const TractionRequest& request) const {
  return Compute(request, nullptr);
}

TractionCurve BekkerTier::Compute(const TractionRequest& request,
                                  const CancelCheck& cancelled) const {
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
      if (cancelled && cancelled()) throw CancelledError();
      TractionPoint p;
      p.slip = slip;
      if (rigid) {
        const RigidWheelState s =
            SolveRigidWheel(soil, radius_m, tyre.width_m, load_n, slip, options_, entry_angle_rad);
        entry_angle_rad = s.entry_angle_rad;
        p.drawbar_pull_n = s.drawbar_pull_n;
        p.torque_nm = s.torque_nm;
        p.sinkage_m = s.sinkage_m;
        p.tractive_efficiency = s.tractive_efficiency;
        p.gross_traction_n = s.gross_traction_n;
        p.motion_resistance_n = s.motion_resistance_n;
      } else {
        const FlexibleTyreState s = SolveFlexibleTyre(soil, tyre, inflation_pa, load_n, slip);
        p.drawbar_pull_n = s.drawbar_pull_n;
        p.torque_nm = s.torque_nm;
        p.sinkage_m = s.sinkage_m;
        p.tractive_efficiency = s.tractive_efficiency;
        p.gross_traction_n = s.gross_traction_n;
        p.motion_resistance_n = s.motion_resistance_n;
      }
      curve.points.push_back(p);
    }
  } catch (const CannotCarryError& e) {
    // Sinkage grows with slip, so one slip the soil cannot carry makes the wheel immobile.
    curve.points.clear();
    curve.immobile_reason = e.what();
  }
  return curve;
}

}  // namespace gonogo::terramech
