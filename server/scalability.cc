#include "server/scalability.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <unistd.h>

#include "server/convert.h"
#include "server/curve_lookup.h"
#include "server/geo/plot.h"
#include "solvers/common/errors.h"
#include "solvers/mobility/similarity.h"

namespace gonogo::server {

namespace {

constexpr int kMaxScales = 8;


// Lengths times k, load times k^2: equal W/(b d) (seed 001 Table 6).
TractionRequest ScaledRequest(const TractionRequest& full, double k) {
  TractionRequest r = full;
  TyreGeometry& t = r.tyre;
  t.diameter_m *= k;
  t.width_m *= k;
  t.section_height_m *= k;
  t.deflection_m *= k;
  t.rolling_radius_m *= k;
  r.wheel_load_n *= k * k;
  return r;
}

// Colours for up to kMaxScales series; the reference is black.
const std::array<uint8_t, 3> kColours[kMaxScales] = {
    {0, 0, 0}, {213, 94, 0}, {0, 114, 178}, {0, 158, 115},
    {204, 121, 167}, {230, 159, 0}, {86, 180, 233}, {120, 120, 120}};

std::string PlotPng(const v1::ScalabilityRequest& request,
                    const std::vector<std::vector<mobility::DimensionlessPoint>>& curves,
                    const mobility::BandWidths& band) {
  struct Quantity {
    const char* title;
    const char* y_label;
    double mobility::DimensionlessPoint::*field;
    double width;
  };
  const Quantity quantities[3] = {
      {"drawbar pull coefficient", "D/W", &mobility::DimensionlessPoint::drawbar_pull_coefficient,
       band.drawbar_pull},
      {"gross traction coefficient", "T/(rW)",
       &mobility::DimensionlessPoint::gross_traction_coefficient, band.gross_traction},
      {"tractive efficiency", "efficiency", &mobility::DimensionlessPoint::tractive_efficiency,
       band.efficiency}};
  std::vector<geo::PlotPanel> panels;
  for (const Quantity& q : quantities) {
    geo::PlotPanel panel;
    panel.title = q.title;
    panel.x_label = "slip";
    panel.y_label = q.y_label;
    panel.x_min = 0;
    panel.x_max = 1;
    geo::PlotBand b;
    for (const auto& p : curves[0]) {
      b.x.push_back(p.slip);
      b.lower.push_back(p.*q.field - q.width);
      b.upper.push_back(p.*q.field + q.width);
    }
    panel.bands.push_back(b);
    for (size_t i = 0; i < curves.size(); ++i) {
      if (curves[i].empty()) continue;  // a scale the soil cannot carry
      geo::PlotSeries s;
      std::ostringstream label;
      label << "scale " << request.scales(static_cast<int>(i));
      s.label = label.str();
      s.rgb = kColours[i];
      s.dashed = i > 0;
      s.markers = true;
      for (const auto& p : curves[i]) {
        s.x.push_back(p.slip);
        s.y.push_back(p.*q.field);
      }
      panel.series.push_back(s);
    }
    panels.push_back(panel);
  }
  static std::atomic<int> counter{0};
  const auto path = std::filesystem::temp_directory_path() /
                    ("gonogo-scalability-" + std::to_string(getpid()) + "-" +
                     std::to_string(counter++) + ".png");
  geo::WritePlotPng(panels, path.string());
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  std::filesystem::remove(path);
  return bytes.str();
}

}  // namespace

v1::ScalabilityReport RunScalabilityStudy(const v1::ScalabilityRequest& request,
                                          const TierRegistry& tiers, CurveResolver& resolver,
                                          std::chrono::steady_clock::time_point deadline,
                                          const std::function<bool()>& abandon,
                                          const std::string& curve_scope) {
  Require(!request.tier().empty(), "tier", "is missing");
  const TractionTier& tier = tiers.Get(request.tier());
  Require(request.has_tyre(), "tyre", "is missing");
  const int n = request.scales_size();
  Require(n >= 2 && n <= kMaxScales, "scales",
          "give 2 to " + std::to_string(kMaxScales) + " scales, one of them 1");
  Require(request.scales(0) == 1.0, "scales", "the first scale must be 1 (the full-scale tyre)");
  for (int i = 0; i < n; ++i) {
    const double k = request.scales(i);
    Require(std::isfinite(k) && k > 0 && k <= 1, "scales", "each scale must lie in (0, 1]");
    for (int j = 0; j < i; ++j) Require(request.scales(j) != k, "scales", "scales repeat");
  }
  TractionRequest full;
  full.tyre = FromProto(request.tyre());
  full.wheel_load_n = request.wheel_load_n();
  full.soil = SoilForTier(tier, FromProto(request.soil()));
  // An explicit rolling radius scales with the tyre; a derived one follows d/2 - delta anyway.
  full.slips = TractionRequest::SlipSweep(request.slip_step() == 0 ? 0.05 : request.slip_step());
  full.Validate();
  tier.ValidateSoil(full.soil, "soil");
  tier.ResolveChoices(full, "");

  // One task per scale: the exact cache key, else the pool (never similarity: see the header).
  std::vector<CurveTask> tasks;
  for (int i = 0; i < n; ++i) {
    tasks.push_back(CurveResolver::Prepare(tier, ScaledRequest(full, request.scales(i))));
  }
  ResolveOptions options;
  options.allow_similarity = false;
  options.deadline = deadline;
  options.stop = abandon;
  options.stop_on_failure = true;
  options.scope = curve_scope;
  const std::vector<Resolution> resolved = resolver.Resolve(tier, tasks, options);
  std::vector<cache::StoredCurve> found;  // the stored curve of each scale
  for (int i = 0; i < n; ++i) {
    const Resolution& r = resolved[i];
    if (r.source == CurveSource::kCancelled) {
      throw std::runtime_error("the scalability study was not finished in time");
    }
    if (!r.ok()) {
      ThrowError(r.error_kind, "scales",
                 "scale " + std::to_string(request.scales(i)) + ": " + r.error);
    }
    found.push_back(r.stored);
  }

  // The full-scale wheel must be carried (it defines the band); a scale model that sinks past its
  // axle is reported as such.
  Require(found[0].curve.immobile_reason.empty(), "tyre",
          "the full-scale wheel: " + found[0].curve.immobile_reason);
  std::vector<std::vector<mobility::DimensionlessPoint>> dimensionless;
  for (int i = 0; i < n; ++i) {
    dimensionless.push_back(mobility::ToDimensionless(tasks[i].request, found[i].curve));
  }
  const mobility::BandWidths band = mobility::FullScaleBand(dimensionless[0]);
  v1::ScalabilityReport report;
  for (int i = 0; i < n; ++i) {
    v1::ScalabilityRow* row = report.add_rows();
    row->set_scale(request.scales(i));
    *row->mutable_tyre() = ToProto(tasks[i].request.tyre);
    row->set_wheel_load_n(tasks[i].request.wheel_load_n);
    if (found[i].curve.immobile_reason.empty()) {
      const mobility::BandAgreement a =
          mobility::CompareToFullScale(dimensionless[0], dimensionless[i]);
      row->set_drawbar_pull_inside_pct(a.drawbar_pull_pct);
      row->set_gross_traction_inside_pct(a.gross_traction_pct);
      row->set_efficiency_inside_pct(a.efficiency_pct);
    } else {
      row->set_immobile_reason(found[i].curve.immobile_reason);
    }
    for (const TractionPoint& p : found[i].curve.points) *row->add_points() = ToProto(p);
    if (i > 0) {
      if (auto seed = mobility::ScalabilityTable::Seed001().For(request.scales(i),
                                                                full.soil.cone_index_pa)) {
        v1::SimilarityReliability* m = row->mutable_seed_measured();
        m->set_reference_soil(seed->soil);
        m->set_reference_scale(seed->scale);
        m->set_drawbar_pull_pct(seed->drawbar_pull_pct);
        m->set_gross_traction_pct(seed->gross_traction_pct);
        m->set_efficiency_pct(seed->efficiency_pct);
      }
    }
    v1::TractionCurve shell;
    FillCurve(found[i], false, &shell);
    *row->mutable_provenance() = shell.provenance();
  }
  report.set_band_drawbar_pull(band.drawbar_pull);
  report.set_band_gross_traction(band.gross_traction);
  report.set_band_efficiency(band.efficiency);
  report.set_band_definition(
      "full-scale curve +- one sample standard deviation of the full-scale coefficient over the "
      "slip sweep; a scaled point is inside when it lies within the band at the same slip");
  report.set_plot_png(PlotPng(request, dimensionless, band));
  return report;
}

}  // namespace gonogo::server
