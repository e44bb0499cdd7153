#include "solvers/mobility/soft_soil.h"

#include "solvers/terramech/nrmm_vci.h"

namespace gonogo::mobility {

double VehicleConeIndexPa(const VehicleSpec& v, int passes) {
  terramech::WheeledVehicle w;
  w.gross_mass_kg = v.mass_kg;
  w.axle_count = static_cast<int>(v.axles.size());
  w.tyre_count = v.WheelCount();
  const TyreGeometry& tyre = v.axles.front().tyre;
  w.tyre_width_m = tyre.width_m;
  w.tyre_diameter_m = tyre.diameter_m;
  w.ground_clearance_m = v.ground_clearance_m;
  w.engine_power_w = v.drive_power_w;
  w.automatic_transmission = v.automatic_transmission;
  w.chains = v.tyre_chains;
  if (tyre.deflection_m > 0) w.tyre_deflection_ratio = tyre.deflection_m / tyre.section_height_m;
  w.Validate("vehicle.");
  return terramech::ComputeVehicleConeIndex(w).ForPassesPa(passes);
}

}  // namespace gonogo::mobility
