#include "solvers/mobility/similarity.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "solvers/common/errors.h"

namespace gonogo::mobility {

extern const char kScalabilityTablesCsv[];  // generated from data/scalability_tables.csv

namespace {
// Cone indexes of seed 001's two soils (Table 3 and section 5), Pa.
constexpr double k2nsConeIndexPa = 149e3;
constexpr double kFgsConeIndexPa = 22e3;

bool RelativeClose(double a, double b, double tolerance) {
  return std::abs(a - b) <= tolerance * std::max(std::abs(a), std::abs(b));
}
}  // namespace

PiTerms ComputePiTerms(const TractionRequest& r) {
  return PiTerms{r.tyre.width_m / r.tyre.diameter_m, r.tyre.deflection_m / r.tyre.section_height_m,
                 r.wheel_load_n / (r.tyre.width_m * r.tyre.diameter_m)};
}

bool PiTermsMatch(const PiTerms& a, const PiTerms& b, double tolerance) {
  return RelativeClose(a.width_over_diameter, b.width_over_diameter, tolerance) &&
         std::abs(a.deflection_over_height - b.deflection_over_height) <= tolerance &&
         RelativeClose(a.load_over_bd_pa, b.load_over_bd_pa, tolerance);
}

std::vector<DimensionlessPoint> ToDimensionless(const TractionRequest& r, const TractionCurve& c) {
  const double w = r.wheel_load_n;
  const double rw = r.tyre.RollingRadius() * w;
  std::vector<DimensionlessPoint> out;
  out.reserve(c.points.size());
  for (const TractionPoint& p : c.points) {
    out.push_back({p.slip, p.drawbar_pull_n / w, p.torque_nm / rw, p.sinkage_m / r.tyre.diameter_m,
                   p.tractive_efficiency, p.motion_resistance_n / w});
  }
  return out;
}

TractionCurve FromDimensionless(const TractionRequest& target,
                                const std::vector<DimensionlessPoint>& points) {
  const double w = target.wheel_load_n;
  const double r = target.tyre.RollingRadius();
  TractionCurve c;
  for (const DimensionlessPoint& p : points) {
    TractionPoint q;
    q.slip = p.slip;
    q.drawbar_pull_n = p.drawbar_pull_coefficient * w;
    q.torque_nm = p.gross_traction_coefficient * r * w;
    q.sinkage_m = p.sinkage_over_diameter * target.tyre.diameter_m;
    q.tractive_efficiency = p.tractive_efficiency;
    q.gross_traction_n = p.gross_traction_coefficient * w;
    q.motion_resistance_n = p.motion_resistance_coefficient * w;
    c.points.push_back(q);
  }
  return c;
}

namespace {
// Sample standard deviation of a field over the points.
template <typename Field>
double StandardDeviation(const std::vector<DimensionlessPoint>& points, Field field) {
  if (points.size() < 2) return 0;
  double mean = 0;
  for (const auto& p : points) mean += field(p);
  mean /= points.size();
  double sum = 0;
  for (const auto& p : points) sum += (field(p) - mean) * (field(p) - mean);
  return std::sqrt(sum / (points.size() - 1));
}
}  // namespace

BandWidths FullScaleBand(const std::vector<DimensionlessPoint>& f) {
  return {StandardDeviation(f, [](const auto& p) { return p.drawbar_pull_coefficient; }),
          StandardDeviation(f, [](const auto& p) { return p.gross_traction_coefficient; }),
          StandardDeviation(f, [](const auto& p) { return p.tractive_efficiency; })};
}

BandAgreement CompareToFullScale(const std::vector<DimensionlessPoint>& full,
                                 const std::vector<DimensionlessPoint>& scaled) {
  Require(full.size() == scaled.size() && !full.empty(), "scales",
          "full-scale and scaled curves must share one slip sweep");
  const BandWidths band = FullScaleBand(full);
  int d = 0, t = 0, e = 0;
  for (size_t i = 0; i < full.size(); ++i) {
    Require(std::abs(full[i].slip - scaled[i].slip) < 1e-9, "scales",
            "full-scale and scaled curves must share one slip sweep");
    // A hair of tolerance so that identical curves with a zero-width band count as inside.
    d += std::abs(scaled[i].drawbar_pull_coefficient - full[i].drawbar_pull_coefficient) <=
         band.drawbar_pull + 1e-12;
    t += std::abs(scaled[i].gross_traction_coefficient - full[i].gross_traction_coefficient) <=
         band.gross_traction + 1e-12;
    e += std::abs(scaled[i].tractive_efficiency - full[i].tractive_efficiency) <=
         band.efficiency + 1e-12;
  }
  const double n = static_cast<double>(full.size());
  return {100.0 * d / n, 100.0 * t / n, 100.0 * e / n};
}

ScalabilityTable ScalabilityTable::Parse(const std::string& csv) {
  ScalabilityTable t;
  std::istringstream lines(csv);
  bool header = true;
  int n = 0;
  for (std::string line; std::getline(lines, line);) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::istringstream cells(line);
    ScalabilityRecord rec;
    std::string cell;
    std::vector<std::string> v;
    while (std::getline(cells, cell, ',')) v.push_back(cell);
    Require(v.size() == 5, "scalability_tables.csv", "line " + std::to_string(n) + " needs 5 columns");
    try {
      rec = {v[0], std::stod(v[1]), std::stod(v[2]), std::stod(v[3]), std::stod(v[4])};
    } catch (const std::logic_error&) {
      throw InputError("scalability_tables.csv", "line " + std::to_string(n) + " has a bad number");
    }
    t.records_.push_back(rec);
  }
  return t;
}

const ScalabilityTable& ScalabilityTable::Seed001() {
  static const ScalabilityTable table = Parse(kScalabilityTablesCsv);
  return table;
}

std::optional<ScalabilityRecord> ScalabilityTable::For(double ratio, double cone_index_pa) const {
  // The largest tabulated scale not above the ratio.
  double scale = -1;
  for (const auto& r : records_) {
    if (r.scale <= ratio + 1e-9) scale = std::max(scale, r.scale);
  }
  if (scale < 0) return std::nullopt;
  auto row = [&](const std::string& soil) -> std::optional<ScalabilityRecord> {
    for (const auto& r : records_) {
      if (r.soil == soil && r.scale == scale) return r;
    }
    return std::nullopt;
  };
  const auto ns = row("2NS");
  const auto fgs = row("FGS");
  if (!ns || !fgs) return ns ? ns : fgs;
  if (cone_index_pa > 0) {
    const double to_2ns = std::abs(std::log(cone_index_pa / k2nsConeIndexPa));
    const double to_fgs = std::abs(std::log(cone_index_pa / kFgsConeIndexPa));
    return to_2ns <= to_fgs ? ns : fgs;
  }
  ScalabilityRecord worst{"2NS/FGS (lower of the two)", scale,
                          std::min(ns->drawbar_pull_pct, fgs->drawbar_pull_pct),
                          std::min(ns->gross_traction_pct, fgs->gross_traction_pct),
                          std::min(ns->efficiency_pct, fgs->efficiency_pct)};
  return worst;
}

}  // namespace gonogo::mobility
