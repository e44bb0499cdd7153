// The 8-node hexahedron with one-point (centroid) integration and Flanagan-Belytschko hourglass
// control: what every element of the explicit solver computes once, in the reference
// configuration (total Lagrangian). Hourglass control after D. P. Flanagan and T. Belytschko, "A
// uniform strain hexahedron and quadrilateral with orthogonal hourglass control", IJNME 17 (1981)
// 679-706, and Belytschko, Liu & Moran, Nonlinear Finite Elements for Continua and Structures
// (Wiley 2000), ch. 8.
#pragma once

#include <Eigen/Core>
#include <array>

#include "solvers/fe/mesh.h"

namespace gonogo::fe {

using Mat83 = Eigen::Matrix<double, 8, 3>;
using Mat48 = Eigen::Matrix<double, 4, 8>;

struct Hex8Reference {
  Mat83 gradients_per_m;      // (8 x 3) b_a = dN_a/dX at the centroid
  double volume_m3 = 0;       // V_0 = 8 det(dX/dxi) at the centroid
  Mat48 hourglass_vectors;    // (4 x 8) gamma_alpha,a of Flanagan & Belytschko (1981)
  double characteristic_length_m = 0;  // V_0 / largest face area, for the stable time step
};

// Throws InputError("mesh", ...) when the element is inverted or degenerate (det J <= 0).
Hex8Reference ComputeHex8Reference(const std::array<Vec3, 8>& reference_positions_m);

// Deformation gradient F = sum_a x_a (x) b_a of one-point integration.
Eigen::Matrix3d DeformationGradient(const std::array<Vec3, 8>& current_positions_m,
                                    const Mat83& gradients_per_m);

}  // namespace gonogo::fe
