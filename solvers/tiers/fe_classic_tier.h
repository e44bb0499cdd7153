// The "fe-classic" traction tier: one rigid wheel driven through the drawbar-pull procedure of
// seed 001 section 6.3 (solvers/rig/wheel_rig.h) on an explicit FE soil bin closed by a
// Drucker-Prager soil (solvers/fe, solvers/material). The rung below fe-de and fe-ann, whose
// closures replace the return map behind the same seam (ARCHITECTURE sections 1 and 4).
//
// Soil: request.soil.parameters of the drucker-prager soil model when given, else
// request.soil.soil_name, a row of the fe-classic soil library (solvers/rig/data/fe_soils.csv);
// the cone index is not read. Tyre: a rigid wheel of radius d/2
// and width b (section height, deflection and inflation pressure are not used). A curve costs
// minutes on one core at the default resolution (README "Figures").
//
// Throws InputError("soil") for an unknown soil, the fields of TractionRequest::Validate;
// returns an immobile curve when the wheel sinks to its axle; throws std::runtime_error when the
// FE mesh fails. Thread-safe; each call builds its own mesh.
#pragma once

#include <string>

#include "solvers/common/tier.h"
#include "solvers/rig/fe_soils.h"
#include "solvers/rig/wheel_rig.h"

namespace gonogo::tiers {

struct FeClassicOptions {
  double elements_per_radius = 6;  // resolution of the soil bin along the wheel path
  int threads = 1;                 // OpenMP threads of one curve
};

class FeClassicTier : public TractionTier {
 public:
  FeClassicTier() : FeClassicTier(rig::FeSoilLibrary::Builtin(), FeClassicOptions{}) {}
  FeClassicTier(rig::FeSoilLibrary library, FeClassicOptions options)
      : library_(std::move(library)), options_(options) {}

  std::string Name() const override { return "fe-classic"; }
  // Bumped whenever the rig's physics changes, so cached curves of the old model are not served
  // (2: incremental, stress-returned and viscous hourglass control; 3: standard gravity 9.80665
  // m/s^2 in the soil bin and the wheel's weight, was 9.81).
  std::string Version() const override { return "fe-classic-3"; }
  bool UsesConeIndex() const override { return false; }
  bool UsesSoilName() const override { return true; }
  TierDescription Describe() const override;
  // Minutes on one core at the default resolution (README "Figures").
  TierNeeds Needs(const TractionRequest& request) const override;
  void ValidateSoil(const SoilState& soil, const std::string& field) const override;

  // The soil the tier runs on; throws InputError(field...) for a soil it cannot resolve.
  rig::FeSoil ResolveSoil(const SoilState& soil, const std::string& field) const;

 protected:
  // Polls context.Cancelled() every 200 time steps and throws CancelledError once it is true;
  // reports the fraction of simulated time done.
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override;

 private:
  rig::FeSoilLibrary library_;
  FeClassicOptions options_;
};

}  // namespace gonogo::tiers
