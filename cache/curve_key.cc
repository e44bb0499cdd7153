#include "cache/curve_key.h"

#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "solvers/common/soil_model.h"

namespace gonogo::cache {

namespace {
double Snap(double value, double resolution) { return std::round(value / resolution) * resolution; }

std::string Fixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}
}  // namespace

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
  if (q.soil.parameters) {
    // Defaults filled and snapped to the key's digits, so the computed curve is the key's curve.
    q.soil.parameters =
        SnapToCanonical(SoilModels().Validate(*q.soil.parameters, "soil.parameters"));
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
                    ";w_n=" + Fixed(q.wheel_load_n, 0) + ";params=" + CanonicalText(q.soil.parameters) +
                    ";slips=";
  for (size_t i = 0; i < q.slips.size(); ++i) {
    if (i) key += ',';
    key += Fixed(q.slips[i], 6);
  }
  // Only a tier with surrogate models has one (fe-ann); every other key is as it was.
  if (!q.surrogate_model.empty()) key += ";model=" + q.surrogate_model;
  return key;
}

std::string SurrogateModelOfKey(const std::string& key) {
  const std::string field = ";model=";
  const std::size_t at = key.rfind(field);
  return at == std::string::npos ? std::string() : key.substr(at + field.size());
}

std::string SimilarityGroup(const std::string& tier, const std::string& tier_version,
                            const TractionRequest& q) {
  std::string group = std::string(kSimilarityGroupVersion) + ";tier=" + tier + ";version=" + tier_version +
                      ";soil=" + q.soil.soil_name + ";ci_pa=" + Fixed(q.soil.cone_index_pa, 2) +
                      ";pi_pa=" + Fixed(q.tyre.inflation_pressure_pa, 0) +
                      ";params=" + CanonicalText(q.soil.parameters) + ";slips=";
  for (size_t i = 0; i < q.slips.size(); ++i) {
    if (i) group += ',';
    group += Fixed(q.slips[i], 6);
  }
  if (!q.surrogate_model.empty()) group += ";model=" + q.surrogate_model;
  return group;
}

std::string Scoped(const std::string& scope, const std::string& key_or_group) {
  return scope.empty() ? key_or_group : "scope=" + scope + "|" + key_or_group;
}

}  // namespace gonogo::cache
