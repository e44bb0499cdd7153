// NRMM soft-soil go/no-go for wheeled vehicles in fine-grained soil: the WES mobility index MI and
// the vehicle cone index VCI, the minimum rating cone index (RCI) of the critical layer that lets
// the vehicle complete 1 or 50 passes. The relations are fits in US customary units (lb, in, hp,
// psi); inputs here are SI and are converted inside with the named constants below.
//
// Sources
//   [RN71]  Rula, A.A., Nuttall, C.J. (1971) An analysis of ground mobility models (ANAMOB).
//           WES Technical Report M-71-4. MI factors and VCI1 / VCI50 relations, also reproduced in
//           Wong, J.Y., Theory of Ground Vehicles (empirical methods based on the cone index) and
//           US Army FM 5-430-00-1 (1994).
//   [PW06]  Priddy, J.D., Willoughby, W.E. (2006) Clarification of vehicle cone index with
//           reference to mean maximum pressure. J. Terramechanics 43, 85-96: VCI1 for MI <= 115 and
//           MI > 115, and the deflection correction factor DCF.
//   [C09]   Ciobotaru, T. (2009) Semi-empiric algorithm for assessment of the vehicle mobility.
//           Leonardo Electronic Journal of Practices and Technologies: factor definitions.
#pragma once

#include <string>

namespace gonogo::terramech {

// ---- Unit conversions (exact by definition unless noted) ----
inline constexpr double kKilogramsPerPound = 0.45359237;
inline constexpr double kMetresPerInch = 0.0254;
inline constexpr double kWattsPerHorsepower = 745.69987158227022;  // 550 ft lbf / s
inline constexpr double kPascalsPerPsi = 6894.757293168361;        // lbf / in^2
inline constexpr double kPoundsPerShortTon = 2000.0;
inline constexpr double kPoundsPerKip = 1000.0;

// Tyre deflection delta/h of most vehicles behind the MI data; DCF = 1 there [PW06].
inline constexpr double kReferenceDeflectionRatio = 0.15;

// A self-propelled wheeled vehicle, all axles driven, as the NRMM soft-soil relations see it.
struct WheeledVehicle {
  double gross_mass_kg = 0;
  int axle_count = 0;
  int tyre_count = 0;          // all tyres, duals counted singly
  double tyre_width_m = 0;     // section width b
  double tyre_diameter_m = 0;  // unloaded outside diameter d
  double ground_clearance_m = 0;
  double engine_power_w = 0;  // gross engine power
  bool automatic_transmission = false;
  bool chains = false;  // tyre chains (the grouser factor)
  // Tyre deflection delta/h on a hard surface, for the deflection correction of VCI1.
  double tyre_deflection_ratio = kReferenceDeflectionRatio;

  // Throws InputError naming the field, prefixed by `field_prefix` ("vehicle.").
  void Validate(const std::string& field_prefix = "") const;
};

// The mobility index and the factors it is built from [RN71], [C09]:
//   MI = (CPF * WF / (TF * GF) + WLF - CF) * EF * TrF.
struct MobilityIndexFactors {
  double contact_pressure = 0;  // CPF = W_lb / (n_tyres * b_in * d_in / 2), psi
  double weight = 0;            // WF, piecewise linear in the axle load X = W_kips / n_axles
  double tyre = 0;              // TF = (10 + b_in) / 100
  double grouser = 0;           // GF = 1.05 with chains, 1.00 without
  double wheel_load = 0;        // WLF = W_kips / (2 n_axles)
  double clearance = 0;         // CF = clearance_in / 10
  double engine = 0;            // EF = 1.00 at >= 10 hp per short ton, else 1.05
  double transmission = 0;      // TrF = 1.00 automatic, 1.05 manual
  double mobility_index = 0;    // MI, dimensionless (psi-based)
};
MobilityIndexFactors ComputeMobilityIndex(const WheeledVehicle& vehicle);

// Weight factor WF of [RN71] for axle load X in kips:
//   X < 2: 0.553 X;  2 <= X <= 13.5: 0.033 X + 1.05;  13.5 < X <= 20: 0.142 X - 0.42;
//   X > 20: 0.278 X - 3.115.
double WeightFactor(double axle_load_kips);

// Deflection correction factor DCF = (0.15 / (delta/h))^0.25 [PW06].
double DeflectionCorrectionFactor(double tyre_deflection_ratio);

// One-pass VCI in psi [PW06] (DCF = 1 gives [RN71]):
//   MI <= 115: VCI1 = (11.48 + 0.2 MI - 39.2 / (MI + 3.74)) DCF;
//   MI >  115: VCI1 = 4.1 MI^0.446 DCF.
// MI below 0 lies outside the fitted data and is taken as 0.
double OnePassVciPsi(double mobility_index, double deflection_correction = 1.0);

// Fifty-pass VCI in psi [RN71]: VCI50 = 28.23 + 0.43 MI - 92.67 / (MI + 3.67), MI below 0 taken
// as 0. No published DCF or high-MI branch is applied.
double FiftyPassVciPsi(double mobility_index);

// VCI of one vehicle, in Pa.
struct VehicleConeIndex {
  double mobility_index = 0;
  double vci1_pa = 0;   // one pass
  double vci50_pa = 0;  // fifty passes

  // VCI for `passes` = 1 or 50; no published interpolation exists for other counts, so any other
  // value throws InputError("passes", ...).
  double ForPassesPa(int passes) const;
};
VehicleConeIndex ComputeVehicleConeIndex(const WheeledVehicle& vehicle);

// NRMM soft-soil test: GO for the passes when the rating cone index of the critical layer is at
// least the VCI for those passes.
bool SoftSoilGo(double rating_cone_index_pa, const VehicleConeIndex& vci, int passes);

}  // namespace gonogo::terramech
