// Value types every traction tier speaks: the request (soil state, tyre, wheel load, slip sweep) and the
// TractionCurve it answers with (ARCHITECTURE section 1). Plain data, SI units in every name.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "solvers/common/errors.h"
#include "solvers/common/soil_model.h"

namespace gonogo {

// Plausible ranges (RequirePlausible): from a garden cart's wheel to a mining haul truck's 4 m tyre
// carrying about 100 t, and cone indices from water to ground a penetrometer cannot enter.
inline constexpr PlausibleRange kPlausibleTyreDiameter{0.1, 5.0, "m"};
inline constexpr PlausibleRange kPlausibleTyreWidth{0.02, 2.0, "m"};
inline constexpr PlausibleRange kPlausibleWheelLoad{10.0, 1.5e6, "N"};
inline constexpr PlausibleRange kPlausibleConeIndex{0.0, 2e7, "Pa"};
// The finest slip sweep a curve may ask for: 1,001 points (a step below it is a LimitError).
inline constexpr double kMinSlipStep = 0.001;

// Pneumatic tyre (or rigid wheel when deflection_m = 0). Symbols of seed 001 Table 1 in brackets.
struct TyreGeometry {
  double diameter_m = 0;         // unloaded outside diameter [d]
  double width_m = 0;            // section width [b]
  double section_height_m = 0;   // section height [h]
  double deflection_m = 0;       // vertical deflection under load [delta]
  double rolling_radius_m = 0;   // rolling radius used for torque and slip [r]; 0 = d/2 - delta
  double inflation_pressure_pa = 0;  // gauge inflation pressure [p_i], Pa; 0 = not given

  double RollingRadius() const { return rolling_radius_m > 0 ? rolling_radius_m : 0.5 * diameter_m - deflection_m; }
  void Validate(const std::string& field_prefix) const;
};

// Bekker-Wong pressure-sinkage and Janosi-Hanamoto shear parameters of a soil, SI units throughout.
// p = (kc / b + kphi) z^n;  tau = (c + sigma tan phi) (1 - exp(-j / K)).
struct BekkerParameters {
  double n = 0;                       // sinkage exponent, -
  double kc = 0;                      // cohesive modulus k_c, N/m^(n+1)
  double kphi = 0;                    // frictional modulus k_phi, N/m^(n+2)
  double cohesion_pa = 0;             // c, Pa
  double friction_angle_deg = 0;      // phi, degrees
  double shear_deformation_m = 0;     // Janosi-Hanamoto shear deformation modulus K, m

  void Validate(const std::string& field_prefix) const;

  // The "bekker" soil model's parameter set (solvers/common/soil_model.h) and back; FromSoilModel
  // reads a set already validated by SoilModels().Validate.
  SoilParameters ToSoilModel() const;
  static BekkerParameters FromSoilModel(const SoilParameters& parameters);
};

// Soil state of one terrain unit. The empirical tier reads only the cone index.
struct SoilState {
  double cone_index_pa = 0;      // cone index [CI], Pa
  std::string soil_name;         // soil-catalogue name, empty when only the cone index is known
  // Explicit parameters of one soil model (bekker, drucker-prager, dem-hertz-mindlin, ...);
  // override the catalogue entry.
  std::optional<SoilParameters> parameters;

  // Checks the cone index and, when given, the parameters against their model's declaration
  // (errors name field_prefix + "parameters." + the parameter).
  void Validate(const std::string& field_prefix) const;
};

// A request's own guard for a tier with a surrogate (fe-ann: solvers/ann/surrogate_ensemble.h and
// ann_material.h): when a point is flagged as outside what the surrogate learnt, and what answers
// it then. A field left unset keeps the tier's, which the deployment sets (gonogo-server
// --fe-ann-*); the tier writes the whole guard into the request before it is keyed.
struct SurrogateGuard {
  // Mahalanobis distance of an input from the training inputs above which it is flagged, -;
  // 0: the model's own.
  std::optional<double> distance_threshold;
  // The ensemble members' spread, relative to their mean stress, above which a point is flagged,
  // -; 0: the model's own.
  std::optional<double> spread_threshold;
  // Mean compression -tr(sigma)/3 below which a point is flagged, Pa; 0: no floor.
  std::optional<double> pressure_floor_pa;
  // true: a flagged point is answered by the soil's RVE; false: by the network, and counted.
  std::optional<bool> fallback_enabled;
  // A fallen-back point returns to the network after this many increments in a row the ensemble
  // would not have flagged; 0: it stays on its RVE.
  std::optional<int> return_after_steps;

