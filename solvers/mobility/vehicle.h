// The vehicle as the map service sees it: axles with their share of the weight, tyres, drive line.
#pragma once

#include <string>
#include <vector>

#include "solvers/common/traction.h"
#include "solvers/common/units.h"

namespace gonogo::mobility {

inline constexpr double kDefaultDrivelineEfficiency = 0.85;

// Plausible ranges (RequirePlausible): from a quad bike to the heaviest off-road haul trucks.
inline constexpr PlausibleRange kPlausibleVehicleMass{10.0, 1e6, "kg"};
inline constexpr PlausibleRange kPlausibleDrivePower{10.0, 2e7, "W"};
inline constexpr PlausibleRange kPlausibleMaxSpeed{0.1, 300.0, "km/h"};
inline constexpr PlausibleRange kPlausibleGroundClearance{0.0, 5.0, "m"};
inline constexpr int kMaxAxles = 20;
inline constexpr int kMaxWheelsPerAxle = 16;

struct AxleSpec {
  double load_fraction = 0;  // share of the vehicle's weight on this axle, 0..1
  int wheels = 0;            // tyres on the axle
  TyreGeometry tyre;
  bool driven = true;
};

struct VehicleSpec {
  std::string name;
  double mass_kg = 0;
  std::vector<AxleSpec> axles;           // front to rear
  double drive_power_w = 0;              // at the driven wheels' drive line input
  double max_speed_kmh = 0;
  double driveline_efficiency = kDefaultDrivelineEfficiency;
  double ground_clearance_m = 0;
  bool automatic_transmission = false;
  bool tyre_chains = false;

  // Throws InputError naming the field ("vehicle.axles[1].tyre.width_m", ...).
  void Validate() const;
  double WeightN() const { return mass_kg * units::kStandardGravityMps2; }
  // Static vertical load on one wheel of the axle, N.
  double WheelLoadN(int axle) const;
  int WheelCount() const;
};

// Load fractions of a two-axle vehicle from its centre of gravity (static moment balance):
// front = 1 - cg_behind_front_axle / wheelbase, rear = cg_behind_front_axle / wheelbase.
void SetTwoAxleSplitFromCg(VehicleSpec& vehicle, double cg_behind_front_axle_m, double wheelbase_m);

}  // namespace gonogo::mobility
