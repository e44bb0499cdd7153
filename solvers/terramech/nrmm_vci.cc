#include "solvers/terramech/nrmm_vci.h"

#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::terramech {

namespace {

bool PositiveFinite(double v) { return std::isfinite(v) && v > 0; }

// Break points (kips per axle) and pieces of the weight factor, [RN71].
constexpr double kWeightBreakLightKips = 2.0;
constexpr double kWeightBreakMediumKips = 13.5;
constexpr double kWeightBreakHeavyKips = 20.0;

constexpr double kTyreFactorOffsetIn = 10.0;  // TF = (10 + b_in) / 100
constexpr double kTyreFactorScaleIn = 100.0;
constexpr double kClearanceScaleIn = 10.0;  // CF = clearance_in / 10
constexpr double kPenaltyFactor = 1.05;     // GF with chains, EF underpowered, TrF manual
constexpr double kEnginePowerThresholdHpPerTon = 10.0;

// VCI relations, psi [PW06], [RN71].
constexpr double kVci1BranchMi = 115.0;
constexpr double kDcfExponent = 0.25;

}  // namespace

void WheeledVehicle::Validate(const std::string& p) const {
  Require(PositiveFinite(gross_mass_kg), p + "gross_mass_kg", "must be a positive number of kg");
  Require(axle_count >= 1, p + "axle_count", "must be at least 1");
  Require(tyre_count >= axle_count, p + "tyre_count", "must be at least the number of axles");
  Require(PositiveFinite(tyre_width_m), p + "tyre_width_m", "must be a positive number of metres");
  Require(PositiveFinite(tyre_diameter_m), p + "tyre_diameter_m",
          "must be a positive number of metres");
  Require(tyre_width_m < tyre_diameter_m, p + "tyre_width_m", "must be less than the diameter");
  Require(std::isfinite(ground_clearance_m) && ground_clearance_m >= 0, p + "ground_clearance_m",
          "must be zero or a positive number of metres");
  Require(PositiveFinite(engine_power_w), p + "engine_power_w", "must be a positive number of W");
  Require(std::isfinite(tyre_deflection_ratio) && tyre_deflection_ratio > 0 &&
              tyre_deflection_ratio < 1,
          p + "tyre_deflection_ratio", "must lie in (0, 1)");
}

double WeightFactor(double axle_load_kips) {
  Require(std::isfinite(axle_load_kips) && axle_load_kips >= 0, "axle_load_kips",
          "must be a finite number >= 0");
  const double x = axle_load_kips;
  if (x < kWeightBreakLightKips) return 0.553 * x;
  if (x <= kWeightBreakMediumKips) return 0.033 * x + 1.050;
  if (x <= kWeightBreakHeavyKips) return 0.142 * x - 0.420;
  return 0.278 * x - 3.115;
}

MobilityIndexFactors ComputeMobilityIndex(const WheeledVehicle& v) {
  v.Validate("vehicle.");
  // US customary quantities the fits were made in.
  const double weight_lb = v.gross_mass_kg / kKilogramsPerPound;  // lbf under standard gravity
  const double weight_kips = weight_lb / kPoundsPerKip;
  const double width_in = v.tyre_width_m / kMetresPerInch;
  const double diameter_in = v.tyre_diameter_m / kMetresPerInch;
  const double clearance_in = v.ground_clearance_m / kMetresPerInch;
  const double power_hp = v.engine_power_w / kWattsPerHorsepower;
  const double weight_tons = weight_lb / kPoundsPerShortTon;

  MobilityIndexFactors f;
  f.contact_pressure = weight_lb / (v.tyre_count * width_in * 0.5 * diameter_in);
  f.weight = WeightFactor(weight_kips / v.axle_count);
  f.tyre = (kTyreFactorOffsetIn + width_in) / kTyreFactorScaleIn;
  f.grouser = v.chains ? kPenaltyFactor : 1.0;
  f.wheel_load = weight_kips / (2.0 * v.axle_count);
  f.clearance = clearance_in / kClearanceScaleIn;
  f.engine = power_hp / weight_tons >= kEnginePowerThresholdHpPerTon ? 1.0 : kPenaltyFactor;
  f.transmission = v.automatic_transmission ? 1.0 : kPenaltyFactor;
  // MI = (CPF WF / (TF GF) + WLF - CF) EF TrF.
  f.mobility_index =
      (f.contact_pressure * f.weight / (f.tyre * f.grouser) + f.wheel_load - f.clearance) *
      f.engine * f.transmission;
  return f;
}

double DeflectionCorrectionFactor(double tyre_deflection_ratio) {
  Require(std::isfinite(tyre_deflection_ratio) && tyre_deflection_ratio > 0 &&
              tyre_deflection_ratio < 1,
          "tyre_deflection_ratio", "must lie in (0, 1)");
  return std::pow(kReferenceDeflectionRatio / tyre_deflection_ratio, kDcfExponent);
}

double OnePassVciPsi(double mobility_index, double deflection_correction) {
  Require(std::isfinite(mobility_index), "mobility_index", "must be finite");
  Require(PositiveFinite(deflection_correction), "deflection_correction", "must be positive");
  const double mi = std::max(mobility_index, 0.0);
  if (mi <= kVci1BranchMi) return (11.48 + 0.2 * mi - 39.2 / (mi + 3.74)) * deflection_correction;
  return 4.1 * std::pow(mi, 0.446) * deflection_correction;
}

double FiftyPassVciPsi(double mobility_index) {
  Require(std::isfinite(mobility_index), "mobility_index", "must be finite");
  const double mi = std::max(mobility_index, 0.0);
  return 28.23 + 0.43 * mi - 92.67 / (mi + 3.67);
}

double VehicleConeIndex::ForPassesPa(int passes) const {
  if (passes == 1) return vci1_pa;
  if (passes == 50) return vci50_pa;
  throw InputError("passes", "must be 1 or 50 (no published VCI for other pass counts)");
}

VehicleConeIndex ComputeVehicleConeIndex(const WheeledVehicle& vehicle) {
  const MobilityIndexFactors f = ComputeMobilityIndex(vehicle);
  VehicleConeIndex vci;
  vci.mobility_index = f.mobility_index;
  vci.vci1_pa =
      OnePassVciPsi(f.mobility_index, DeflectionCorrectionFactor(vehicle.tyre_deflection_ratio)) *
      kPascalsPerPsi;
  vci.vci50_pa = FiftyPassVciPsi(f.mobility_index) * kPascalsPerPsi;
  return vci;
}

bool SoftSoilGo(double rating_cone_index_pa, const VehicleConeIndex& vci, int passes) {
  Require(std::isfinite(rating_cone_index_pa) && rating_cone_index_pa >= 0, "rating_cone_index_pa",
          "must be a finite number >= 0");
  return rating_cone_index_pa >= vci.ForPassesPa(passes);
}

}  // namespace gonogo::terramech
