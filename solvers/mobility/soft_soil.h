// NRMM's soft-soil test for a whole vehicle: its vehicle cone index (VCI) from the mobility index of
// solvers/terramech/nrmm_vci.h, to be compared with a cell's rating cone index (RCI >= VCI is GO).
#pragma once

#include "solvers/mobility/vehicle.h"

namespace gonogo::mobility {

// VCI in Pa for 1 or 50 passes. The mobility index reads the first axle's tyre (NRMM takes one tyre
// size per vehicle) and the drive power as the engine power.
double VehicleConeIndexPa(const VehicleSpec& vehicle, int passes);

}  // namespace gonogo::mobility
