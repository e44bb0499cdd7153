// The fe-de configuration the tier's tests run: the ci preset with the procedure cut to 0.45 s
// (a curve in about 35 s alone on the shared 2-core machine).
#pragma once

#include "solvers/tiers/fe_de_tier.h"

namespace gonogo::tiers {

inline FeDeOptions TinyFeDeOptions() {
  FeDeOptions options = FeDeOptions::Preset("ci");
  options.procedure.gravity_settle_s = 0.05;
  options.procedure.load_settle_s = 0.1;
  options.procedure.self_propelled_s = 0.1;
  options.procedure.speed_ramp_up_s = 0.03;
  options.procedure.slip_ramp_s = 0.2;
  return options;
}

}  // namespace gonogo::tiers
