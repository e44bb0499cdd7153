// A material point's history along a strain path: what a surrogate of the point learns from
// (issue "FE-ANN tier", training data). Per step the displacement-gradient increment dH applied,
// the Cauchy stress after it and, optionally, internal variables of the state (void ratio,
// coordination ...), with the stress the path started from.
//
// Stored compactly (SerializeHistory: a tagged little-endian float64 block, 8 + 16 + 8 (9 + 6 + V)
// bytes per step) and exported as NumPy .npy or CSV for training elsewhere: one row per step,
// columns history, step, dH_xx dH_xy dH_xz dH_yx dH_yy dH_yz dH_zx dH_zy dH_zz (row-major),
// sigma_xx sigma_yy sigma_zz sigma_yz sigma_xz sigma_xy (Pa, tension positive), then the
// internal variables by name.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/material/constitutive.h"
#include "solvers/material/kinematics.h"

namespace gonogo::ann {

using material::Matrix3;
using material::Vector6;

struct StrainHistory {
  Matrix3 initial_stress_pa = Matrix3::Zero();
  std::vector<std::string> internal_variable_names;
  std::vector<Matrix3> increments;                   // dH per step
  std::vector<Vector6> stresses_pa;                  // Voigt, after each step
  std::vector<std::vector<double>> internal_variables;  // per step, by name (may be empty)
  // The internal variables of the state the path started from, by name: what a network that
  // carries them (stress_surrogate.h) takes before the first step. Empty when not recorded.
  std::vector<double> initial_internal_variables;
  // Why the path ended before its last step (a model failure); empty when it ran to the end.
  std::string stopped_reason;

  std::size_t steps() const { return increments.size(); }
};

// Compact bytes: "GNGHIS01" when the initial internal variables are not recorded (the bytes, and so
// the data hashes, of histories recorded before they were), "GNGHIS02" with them after the names.
// ParseHistory reads both and throws InputError("history", ...) for a truncated,
// foreign or inconsistent buffer.
std::string SerializeHistory(const StrainHistory& history);
StrainHistory ParseHistory(const std::string& bytes);

// The export's column names (see above), for histories with these internal variables.
std::vector<std::string> HistoryColumns(const std::vector<std::string>& internal_variable_names);

// Every step of every history as one float64 table. All histories must carry the same internal
// variables (InputError("histories", ...) otherwise). The .npy is format 1.0, little-endian
// '<f8', C order, shape (rows, columns); its column names go in a `.columns.txt` beside it (the
// .npy format has no place for them). Throws std::runtime_error when a file cannot be written.
void WriteHistoriesNpy(const std::string& path, const std::vector<StrainHistory>& histories);
void WriteHistoriesCsv(const std::string& path, const std::vector<StrainHistory>& histories);

// `history` seen in a frame turned by the rotation Q: dH' = Q dH Q^T, sigma' = Q sigma Q^T (the
// initial stress too). A symmetric tensor recorded as the six internal variables <name>_xx,
// _yy, _zz, _yz, _xz, _xy (a fabric) is turned the same way; every other internal variable is
// kept, so it must be an invariant (void ratio, coordination number).
StrainHistory Rotated(const StrainHistory& history, const Matrix3& rotation);

// The training set of an isotropic material augmented by its frame indifference: `histories`
// followed by `copies` rotated copies of each, turned by rotations drawn uniformly (a normalised
// Gaussian quaternion) from `seed`. A DE packing prepared isotropically is isotropic up to its
// fabric's noise: the same path in another frame is another path of the same soil, so the
// network learns answers for stresses whose principal axes are not the laboratory's, and the
// envelope (surrogate_ensemble.h) covers them. Throws InputError("rotated_copies", ...) for
// copies outside [0, 64].
std::vector<StrainHistory> WithRotatedCopies(const std::vector<StrainHistory>& histories,
                                             int copies, std::uint64_t seed);

}  // namespace gonogo::ann
