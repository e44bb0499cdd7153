// The "empirical" traction tier: one pneumatic wheel on a soil known only by its cone index, by the
// Brixius (1987) equations (solvers/terramech/brixius.h). Answers in microseconds; the lowest rung
// of the tier ladder (ARCHITECTURE section 1). The NRMM soft-soil test (nrmm_vci.h) is a
// vehicle-level check and is applied by the mobility layer, not here.
#pragma once

#include <string>

#include "solvers/common/tier.h"
#include "solvers/terramech/brixius.h"

namespace gonogo::tiers {

// Fills every TractionPoint field at each requested slip s, for wheel load W, rolling radius r:
//   gross_traction_n    GT = W * GT/W                     (Brixius eq. 21)
//   motion_resistance_n MR = W * MR/W                     (Brixius eqs. 19-20, MR/W capped at 1)
//   drawbar_pull_n      NT = GT - MR
//   torque_nm           GT * r, r = TyreGeometry::RollingRadius()
//   tractive_efficiency (NT/GT)(1 - s), 0 where NT <= 0
//   sinkage_m           powered-wheel sinkage of the ERDC VTI (Dettwiller et al. 2018, eq. 21),
//                       the same at every slip
// Zero cone index gives Bn = 0: GT = 0.04 W (tyre loss only), MR = W, NT = -0.96 W, efficiency 0,
// sinkage = d: the wheel is immobile. Throws InputError for a request that fails Validate().
// Stateless and thread-safe.
class EmpiricalTier : public TractionTier {
 public:
  std::string Name() const override { return "empirical"; }
  std::string Version() const override { return "empirical-1"; }
  TierDescription Describe() const override;

 protected:
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override;
};

}  // namespace gonogo::tiers
