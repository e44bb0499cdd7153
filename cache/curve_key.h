// Canonical, quantised, versioned keys for traction curves (ARCHITECTURE section 6).
//
// A request is first snapped to the key's resolution and then computed with the snapped values, so a
// cached curve is exactly the curve of its key: cone index on logarithmic bins 1 % apart, lengths to
// 0.1 mm, wheel load to 1 N, inflation pressure to 100 Pa, slips to 1e-6; explicit soil-model
// parameters enter as their canonical text (solvers/common/soil_model.h: defaults filled, sorted,
// nine significant digits). The tier's version is part of the key, so a solver change never serves
// a stale curve.
#pragma once

#include <string>

#include "solvers/common/traction.h"

namespace gonogo::cache {

inline constexpr char kCurveKeyVersion[] = "gonogo-curve-v2";
inline constexpr char kSimilarityGroupVersion[] = "gonogo-similar-v2";
inline constexpr double kConeIndexBinRatio = 1.01;   // adjacent cone-index bins differ by 1 %
inline constexpr double kLengthResolutionM = 1e-4;   // 0.1 mm
inline constexpr double kLoadResolutionN = 1.0;
inline constexpr double kSlipResolution = 1e-6;
inline constexpr double kPressureResolutionPa = 100.0;  // inflation pressure

// Bin of a cone index (Pa). Bin 0 is 1 kPa; INT32_MIN stands for a cone index of exactly 0.
int ConeIndexBin(double cone_index_pa);
// The representative cone index (Pa) of a bin.
double ConeIndexOfBin(int bin);
// Snaps every field of the request to the key's resolution; explicit soil parameters get their
// model's defaults (SoilModels().Validate, which throws InputError for an invalid set) and nine
// significant digits.
TractionRequest Quantise(const TractionRequest& request);
// Key of an already quantised request.
std::string CurveKey(const std::string& tier, const std::string& tier_version,
                     const TractionRequest& quantised);

// The surrogate model a key names (its ";model=" field, last when present); "" for none.
std::string SurrogateModelOfKey(const std::string& key);

// Everything a curve depends on except the tyre's size and its load: curves in one group are on
// the same soil with the same procedure, so they can stand in for each other when their pi-terms
// match (solvers/mobility/similarity.h).
std::string SimilarityGroup(const std::string& tier, const std::string& tier_version,
                            const TractionRequest& quantised);
// A cache key or similarity group within a scope: itself for the shared scope (""), else prefixed
// by the scope, so that curves of one scope (an identity, when sharing is off) never answer another.
std::string Scoped(const std::string& scope, const std::string& key_or_group);

}  // namespace gonogo::cache
