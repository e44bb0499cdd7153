// The "fe-de" traction tier (seed 000's hierarchical multiscale model): the single-wheel rig of
// seed 001 section 6.3 (solvers/rig/wheel_rig.h) on an explicit FE soil bin whose every
// integration point is a periodic DE RVE (solvers/dem/rve), the RVEs distributed over the task's
// rank group with sticky ownership and load balancing (solvers/bridge).
//
// Soil: request.soil.parameters of the dem-hertz-mindlin model when given, else
// request.soil.soil_name, a dem-hertz-mindlin row of the soil catalogue (soil_catalogue.h); the
// grain count, packing and confining pressure of the RVE are soil parameters. The FE soil's
// density is the consolidated packing's bulk density; the rim grips it with the grains' friction
// coefficient and no adhesion. Tyre: a rigid wheel of radius d/2 and width b.
//
// Time scales (solvers/tiers/README.md, "fe-de"): the FE runs at a fixed step (seed 000:
// 5e-4 s) reached by mass scaling, since the procedure is quasi-static; each FE increment is
// applied to an RVE over as many DE steps as its inertial-number cap asks (at least
// min_steps_per_increment), then relaxed, so the RVE answers quasi-statically whatever the FE
// step.
//
// Collective on the rank group when ComputeContext::communicator is set: group rank 0 runs the
// FE and owns a share of the RVEs, the other ranks serve theirs; alone (no communicator) every
// RVE lives in this process. The curve is the same bit for bit either way.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "solvers/bridge/distributed_point_store.h"
#include "solvers/common/tier.h"
#include "solvers/dem/rve/rve_soil.h"
#include "solvers/material/drucker_prager.h"
#include "solvers/rig/bevameter.h"
#include "solvers/rig/wheel_rig.h"

namespace gonogo::tiers {

struct FeDeOptions {
  // Named configuration, part of the tier's version (so curves of two configurations never share
  // a cache key): "default", "ci" or "tiny".
  std::string preset = "default";
  double elements_per_radius = 4;  // FE resolution along the wheel path, R / h
  double fe_time_step_s = 5e-4;    // FE step, reached by mass scaling (seed 000: 5e-4 s)
  // The bin starts geostatic: each RVE, prepared at the soil's consolidation pressure, is settled
  // isotropically (K0 = 1) at the mean stress of its element's depth, rho g z, but not below
  // this floor (the surface layer of a cohesionless soil has no stiffness at zero stress), Pa.
  double min_initial_pressure_pa = 2e3;
  rig::DrawbarPullProcedure procedure;  // seed 001's
  dem::rve::RveNumerics numerics;
  bridge::BalanceOptions balance;
  // With ComputeContext::checkpoint_dir set, the FE state and every RVE (per rank) are written
  // there this often (wall seconds), and a run of the same request resumes from them.
  double checkpoint_every_s = 60;
  int ranks = 2;    // MPI ranks of one task (TierNeeds::ranks): the FE rank and RVE servers
  int threads = 1;  // OpenMP threads per rank over its RVEs

  // The configurations by name; throws InputError("fe_de_preset", ...) for an unknown one.
  // "default": R/4 mesh, seed 001's procedure, RveNumerics defaults (inertial number 1e-3, 20 + 50
  // DE steps per increment). "ci": a full curve in minutes on 2 cores: R/2 mesh, the procedure
  // shortened (0.1 + 0.2 s settling, 0.2 s rolling, 0.6 s slip ramp), 5 + 5 DE steps per
  // increment, inertial number 1e-2. "tiny": ci with the procedure cut to 0.45 s (0.05 + 0.1 s
  // settling, 0.1 s rolling, 0.2 s slip ramp), a curve in well under a minute: the tests' and a
  // smoke run's.
  static FeDeOptions Preset(const std::string& name);
  void Validate(const std::string& field_prefix) const;
};

// How an fe-de run went (group rank 0's view; empty on the other ranks).
struct FeDeRunFigures {
  int ranks = 1;               // of the group the RVEs were spread over
  double wall_seconds = 0;
  // Per FE step (each TryUpdate), when the RVEs were distributed; see bridge::StepBalance.
  std::vector<bridge::StepBalance> balance;
  int PointsMoved() const;
  double MeanImbalance() const;  // mean over steps of max / mean - 1 of the ranks' RVE seconds
  double MaxImbalance() const;
  double MeanBytesPerStep() const;  // sent + received by the FE rank
};

// One fe-de traction curve and its run.
struct FeDeRunReport : FeDeRunFigures {
  TractionCurve curve;
  // The rig's records the curve was filtered from (rig::RigRun::samples: the 5 ms means of drawbar
  // pull, torque, vertical force and sinkage over the whole procedure); empty if the wheel sank.
  std::vector<rig::RigSample> samples;
  int elements = 0;            // FE elements = RVEs (of the wheel's bin)
  int fe_steps = 0;
  double fe_time_step_s = 0;
};

// What answers at a bin's points in place of the distributed RVEs (the fe-ann tier's network),
// built from the soil's template RVE; it runs alone, in this process.
struct PointStandIn {
  std::shared_ptr<const material::ConstitutiveModel> model;
  // The stand-in's state (MaterialState bytes) for a point whose RVE would start as the RVE state
  // `settled_rve_bytes` (the template settled at the stress of the point's depth).
  std::function<std::string(const std::string& settled_rve_bytes)> state_from_rve;
};
using PointStandInFactory =
    std::function<PointStandIn(std::shared_ptr<const dem::rve::RveMaterial> template_rve)>;

// The virtual bevameter on the fe-de soil and its run.
struct FeDeBevameterReport : FeDeRunFigures {
  rig::BevameterResult bevameter;
};

class FeDeTier : public TractionTier {
 public:
  FeDeTier() : FeDeTier(FeDeOptions{}) {}
  explicit FeDeTier(FeDeOptions options);

