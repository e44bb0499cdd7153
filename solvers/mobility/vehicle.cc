#include "solvers/mobility/vehicle.h"

#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::mobility {

void VehicleSpec::Validate() const {
  Require(std::isfinite(mass_kg) && mass_kg > 0, "vehicle.mass_kg", "must be a positive mass in kg");
  RequirePlausible(mass_kg, kPlausibleVehicleMass, "vehicle.mass_kg");
  Require(!axles.empty(), "vehicle.axles", "at least one axle is required");
  Require(axles.size() <= static_cast<size_t>(kMaxAxles), "vehicle.axles",
          "at most " + std::to_string(kMaxAxles) + " axles (got " + std::to_string(axles.size()) + ")");
  double sum = 0;
  bool any_driven = false;
  for (size_t i = 0; i < axles.size(); ++i) {
    const std::string p = "vehicle.axles[" + std::to_string(i) + "].";
    const AxleSpec& a = axles[i];
    Require(std::isfinite(a.load_fraction) && a.load_fraction > 0 && a.load_fraction <= 1,
            p + "load_fraction", "must lie in (0, 1]");
    Require(a.wheels >= 1, p + "wheels", "must be at least 1");
    Require(a.wheels <= kMaxWheelsPerAxle, p + "wheels",
            "must be at most " + std::to_string(kMaxWheelsPerAxle));
    a.tyre.Validate(p + "tyre.");
    sum += a.load_fraction;
    any_driven = any_driven || a.driven;
  }
  Require(std::abs(sum - 1.0) < 1e-3, "vehicle.axles",
          "load fractions must sum to 1 (they sum to " + std::to_string(sum) + ")");
  Require(any_driven, "vehicle.axles", "at least one axle must be driven");
  Require(std::isfinite(drive_power_w) && drive_power_w > 0, "vehicle.drive_power_w",
          "must be a positive power in W");
  RequirePlausible(drive_power_w, kPlausibleDrivePower, "vehicle.drive_power_w");
  Require(std::isfinite(max_speed_kmh) && max_speed_kmh > 0, "vehicle.max_speed_kmh",
          "must be a positive speed in km/h");
  RequirePlausible(max_speed_kmh, kPlausibleMaxSpeed, "vehicle.max_speed_kmh");
  Require(std::isfinite(driveline_efficiency) && driveline_efficiency > 0 &&
              driveline_efficiency <= 1,
          "vehicle.driveline_efficiency", "must lie in (0, 1]");
  Require(std::isfinite(ground_clearance_m) && ground_clearance_m >= 0,
          "vehicle.ground_clearance_m", "must not be negative");
  RequirePlausible(ground_clearance_m, kPlausibleGroundClearance, "vehicle.ground_clearance_m");
}

double VehicleSpec::WheelLoadN(int axle) const {
  const AxleSpec& a = axles.at(axle);
  return WeightN() * a.load_fraction / a.wheels;
}

int VehicleSpec::WheelCount() const {
  int n = 0;
  for (const AxleSpec& a : axles) n += a.wheels;
  return n;
}

void SetTwoAxleSplitFromCg(VehicleSpec& v, double cg_m, double wheelbase_m) {
  Require(v.axles.size() == 2, "vehicle.axles",
          "a split from the centre of gravity needs exactly two axles");
  Require(std::isfinite(wheelbase_m) && wheelbase_m > 0, "vehicle.wheelbase_m",
          "must be positive when load fractions are not given");
  Require(std::isfinite(cg_m) && cg_m > 0 && cg_m < wheelbase_m, "vehicle.cg_behind_front_axle_m",
          "must lie between the axles when load fractions are not given");
  v.axles[0].load_fraction = 1.0 - cg_m / wheelbase_m;
  v.axles[1].load_fraction = cg_m / wheelbase_m;
}

}  // namespace gonogo::mobility
