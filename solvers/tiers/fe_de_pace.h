// The pace of an fe-de curve too long to finish here: the run is stopped after a wall-time budget
// and the whole procedure's time is projected from the FE steps it did (the rig's progress is the
// fraction of the procedure's FE steps). The steps done first are the bin settling under gravity,
// cheaper than the rolling wheel's (RVEs under it need more DE steps per increment), so the
// projection is a lower bound of the whole run.
#pragma once

#include <functional>

#include "solvers/common/tier.h"
#include "solvers/common/traction.h"
#include "solvers/tiers/fe_de_tier.h"

namespace gonogo::tiers {

struct FeDePace {
  double setup_s = 0;          // to the first progress report: templates, settled depths
  double steps_done = 0;       // FE steps after the first report
  double total_steps = 0;      // of the whole procedure
  double stepping_s = 0;       // wall time of those steps
  double fraction_done = 0;
  double seconds_per_step() const { return stepping_s / (steps_done > 1 ? steps_done : 1); }
  double projected_s() const { return setup_s + total_steps * seconds_per_step(); }
};

// Runs `tier` on `request` until its first progress report past `budget_s` of wall time (on a
// rank group, context.communicator set, until the group's first cancel check past it, which
// loses the steps since the last report); `on_progress` (if set) hears each report with the
// elapsed seconds.
FeDePace MeasureFeDePace(const FeDeTier& tier, const TractionRequest& request, double budget_s,
                         ComputeContext context = {},
                         const std::function<void(double fraction, double elapsed_s)>& on_progress = {});

}  // namespace gonogo::tiers