  std::string Name() const override { return "fe-de"; }
  std::string Version() const override;
  bool UsesConeIndex() const override { return false; }
  bool UsesSoilName() const override { return true; }
  TierDescription Describe() const override;
  TierNeeds Needs(const TractionRequest& request) const override;
  void ValidateSoil(const SoilState& soil, const std::string& field) const override;

  // The validated dem-hertz-mindlin set the tier runs on; throws InputError(field...) otherwise.
  SoilParameters ResolveSoil(const SoilState& soil, const std::string& field) const;
  const FeDeOptions& options() const { return options_; }
  // Compute, with the run's figures. Collective as Compute is.
  FeDeRunReport Run(const TractionRequest& request, const ComputeContext& context) const;
  // The virtual bevameter of rig/bevameter.h (plate pressure-sinkage and shear-ring tests, and
  // the Bekker-Janosi fit) on FE bins of the same soil, configuration and rank group as Run's:
  // what seed 000 calibrated its Bekker parameters with, here on the multiscale soil.
  // element_size_m: the bins' resolution (0: the bevameter's default, a quarter of the small
  // plate's radius and of the ring's width). Collective as Run is. With `continuum_twin` set:
  // the same tests on the same bins with that soil instead of the RVEs (as RunContinuumTwin),
  // alone.
  FeDeBevameterReport RunBevameter(
      const SoilState& soil, const rig::BevameterSpec& spec, double element_size_m,
      const ComputeContext& context,
      const material::DruckerPragerParams* continuum_twin = nullptr) const;
  // The continuum twin of Run (fe_de_calibration.h): the same rig, bins, mass scaling and rim
  // contact, the soil's RVE replaced by `strength` (Drucker-Prager) at the RVE's consolidated
  // bulk density; alone, whatever the context's communicator. Curve tier "fe-de-twin".
  FeDeRunReport RunContinuumTwin(const TractionRequest& request,
                                 const material::DruckerPragerParams& strength,
                                 const ComputeContext& context) const;
  // Run with the RVEs replaced by what `make_stand_in` builds from the soil's template RVE, on the
  // same rig, bins, geostatic start (each point's stand-in state made from the RVE its depth
  // would start with), mass scaling and rim contact; alone, whatever the context's communicator.
  // The curve's tier and version are the caller's to set.
  FeDeRunReport RunWithStandIn(const TractionRequest& request,
                               const PointStandInFactory& make_stand_in,
                               const ComputeContext& context) const;

 protected:
  TractionCurve ComputeCurve(const TractionRequest& request,
                             const ComputeContext& context) const override;

 private:
  using BinWork = std::function<void(const rig::SoilBinFactory& bins, rig::RigOptions& options)>;
  // On group rank 0: builds the fe-de soil bins (the RVEs distributed over the context's group)
  // and the rig options of this configuration, calls `work` with them, fills `figures`, returns
  // true. On the other ranks: serves RVEs until rank 0 is done, returns false. With `continuum`
  // set, the bins hold it instead of the RVEs (unstressed, settling under gravity); with
  // `stand_in` set, what it makes (geostatic); either way the run is this process's alone.
  struct BinModel {
    std::shared_ptr<const material::ConstitutiveModel> continuum;
    PointStandInFactory stand_in;
    bool alone() const { return continuum != nullptr || static_cast<bool>(stand_in); }
  };
  bool RunOnBins(const SoilParameters& soil, const ComputeContext& context, const BinWork& work,
                 FeDeRunFigures* figures, const BinModel& bin_model = {}) const;
  void RollWheel(const TractionRequest& request, const rig::SoilBinFactory& bins,
                 const rig::RigOptions& rig_options, FeDeRunReport* report) const;

  FeDeOptions options_;
};

}  // namespace gonogo::tiers