  bool Empty() const {
    return !distance_threshold && !spread_threshold && !pressure_floor_pa && !fallback_enabled &&
           !return_after_steps;
  }
  // Each field set is a valid value (errors name field_prefix + the field).
  void Validate(const std::string& field_prefix) const;
};

// One traction task: a single wheel on one soil state, swept over slip.
struct TractionRequest {
  SoilState soil;
  TyreGeometry tyre;
  double wheel_load_n = 0;       // vertical load on the wheel [W], N
  std::vector<double> slips;     // slip values s = 1 - V/(omega r), each in [0, 1]
  // The registered surrogate model that answers for the soil (the fe-ann tier); empty: the tier's
  // choice, written here before the request is keyed (TractionTier::ResolveChoices).
  std::string surrogate_model;
  // The surrogate's guard, for this request (a tier without a surrogate takes none).
  SurrogateGuard surrogate_guard;

  void Validate() const;
  // Evenly spaced slips 0, step, 2 step, ... up to and including 1 (or the last point below it).
  static std::vector<double> SlipSweep(double step);
};

// One point of a traction curve.
struct TractionPoint {
  double slip = 0;                  // s, -
  double drawbar_pull_n = 0;        // D = gross traction - motion resistance, N
  double torque_nm = 0;             // wheel torque T, N m
  double sinkage_m = 0;             // z, m
  double tractive_efficiency = 0;   // eta = D (1 - s) / (T / r), -; 0 where D <= 0
  double gross_traction_n = 0;      // T / r, N
  double motion_resistance_n = 0;   // N
};

// How many of a surrogate run's fallbacks each of its guard's tests flagged (a point may be flagged
// by more than one).
struct FallbackFlagCounts {
  int beyond_distance = 0;       // the training envelope's distance
  int beyond_spread = 0;         // the ensemble members' spread
  int below_pressure_floor = 0;  // the pressure floor
};

// How a surrogate tier's curve (fe-ann) answered its integration points: part of the curve's
// provenance, kept with it in the cache.
struct SurrogateRun {
  std::int64_t fe_steps = 0;
  // Points answered by their RVE because the model's guard flagged them, and when: the step of
  // each one's own history (one step per FE step) at which it fell back.
  int fallbacks = 0;
  std::vector<std::int64_t> fallback_point_steps;
  FallbackFlagCounts fallbacks_flagged;  // of them, those each of the guard's tests flagged
  std::int64_t returns = 0;           // fallen-back points sent back to the network
  std::int64_t unanswered_flags = 0;  // flags the network answered anyway (fallback off)
  int fallback_paths_kept = 0;        // fallen-back points' RVE paths kept as training data
  std::int64_t network_point_updates = 0;
  double network_seconds = 0;
  double fallback_seconds = 0;        // the RVEs of the fallen-back points
};

struct TractionCurve {
  std::string tier;          // tier name, e.g. "empirical"
  std::string tier_version;  // changes whenever the tier's numbers could change
  std::vector<TractionPoint> points;  // empty when immobile
  // Non-empty when the soil cannot carry the wheel at all: why (the vehicle is NO-GO there).
  std::string immobile_reason;
  std::optional<SurrogateRun> surrogate_run;  // a surrogate tier's curve only

  // Linear interpolation of drawbar pull (N) at slip s within the sweep.
  double DrawbarPullAt(double slip) const;
};

}  // namespace gonogo
