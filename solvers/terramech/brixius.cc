#include "solvers/terramech/brixius.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "solvers/common/errors.h"

namespace gonogo::terramech {

namespace {

// VTI fine-grained constants [D18].
constexpr double kSinkageLoadExponent = 1.5;  // (1 - delta/h)^(3/2) in N_cz, eq. (3)
constexpr double kAspectExponent = 0.75;      // (1 + b/d)^(3/4) in N_c, eq. (1)
constexpr double kSelfPropelledScale = 21.0;  // S_sp = 21 / N_c^2.5 + 0.005, eq. (2)
constexpr double kSelfPropelledExponent = 2.5;
constexpr double kSelfPropelledFloor = 0.005;
constexpr double kPoweredSinkageScale = 1.64;  // z/d = 1.64 / (N_cz / S_sp^0.19)^1.21, eq. (21)
constexpr double kPoweredSinkageSlipExp = 0.19;
constexpr double kPoweredSinkageExponent = 1.21;

void RequireMobilityNumber(double mobility_number) {
  Require(std::isfinite(mobility_number) && mobility_number >= 0, "mobility_number",
          "must be a finite number >= 0");
}

void RequireSlip(double slip) {
  Require(std::isfinite(slip) && slip >= 0 && slip <= 1, "slip", "must lie in [0, 1]");
}

void RequireWheel(double cone_index_pa, const TyreGeometry& tyre, double wheel_load_n) {
  Require(std::isfinite(cone_index_pa) && cone_index_pa >= 0, "cone_index_pa",
          "must be a finite number >= 0");
  tyre.Validate("tyre.");
  Require(std::isfinite(wheel_load_n) && wheel_load_n > 0, "wheel_load_n",
          "must be a positive number of newtons");
}

}  // namespace

double MobilityNumber(double cone_index_pa, const TyreGeometry& tyre, double wheel_load_n) {
  RequireWheel(cone_index_pa, tyre, wheel_load_n);
  const double b = tyre.width_m;
  const double d = tyre.diameter_m;
  // Wheel numeric C_n = CI b d / W, [B87] eq. (16).
  const double wheel_numeric = cone_index_pa * b * d / wheel_load_n;
  // Bn = C_n (1 + 5 delta/h) / (1 + 3 b/d), [B87] eq. (17).
  return wheel_numeric *
         (1.0 + kBrixiusDeflectionWeight * tyre.deflection_m / tyre.section_height_m) /
         (1.0 + kBrixiusAspectWeight * b / d);
}

double GrossTractionRatio(double mobility_number, double slip) {
  RequireMobilityNumber(mobility_number);
  RequireSlip(slip);
  // GT/W = 0.88 (1 - e^(-0.1 Bn)) (1 - e^(-7.5 s)) + 0.04, [B87] eq. (21).
  return kBrixiusTractionScale * -std::expm1(-kBrixiusMobilityRate * mobility_number) *
             -std::expm1(-kBrixiusSlipRate * slip) +
         kBrixiusTyreLossRatio;
}

double MotionResistanceRatio(double mobility_number, double slip) {
  RequireMobilityNumber(mobility_number);
  RequireSlip(slip);
  // Bn -> 0: 1/Bn diverges; the capped limit is returned without forming 0 * inf.
  if (mobility_number <= 0) return kMaxMotionResistanceRatio;
  // MR/W = 1/Bn + 0.04 + 0.5 s / sqrt(Bn), [B87] eqs. (19)-(20).
  const double ratio = 1.0 / mobility_number + kBrixiusTyreLossRatio +
                       kBrixiusSlipResistance * slip / std::sqrt(mobility_number);
  return std::min(ratio, kMaxMotionResistanceRatio);
}

double NetTractionRatio(double mobility_number, double slip) {
  return GrossTractionRatio(mobility_number, slip) - MotionResistanceRatio(mobility_number, slip);
}

double TractiveEfficiency(double mobility_number, double slip) {
  return EvaluateBrixius(mobility_number, slip).tractive_efficiency;
}

BrixiusRatios EvaluateBrixius(double mobility_number, double slip) {
  BrixiusRatios r;
  r.gross_traction = GrossTractionRatio(mobility_number, slip);
  r.motion_resistance = MotionResistanceRatio(mobility_number, slip);
  r.net_traction = r.gross_traction - r.motion_resistance;
  // TE = (NT/GT)(1 - s); GT >= 0.04 W > 0, so the quotient is always defined.
  r.tractive_efficiency =
      r.net_traction > 0 ? r.net_traction / r.gross_traction * (1.0 - slip) : 0.0;
  return r;
}

double FineGrainedSinkageNumeric(double cone_index_pa, const TyreGeometry& tyre,
                                 double wheel_load_n) {
  RequireWheel(cone_index_pa, tyre, wheel_load_n);
  // N_cz = CI b d / (W (1 - delta/h)^(3/2)), [D18] eq. (3). delta < h is checked by Validate.
  const double unloaded = 1.0 - tyre.deflection_m / tyre.section_height_m;
  return cone_index_pa * tyre.width_m * tyre.diameter_m /
         (wheel_load_n * std::pow(unloaded, kSinkageLoadExponent));
}

double FineGrainedNumeric(double sinkage_numeric, const TyreGeometry& tyre) {
  Require(std::isfinite(sinkage_numeric) && sinkage_numeric >= 0, "sinkage_numeric",
          "must be a finite number >= 0");
  tyre.Validate("tyre.");
  // N_c = N_cz / (1 + b/d)^(3/4), [D18] eq. (1).
  return sinkage_numeric / std::pow(1.0 + tyre.width_m / tyre.diameter_m, kAspectExponent);
}

double SelfPropelledSlip(double fine_grained_numeric) {
  Require(std::isfinite(fine_grained_numeric) && fine_grained_numeric >= 0, "fine_grained_numeric",
          "must be a finite number >= 0");
  if (fine_grained_numeric <= 0) return std::numeric_limits<double>::infinity();
  // S_sp = 21 / N_c^2.5 + 0.005, [D18] eq. (2).
  return kSelfPropelledScale / std::pow(fine_grained_numeric, kSelfPropelledExponent) +
         kSelfPropelledFloor;
}

double PoweredSinkageRatio(double sinkage_numeric, double fine_grained_numeric) {
  Require(std::isfinite(sinkage_numeric) && sinkage_numeric >= 0, "sinkage_numeric",
          "must be a finite number >= 0");
  // Zero soil strength: the tyre sinks until it is buried.
  if (sinkage_numeric <= 0 || fine_grained_numeric <= 0) return 1.0;
  // z/d = 1.64 / (N_cz / S_sp^0.19)^1.21, [D18] eq. (21).
  const double slip_term =
      std::pow(SelfPropelledSlip(fine_grained_numeric), kPoweredSinkageSlipExp);
  const double ratio =
      kPoweredSinkageScale / std::pow(sinkage_numeric / slip_term, kPoweredSinkageExponent);
  // `!(ratio < 1)` also catches inf when N_cz underflows relative to S_sp.
  if (!(ratio < 1.0)) return 1.0;
  return std::max(ratio, 0.0);
}

double PoweredSinkage(double cone_index_pa, const TyreGeometry& tyre, double wheel_load_n) {
  const double n_cz = FineGrainedSinkageNumeric(cone_index_pa, tyre, wheel_load_n);
  const double n_c = FineGrainedNumeric(n_cz, tyre);
  return tyre.diameter_m * PoweredSinkageRatio(n_cz, n_c);
}

}  // namespace gonogo::terramech
