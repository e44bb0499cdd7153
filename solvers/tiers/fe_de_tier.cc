#include "solvers/tiers/fe_de_tier.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <utility>

#include "solvers/common/errors.h"
#include "solvers/common/units.h"
#include "solvers/rig/fe_soil_bin.h"
#include "solvers/tiers/soil_catalogue.h"

namespace gonogo::tiers {

namespace {

// RankGroupLink::Call codes of this tier.
constexpr int kCallCancelCheck = 1;

}  // namespace

FeDeOptions FeDeOptions::Preset(const std::string& name) {
  FeDeOptions options;
  options.preset = name;
  if (name == "default") return options;
  if (name == "ci" || name == "tiny") {
    options.elements_per_radius = 2;
    options.procedure.gravity_settle_s = 0.1;
    options.procedure.load_settle_s = 0.2;
    options.procedure.self_propelled_s = 0.2;
    options.procedure.speed_ramp_up_s = 0.05;
    options.procedure.slip_ramp_s = 0.6;
    options.numerics.min_steps_per_increment = 5;
    options.numerics.relax_steps = 5;
    options.numerics.max_inertial_number = 1e-2;
    if (name == "tiny") {
      options.procedure.gravity_settle_s = 0.05;
      options.procedure.load_settle_s = 0.1;
      options.procedure.self_propelled_s = 0.1;
      options.procedure.speed_ramp_up_s = 0.03;
      options.procedure.slip_ramp_s = 0.2;
    }
    return options;
  }
  throw InputError("fe_de_preset",
                   "unknown fe-de configuration '" + name + "'; known: default, ci, tiny");
}

void FeDeOptions::Validate(const std::string& p) const {
  Require(preset == "default" || preset == "ci" || preset == "tiny", p + "preset",
          "must be default, ci or tiny");
  Require(std::isfinite(elements_per_radius) && elements_per_radius >= 2 &&
              elements_per_radius <= 50,
          p + "elements_per_radius", "must lie in [2, 50]");
  Require(std::isfinite(fe_time_step_s) && fe_time_step_s > 0 && fe_time_step_s <= 0.01,
          p + "fe_time_step_s", "must lie in (0, 0.01] s");
  procedure.Validate(p + "procedure.");
  numerics.Validate(p + "numerics.");
  balance.Validate(p + "balance.");
  Require(std::isfinite(min_initial_pressure_pa) && min_initial_pressure_pa > 0,
          p + "min_initial_pressure_pa", "must be a positive pressure, Pa");
  Require(std::isfinite(checkpoint_every_s) && checkpoint_every_s >= 0, p + "checkpoint_every_s",
          "must be a finite number of seconds >= 0");
  Require(ranks >= 1 && ranks <= 4096, p + "ranks", "must lie in [1, 4096]");
  Require(threads >= 1 && threads <= 1024, p + "threads", "must lie in [1, 1024]");
}

FeDeTier::FeDeTier(FeDeOptions options) : options_(std::move(options)) {
  options_.Validate("fe_de.");
}

std::string FeDeTier::Version() const {
  return options_.preset == "default" ? "fe-de-1" : "fe-de-1-" + options_.preset;
}

TierDescription FeDeTier::Describe() const {
  return {"explicit FE soil bin with a periodic DE RVE (Hertz-Mindlin grains, rolling resistance) "
          "at every integration point, RVEs spread over an MPI rank group; rigid wheel through "
          "seed 001's drawbar-pull procedure (" + options_.preset + " configuration)",
          "soil name (dem-hertz-mindlin catalogue rows) or dem-hertz-mindlin parameters; tyre "
          "diameter and width; wheel load",
          options_.preset == "default" ? "hours on a few cores" : "minutes on 2 cores",
          {"dem-hertz-mindlin"}};
}

TierNeeds FeDeTier::Needs(const TractionRequest& /*request*/) const {
  TierNeeds needs;
  needs.ranks = options_.ranks;
  needs.threads = options_.threads;
  needs.expected_seconds = options_.preset == "default" ? 4 * 3600 : 180;
  return needs;
}

SoilParameters FeDeTier::ResolveSoil(const SoilState& soil, const std::string& field) const {
  if (soil.parameters) {
    Require(soil.parameters->model == dem::rve::kRveSoilModel, field + ".parameters.model",
            std::string("the fe-de tier reads parameters of the ") + dem::rve::kRveSoilModel +
                " soil model, not '" + soil.parameters->model + "'");
    return SoilModels().Validate(*soil.parameters, field + ".parameters");
  }
  const SoilCatalogue& catalogue = BuiltinSoilCatalogue();
  if (const CatalogueEntry* entry = catalogue.Find(soil.soil_name, dem::rve::kRveSoilModel)) {
    return entry->parameters;
  }
  std::string known;
  for (const CatalogueEntry& entry : catalogue.Entries()) {
    if (entry.parameters.model == dem::rve::kRveSoilModel) {
      known += (known.empty() ? "" : ", ") + entry.soil;
    }
  }
  throw InputError(field + ".soil_name",
                   (soil.soil_name.empty()
                        ? std::string("is missing")
                        : "no dem-hertz-mindlin soil '" + soil.soil_name + "' in the catalogue") +
                       "; known: " + known);
}

void FeDeTier::ValidateSoil(const SoilState& soil, const std::string& field) const {
  dem::rve::RveMaterialParamsFromSoil(ResolveSoil(soil, field), options_.numerics,
                                      field + ".parameters");
}

int FeDeRunFigures::PointsMoved() const {
  int moved = 0;
  for (const bridge::StepBalance& step : balance) moved += step.points_moved;
  return moved;
}

double FeDeRunFigures::MeanImbalance() const {
  double sum = 0;
  for (const bridge::StepBalance& step : balance) sum += step.imbalance;
  return balance.empty() ? 0 : sum / static_cast<double>(balance.size());
}

double FeDeRunFigures::MaxImbalance() const {
  double largest = 0;
  for (const bridge::StepBalance& step : balance) largest = std::max(largest, step.imbalance);
  return largest;
}

double FeDeRunFigures::MeanBytesPerStep() const {
  double sum = 0;
  for (const bridge::StepBalance& step : balance) {
    sum += static_cast<double>(step.bytes_sent + step.bytes_received);
  }
  return balance.empty() ? 0 : sum / static_cast<double>(balance.size());
}

TractionCurve FeDeTier::ComputeCurve(const TractionRequest& request,
                                     const ComputeContext& context) const {
  return Run(request, context).curve;
}

bool FeDeTier::RunOnBins(const SoilParameters& soil, const ComputeContext& context,
                         const BinWork& work, FeDeRunFigures* figures,
                         const BinModel& bin_model) const {
  const auto start = std::chrono::steady_clock::now();
  dem::rve::RveMaterialParams params =
      dem::rve::RveMaterialParamsFromSoil(soil, options_.numerics, "soil.parameters");
  // Alone, the one rank answers every RVE through the material's own batch, spread over its
  // threads one point to a thread at a time: each point's answer is its own, so the curve is the
  // same on any count. In a rank group this has no effect: bridge::UpdatePoints already spreads
  // each rank's points over its threads, one point a call.
  params.batch_threads = std::max(1, context.threads);
  // Every rank builds the same template RVE (deterministic generation), so a point's state means
  // the same wherever it lives.
  const std::shared_ptr<const dem::rve::RveMaterial> rve = dem::rve::SharedRveMaterial(params);

  const MPI_Comm communicator = bin_model.alone() ? MPI_COMM_NULL : context.communicator;
  int group_rank = 0;
  if (communicator != MPI_COMM_NULL) MPI_Comm_rank(communicator, &group_rank);
  if (group_rank != 0) {
    // An RVE server until rank 0 finishes; it joins rank 0's collective cancellation checks.
    bool cancelled = false;
    bridge::ServeRankGroup(communicator, *rve, bridge::ServeOptions{context.threads},
                           [&](int code) {
                             if (code == kCallCancelCheck) cancelled = context.Cancelled();
                           });
    if (cancelled) throw CancelledError();
    return false;  // the leader's result is the task's
  }

  std::shared_ptr<bridge::RankGroupLink> link;
  std::shared_ptr<const bridge::DistributedModel> distributed;
  std::shared_ptr<const material::ConstitutiveModel> model = rve;
  std::function<std::string(const std::string&)> state_from_rve;
  if (bin_model.continuum) model = bin_model.continuum;
  if (bin_model.stand_in) {
    PointStandIn stand_in = bin_model.stand_in(rve);
    model = std::move(stand_in.model);
    state_from_rve = std::move(stand_in.state_from_rve);
  }
  figures->ranks = 1;
  if (communicator != MPI_COMM_NULL) {
    link = std::make_shared<bridge::RankGroupLink>(communicator);
    figures->ranks = link->size();
    bridge::BalanceOptions balance = options_.balance;
    balance.rank_zero_threads = context.threads;
    distributed = std::make_shared<bridge::DistributedModel>(link, rve, balance);
    model = distributed;
  }
  rig::FeBinSoil bin_soil;
  bin_soil.label = CanonicalText(soil);
  bin_soil.model = model;
  bin_soil.density_kg_m3 = dem::rve::ConsolidatedBulkDensityKgM3(*rve);
  bin_soil.wheel_friction_coefficient = soil.Get("friction");
  bin_soil.wheel_adhesion_pa = 0;
  // Geostatic start: the template settled at the mean stress of each depth (rank 0 only; the
  // states reach their owners as bytes).
  const double unit_weight_n_m3 = bin_soil.density_kg_m3 * units::kStandardGravityMps2;
  const double floor_pa = options_.min_initial_pressure_pa;
  if (!bin_model.continuum) {  // (a continuum soil starts unstressed and settles under gravity)
    bin_soil.initial_state_at_depth = [rve, unit_weight_n_m3, floor_pa,
                                       state_from_rve](double depth_m) {
      dem::rve::Rve settled = rve->initial();
      settled.SettleIsotropic(std::max(floor_pa, unit_weight_n_m3 * depth_m));
      return state_from_rve ? state_from_rve(settled.Save()) : settled.Save();
    };
  }
  rig::FeBinOptions fe_options;
  fe_options.threads = context.threads;
  fe_options.target_time_step_s = options_.fe_time_step_s;
  const rig::FeSoilBinFactory bins(bin_soil, fe_options);

  rig::RigOptions rig_options;
  rig_options.elements_per_radius = options_.elements_per_radius;
  rig_options.threads = context.threads;
  rig_options.progress = context.progress;
  rig_options.poll_every_steps = 20;  // an FE-DE step costs tens of ms: a cancel within a second
  rig_options.checkpoint_dir = context.checkpoint_dir;
  rig_options.checkpoint_every_s = options_.checkpoint_every_s;
  // Collective: the servers take part in the pool's cancellation check at the same point.
  rig_options.cancelled = [&]() {
    if (link) link->Call(kCallCancelCheck);
    return context.Cancelled();
  };
  work(bins, rig_options);
  if (link) link->Finish();
  if (distributed) figures->balance = distributed->balance_history();
  figures->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

void FeDeTier::RollWheel(const TractionRequest& request, const rig::SoilBinFactory& bins,
                         const rig::RigOptions& rig_options, FeDeRunReport* report) const {
  rig::RigWheel wheel;
  wheel.radius_m = 0.5 * request.tyre.diameter_m;
  wheel.width_m = request.tyre.width_m;
  wheel.load_n = request.wheel_load_n;
  TractionCurve& curve = report->curve;
  curve.tier = Name();
  curve.tier_version = Version();
  try {
    const rig::RigRun run = rig::RunDrawbarPullTest(bins, wheel, options_.procedure, rig_options);
    curve.points = rig::CurveFromRun(run, request.slips, wheel.radius_m);
    report->elements = run.elements;
    report->fe_steps = run.steps;
    report->fe_time_step_s = run.time_step_s;
    report->samples = run.samples;
  } catch (const CannotCarryError& e) {
    curve.points.clear();
    curve.immobile_reason = e.what();
  }
}

FeDeRunReport FeDeTier::Run(const TractionRequest& request, const ComputeContext& context) const {
  request.Validate();
  const SoilParameters soil = ResolveSoil(request.soil, "soil");
  FeDeRunReport report;
  const auto roll = [&](const rig::SoilBinFactory& bins, const rig::RigOptions& rig_options) {
    RollWheel(request, bins, rig_options, &report);
  };
  if (!RunOnBins(soil, context, roll, &report)) return {};
  return report;
}

FeDeRunReport FeDeTier::RunContinuumTwin(const TractionRequest& request,
                                         const material::DruckerPragerParams& strength,
                                         const ComputeContext& context) const {
  request.Validate();
  const SoilParameters soil = ResolveSoil(request.soil, "soil");
  const auto model = std::make_shared<const material::DruckerPrager>(strength);
  FeDeRunReport report;
  const auto roll = [&](const rig::SoilBinFactory& bins, rig::RigOptions& rig_options) {
    rig_options.checkpoint_dir.clear();
    RollWheel(request, bins, rig_options, &report);
  };
  BinModel bin_model;
  bin_model.continuum = model;
  RunOnBins(soil, context, roll, &report, bin_model);
  report.curve.tier = "fe-de-twin";
  return report;
}

FeDeRunReport FeDeTier::RunWithStandIn(const TractionRequest& request,
                                       const PointStandInFactory& make_stand_in,
                                       const ComputeContext& context) const {
  request.Validate();
  const SoilParameters soil = ResolveSoil(request.soil, "soil");
  FeDeRunReport report;
  const auto roll = [&](const rig::SoilBinFactory& bins, rig::RigOptions& rig_options) {
    RollWheel(request, bins, rig_options, &report);
  };
  BinModel bin_model;
  bin_model.stand_in = make_stand_in;
  RunOnBins(soil, context, roll, &report, bin_model);
  return report;
}

FeDeBevameterReport FeDeTier::RunBevameter(
    const SoilState& soil_state, const rig::BevameterSpec& spec, double element_size_m,
    const ComputeContext& context, const material::DruckerPragerParams* continuum_twin) const {
  spec.Validate("bevameter.");
  Require(std::isfinite(element_size_m) && element_size_m >= 0, "bevameter.element_size_m",
          "must be a length >= 0, m (0: the bevameter's own choice)");
  const SoilParameters soil = ResolveSoil(soil_state, "soil");
  FeDeBevameterReport report;
  const auto test = [&](const rig::SoilBinFactory& bins, rig::RigOptions& rig_options) {
    rig_options.element_size_m = element_size_m;
    rig_options.checkpoint_dir.clear();  // only the wheel bins checkpoint
    report.bevameter = rig::RunVirtualBevameter(bins, spec, rig_options);
  };
  BinModel bin_model;
  if (continuum_twin) {
    bin_model.continuum = std::make_shared<const material::DruckerPrager>(*continuum_twin);
  }
  if (!RunOnBins(soil, context, test, &report, bin_model)) return {};
  return report;
}

}  // namespace gonogo::tiers
