#include "cache/curve_key.h"

#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace gonogo::cache {

namespace {
double Snap(double value, double resolution) { return std::round(value / resolution) * resolution; }

std::string Fixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}
}  // namespace

std::string BekkerText(const SoilState& soil) {
  if (!soil.bekker) return "";
  const BekkerParameters& b = *soil.bekker;
  char buf[256];
  std::snprintf(buf, sizeof buf, "n=%.9g,kc=%.9g,kphi=%.9g,c=%.9g,phi_deg=%.9g,K=%.9g", b.n, b.kc,
                b.kphi, b.cohesion_pa, b.friction_angle_deg, b.shear_deformation_m);
  return buf;
}

int ConeIndexBin(double cone_index_pa) {
  if (cone_index_pa <= 0) return INT_MIN;
  return static_cast<int>(std::lround(std::log(cone_index_pa / 1000.0) / std::log(kConeIndexBinRatio)));
}

double ConeIndexOfBin(int bin) {
  if (bin == INT_MIN) return 0.0;
  // Rounded to 0.01 Pa so that the representative value prints identically everywhere.
  return Snap(1000.0 * std::pow(kConeIndexBinRatio, bin), 0.01);
}

TractionRequest Quantise(const TractionRequest& r) {
  TractionRequest q = r;
  q.soil.cone_index_pa = ConeIndexOfBin(ConeIndexBin(r.soil.cone_index_pa));
  q.tyre.diameter_m = Snap(r.tyre.diameter_m, kLengthResolutionM);
  q.tyre.width_m = Snap(r.tyre.width_m, kLengthResolutionM);
  q.tyre.section_height_m = Snap(r.tyre.section_height_m, kLengthResolutionM);
  q.tyre.deflection_m = Snap(r.tyre.deflection_m, kLengthResolutionM);
  // The rolling radius is always stored explicitly, so "derived" and "given" requests share keys.
  q.tyre.rolling_radius_m = Snap(r.tyre.RollingRadius(), kLengthResolutionM);
  q.tyre.inflation_pressure_pa = Snap(r.tyre.inflation_pressure_pa, kPressureResolutionPa);
  q.wheel_load_n = Snap(r.wheel_load_n, kLoadResolutionN);
  for (double& s : q.slips) s = Snap(s, kSlipResolution);
  if (q.soil.bekker) {
    // Snap to the nine significant digits of the key so the computed curve is the key's curve.
    BekkerParameters& b = *q.soil.bekker;
    for (double* v : {&b.n, &b.kc, &b.kphi, &b.cohesion_pa, &b.friction_angle_deg,
                      &b.shear_deformation_m}) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.9g", *v);
      *v = std::strtod(buf, nullptr);
    }
  }
  return q;
}

std::string CurveKey(const std::string& tier, const std::string& tier_version,
                     const TractionRequest& q) {
  std::string key = std::string(kCurveKeyVersion) + ";tier=" + tier + ";version=" + tier_version +
                    ";soil=" + q.soil.soil_name + ";ci_pa=" + Fixed(q.soil.cone_index_pa, 2) +
                    ";d_m=" + Fixed(q.tyre.diameter_m, 4) + ";b_m=" + Fixed(q.tyre.width_m, 4) +
                    ";h_m=" + Fixed(q.tyre.section_height_m, 4) +
                    ";delta_m=" + Fixed(q.tyre.deflection_m, 4) +
                    ";r_m=" + Fixed(q.tyre.rolling_radius_m, 4) +
                    ";pi_pa=" + Fixed(q.tyre.inflation_pressure_pa, 0) +
                    ";w_n=" + Fixed(q.wheel_load_n, 0) + ";bekker=" + BekkerText(q.soil) +
                    ";slips=";
  for (size_t i = 0; i < q.slips.size(); ++i) {
    if (i) key += ',';
    key += Fixed(q.slips[i], 6);
  }
  return key;
}

std::string SimilarityGroup(const std::string& tier, const std::string& tier_version,
                            const TractionRequest& q) {
  std::string group = "gonogo-similar-v1;tier=" + tier + ";version=" + tier_version +
                      ";soil=" + q.soil.soil_name + ";ci_pa=" + Fixed(q.soil.cone_index_pa, 2) +
                      ";pi_pa=" + Fixed(q.tyre.inflation_pressure_pa, 0) +
                      ";bekker=" + BekkerText(q.soil) + ";slips=";
  for (size_t i = 0; i < q.slips.size(); ++i) {
    if (i) group += ',';
    group += Fixed(q.slips[i], 6);
  }
  return group;
}

}  // namespace gonogo::cache
