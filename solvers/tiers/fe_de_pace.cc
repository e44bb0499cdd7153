#include "solvers/tiers/fe_de_pace.h"

#include <chrono>

#include "solvers/common/errors.h"

namespace gonogo::tiers {

FeDePace MeasureFeDePace(const FeDeTier& tier, const TractionRequest& request, double budget_s,
                         ComputeContext context,
                         const std::function<void(double fraction, double elapsed_s)>& on_progress) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const bool alone = context.communicator == MPI_COMM_NULL;
  double first_report_s = -1, first_fraction = 0, last_report_s = 0, fraction_done = 0;
  context.progress = [&](double fraction) {
    if (first_report_s < 0) {  // the first report comes after the setup
      first_report_s = elapsed();
      first_fraction = fraction;
    }
    fraction_done = fraction;
    last_report_s = elapsed();  // the pace runs from the first report to the last
    if (on_progress) on_progress(fraction, last_report_s);
    // Alone, stopped here, after the report, not by a cancel check: the rig checks for a cancel
    // just before it reports, so a cancel would lose the last report (at the default
    // configuration reports come every 20 FE steps, minutes apart).
    if (alone && last_report_s > budget_s) throw CancelledError();
  };
  // On a rank group every member must stop at the same call: a cancel check, agreed collectively.
  if (!alone) context.cancelled = [&] { return elapsed() > budget_s; };
  try {
    tier.Run(request, context);
  } catch (const CancelledError&) {
  }
  const FeDeOptions& o = tier.options();
  const rig::DrawbarPullProcedure& p = o.procedure;
  FeDePace pace;
  pace.total_steps =
      (p.gravity_settle_s + p.load_settle_s + p.self_propelled_s + p.slip_ramp_s) / o.fe_time_step_s;
  pace.setup_s = first_report_s < 0 ? elapsed() : first_report_s;
  pace.steps_done = (fraction_done - first_fraction) * pace.total_steps;
  pace.stepping_s = first_report_s < 0 ? 0 : last_report_s - first_report_s;
  pace.fraction_done = fraction_done;
  return pace;
}

}  // namespace gonogo::tiers
