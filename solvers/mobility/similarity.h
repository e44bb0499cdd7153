// Similarity of tyre-soil systems (seed 001, section 4, eqs. 10-11): on one soil, the drawbar-pull
// coefficient D/W, the gross-traction coefficient T/(rW) and the tractive efficiency are functions of
// b/d, delta/h, slip and CI b d / W only. So a curve computed for one tyre answers a geometrically
// similar tyre with the same pi-terms, scaled back to dimensional form. Seed 001 measured how well
// that holds by scale (its Tables 7 and 8, `data/scalability_tables.csv`).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "solvers/common/traction.h"

namespace gonogo::mobility {

// Pi-terms of a request (seed 001 eq. 7). On one soil CI is fixed, so equal CI b d / W is equal
// ground pressure W / (b d); that form is kept because it also serves soils given without a CI.
struct PiTerms {
  double width_over_diameter = 0;       // b / d
  double deflection_over_height = 0;    // delta / h
  double load_over_bd_pa = 0;           // W / (b d), Pa
};

PiTerms ComputePiTerms(const TractionRequest& request);

// Relative tolerance on every pi-term for a similarity hit (b/d and W/(b d) relative, delta/h
// absolute as a fraction of h).
inline constexpr double kPiTermTolerance = 0.01;
// Seed 001, conclusions: "up to 0.5 scale-system can predict the full-scale system's mobility
// performance on sandy soils"; smaller ratios are not served from similarity.
inline constexpr double kMinimumScaleRatio = 0.5;

bool PiTermsMatch(const PiTerms& a, const PiTerms& b, double tolerance = kPiTermTolerance);

// One point of a curve in dimensionless form.
struct DimensionlessPoint {
  double slip = 0;
  double drawbar_pull_coefficient = 0;    // D / W
  double gross_traction_coefficient = 0;  // T / (r W)
  double sinkage_over_diameter = 0;       // z / d
  double tractive_efficiency = 0;
  double motion_resistance_coefficient = 0;  // MR / W
};

std::vector<DimensionlessPoint> ToDimensionless(const TractionRequest& request,
                                                const TractionCurve& curve);
// The dimensional curve of `target` from dimensionless points (D = (D/W) W, T = (T/(rW)) r W,
// z = (z/d) d; efficiency unchanged).
TractionCurve FromDimensionless(const TractionRequest& target,
                                const std::vector<DimensionlessPoint>& points);

// The comparison of seed 001 section 6.4 for a model: the percentage of a scaled tyre's points
// inside the full-scale tyre's one-standard-deviation band. The seed's band is the scatter of its DEM
// data; a model curve has no scatter, so the band here is the full-scale curve +- the standard
// deviation of the full-scale coefficient over the slip sweep (the spread of the full-scale data set
// the seed draws its band from). Points are compared slip by slip; both curves share the sweep.
struct BandAgreement {
  double drawbar_pull_pct = 0;     // D/W
  double gross_traction_pct = 0;   // T/(rW)
  double efficiency_pct = 0;
};
struct BandWidths {
  double drawbar_pull = 0;         // one standard deviation of the full-scale D/W
  double gross_traction = 0;
  double efficiency = 0;
};
BandWidths FullScaleBand(const std::vector<DimensionlessPoint>& full_scale);
// Throws InputError("scales") when the sweeps differ.
BandAgreement CompareToFullScale(const std::vector<DimensionlessPoint>& full_scale,
                                 const std::vector<DimensionlessPoint>& scaled);

// Seed 001 Tables 7 and 8: percent of scaled-tyre points inside the full-scale one-standard-
// deviation band.
struct ScalabilityRecord {
  std::string soil;          // "2NS" (cone index 149 kPa) or "FGS" (22 kPa)
  double scale = 0;          // 0.7, 0.5, 0.25
  double drawbar_pull_pct = 0;
  double gross_traction_pct = 0;
  double efficiency_pct = 0;
};

class ScalabilityTable {
 public:
  // Parses the CSV of `data/scalability_tables.csv` ('#' comments, a header line).
  static ScalabilityTable Parse(const std::string& csv_text);
  // The table of seed 001, embedded at build time.
  static const ScalabilityTable& Seed001();

  // The measured reliability for a scale ratio (smaller over larger diameter): the row of the
  // largest tabulated scale not above the ratio (conservative), from the soil nearest in log cone
  // index; with no cone index, the lower of the two soils' figures. nullopt below the smallest scale.
  std::optional<ScalabilityRecord> For(double scale_ratio, double cone_index_pa) const;
  const std::vector<ScalabilityRecord>& records() const { return records_; }

 private:
  std::vector<ScalabilityRecord> records_;
};

}  // namespace gonogo::mobility
