// Physical and mathematical constants and unit conversions used across gonogo, in one place so
// that no two parts of the code disagree on a value (two values of g were in use before this
// header). Header-only, constexpr, no dependencies.
//
// Names carry the unit, as everywhere in gonogo (CONVENTIONS.md): kStandardGravityMps2 is m/s^2.
// Conversions between customary units of a single module (psi, inch, pound in the NRMM cone-index
// code) stay with that module; this header holds what more than one module needs.
#pragma once

namespace gonogo::units {

// Mathematical constants (to the precision of a double).
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kHalfPi = 0.5 * kPi;
inline constexpr double kTwoPi = 2.0 * kPi;

// Standard acceleration of gravity g_n = 9.80665 m/s^2, exact by definition: declaration of the
// 3rd CGPM (1901) on the unit of mass and the definition of weight, restated in ISO 80000-3
// (standard acceleration of free fall, g_n). The value gonogo uses for weight <-> mass everywhere;
// code reproducing a published table computed with another g (9.81, say) keeps that value as a
// named local constant with its source.
inline constexpr double kStandardGravityMps2 = 9.80665;

// Angles.
inline constexpr double kRadiansPerDegree = kPi / 180.0;
inline constexpr double kDegreesPerRadian = 180.0 / kPi;
constexpr double DegreesToRadians(double degrees) { return degrees * kRadiansPerDegree; }
constexpr double RadiansToDegrees(double radians) { return radians * kDegreesPerRadian; }

// Pressure: gonogo computes in pascals; parameter tables and papers often give kilopascals.
inline constexpr double kPascalsPerKilopascal = 1e3;
constexpr double KilopascalsToPascals(double kilopascals) {
  return kilopascals * kPascalsPerKilopascal;
}
constexpr double PascalsToKilopascals(double pascals) { return pascals / kPascalsPerKilopascal; }

}  // namespace gonogo::units
