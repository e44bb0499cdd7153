// The "bekker" traction tier: one wheel on a soil described by Bekker-Janosi parameters, by the
// Wong-Reece driven rigid wheel, or by Wong's elastic-mode method when the tyre is soft enough to
// flatten (solvers/terramech/bekker.h). A curve of 100 slips costs milliseconds; the rung above
// the empirical tier (ARCHITECTURE section 1).
#pragma once

#include <string>

#include "solvers/common/tier.h"
#include "solvers/terramech/bekker.h"
#include "solvers/terramech/bekker_soils.h"

namespace gonogo::tiers {

// Soil: request.soil.parameters (model "bekker") when set, else the library entry named
// request.soil.soil_name (case-insensitive); the cone index is not read.
//
// Mode [W08] 2.7.2, decided once per request from p_gcr = CriticalGroundPressurePa(soil, d, b, W):
//   rigid   when tyre.inflation_pressure_pa = 0 (not given) or p_i >= p_gcr: a rigid wheel of the
//           tyre's diameter (r = d/2; deflection and rolling radius are not used),
//           SolveRigidWheel at every slip;
//   elastic when 0 < p_i < p_gcr: SolveFlexibleTyre with ground pressure p_i (carcass stiffness
//           p_c is not modelled: TyreGeometry has no field for it, so p_c = 0), torque with
//           TyreGeometry::RollingRadius().
// Every TractionPoint field is filled: drawbar pull, torque, sinkage from the equilibrium at that
// slip, gross traction T/r, motion resistance T/r - D, efficiency D (1 - s) r / T (0 where D <= 0).
// The mode is not reported in the curve (TractionCurve has no field for it); README "bekker"
// documents the rule.
//
// Throws InputError: "soil" when neither explicit parameters nor a known library name is given
// (the message lists the known soils), the fields of TractionRequest::Validate, "wheel_load_n"
// when the wheel would sink past its axle, "tyre.inflation_pressure_pa" when an elastic-mode tyre
// would bottom out. Stateless after construction and thread-safe.
class BekkerTier : public TractionTier {
 public:
  // The built-in soil library and the published Wong-Reece constants.
  BekkerTier();
  explicit BekkerTier(terramech::BekkerSoilLibrary library,
                      terramech::WongReeceOptions options = {});

  std::string Name() const override { return "bekker"; }
  std::string Version() const override { return "bekker-1"; }
  bool UsesConeIndex() const override { return false; }
  bool UsesSoilName() const override { return true; }
  TierDescription Describe() const override;
  void ValidateSoil(const SoilState& soil, const std::string& field) const override;

  // The parameters the tier uses for `soil`; throws InputError(field, ...) as described above.
  BekkerParameters ResolveSoil(const SoilState& soil, const std::string& field) const;

 protected:
  // Polls context.Cancelled() before every slip point and throws CancelledError once it is true.
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override;

 private:
  terramech::BekkerSoilLibrary library_;
  terramech::WongReeceOptions options_;
};

}  // namespace gonogo::tiers
