// Go/NoGo and speed made good for one cell (ARCHITECTURE section 7).
//
// For a terrain unit the wheels' traction curves are summed into the vehicle's total drawbar pull
// D(s) and total gross traction F(s) over the slip sweep. On a cell of grade angle theta the vehicle
// must pull W sin(theta) (slope rasters carry no aspect, so every slope is taken as climbed: the worst
// case for traction):
//   GO       D(design slip)/W - sin(theta) >= margin, and the soft-soil test passes;
//   SLOW-GO  not GO, but some slip s <= max slip gives D(s)/W - sin(theta) > 0, and the soft-soil test
//            passes;
//   NO-GO    otherwise.
// Speed made good: the vehicle runs at the smallest slip s* that balances the grade; the driven wheels
// turn at the speed the drive power allows against their gross traction, and the vehicle moves at
// (1 - s*) of it:  V = P eta_driveline (1 - s*) / F(s*),  capped at the vehicle's maximum speed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/common/traction.h"
#include "solvers/mobility/vehicle.h"

namespace gonogo::mobility {

enum class GoClass : uint8_t { kNoGo = 0, kSlowGo = 1, kGo = 2, kNoData = 255 };

struct Criteria {
  double design_slip = 0.20;
  double max_slip = 0.50;
  double go_margin = 0.05;  // D/W needed above the grade at the design slip for GO
  int passes = 1;           // NRMM soft-soil test: 1 or 50
  double slip_step = 0.05;  // slip sweep spacing

  void Validate() const;
};

// The whole vehicle's traction on one terrain unit.
struct VehicleTraction {
  std::vector<double> slip;              // the sweep, ascending
  std::vector<double> drawbar_pull_n;    // sum over all wheels (non-driven wheels: their resistance)
  std::vector<double> gross_traction_n;  // sum over driven wheels
  bool soft_soil_ok = true;              // NRMM RCI >= VCI (empirical tier), else true
  std::string immobile_reason;           // non-empty: some wheel cannot be carried at all
};

// Sums per-axle curves (one curve per axle, each for one wheel of that axle) into the vehicle's
// traction. A non-driven wheel is towed: it contributes the drawbar pull of its curve at zero slip
// (minus its rolling resistance) at every slip and no gross traction.
VehicleTraction CombineAxles(const VehicleSpec& vehicle,
                             const std::vector<const TractionCurve*>& curve_per_axle);

// Why a cell is NO-GO, for the summary.
enum class NoGoReason : uint8_t { kNone = 0, kCannotCarry, kSoftSoil, kTraction };

struct CellVerdict {
  GoClass go_class = GoClass::kNoData;
  float speed_kmh = 0;
  NoGoReason reason = NoGoReason::kNone;
};

CellVerdict EvaluateCell(const VehicleSpec& vehicle, const Criteria& criteria,
                         const VehicleTraction& traction, double slope_percent);

}  // namespace gonogo::mobility
