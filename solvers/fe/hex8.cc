#include "solvers/fe/hex8.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::fe {
namespace {

// The four hourglass base vectors h_alpha,a: the bilinear and trilinear terms xi eta, eta zeta,
// zeta xi and xi eta zeta evaluated at the nodes (Flanagan & Belytschko 1981).
Mat48 HourglassBase() {
  Mat48 h;
  for (int a = 0; a < 8; ++a) {
    const double xi = kHexNodeSigns[a][0], eta = kHexNodeSigns[a][1], zeta = kHexNodeSigns[a][2];
    h(0, a) = xi * eta;
    h(1, a) = eta * zeta;
    h(2, a) = zeta * xi;
    h(3, a) = xi * eta * zeta;
  }
  return h;
}

double QuadArea(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return 0.5 * (c - a).cross(d - b).norm();
}

}  // namespace

Hex8Reference ComputeHex8Reference(const std::array<Vec3, 8>& X) {
  // Shape functions N_a = (1 + xi_a xi)(1 + eta_a eta)(1 + zeta_a zeta) / 8; at the centroid
  // dN_a/dxi = xi_a / 8 and so on.
  Mat83 dn_dxi;
  for (int a = 0; a < 8; ++a) {
    for (int i = 0; i < 3; ++i) dn_dxi(a, i) = kHexNodeSigns[a][i] / 8.0;
  }
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Zero();  // J_ij = dX_i/dxi_j
  for (int a = 0; a < 8; ++a) jacobian += X[a] * dn_dxi.row(a);
  const double det = jacobian.determinant();
  Require(det > 0, "mesh", "an element is inverted or degenerate (det J <= 0)");

  Hex8Reference ref;
  ref.gradients_per_m = dn_dxi * jacobian.inverse();  // b_a = J^-T dN_a/dxi, stored as rows
  ref.volume_m3 = 8.0 * det;
  // gamma_alpha = h_alpha - (h_alpha . X_i) b_i  (Flanagan & Belytschko 1981): orthogonal
  // to every linear field, so rigid motion and homogeneous strain excite no hourglass force.
  const Mat48 h = HourglassBase();
  Mat83 positions;
  for (int a = 0; a < 8; ++a) positions.row(a) = X[a].transpose();
  ref.hourglass_vectors = h - (h * positions) * ref.gradients_per_m.transpose();

  static constexpr int kFaces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                       {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  double largest_face = 0;
  for (const auto& f : kFaces) {
    largest_face = std::max(largest_face, QuadArea(X[f[0]], X[f[1]], X[f[2]], X[f[3]]));
  }
  ref.characteristic_length_m = ref.volume_m3 / largest_face;
  return ref;
}

Eigen::Matrix3d DeformationGradient(const std::array<Vec3, 8>& x, const Mat83& b) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 8; ++a) f += x[a] * b.row(a);
  return f;
}

}  // namespace gonogo::fe
