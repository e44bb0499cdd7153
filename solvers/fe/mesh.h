// Structured 8-node hexahedral meshes: the soil bin of the wheel rig and the boxes of the tests.
//
// Coordinates: x along the direction of travel, y across it, z up; the undisturbed soil surface is
// z = 0 and the soil occupies z < 0. Node order inside an element follows the usual hexahedron
// convention (Hughes 1987, fig. 3.2.x; VTK_HEXAHEDRON): the bottom face (low z) counter-clockwise
// seen from above, then the top face in the same order. Natural coordinates of node a are
// (xi_a, eta_a, zeta_a) = kHexNodeSigns[a].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace gonogo::fe {

using Vec3 = Eigen::Vector3d;

inline constexpr int kHexNodeSigns[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                            {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

struct HexMesh {
  std::vector<Vec3> reference_positions_m;  // (nodes) X, m
  std::vector<std::array<int, 8>> elements;  // (elements x 8) node indices
  // Structured meshes only: node index of grid point (i, j, k), and the grid's coordinate lines.
  std::vector<double> x_lines_m, y_lines_m, z_lines_m;

  int num_nodes() const { return static_cast<int>(reference_positions_m.size()); }
  int num_elements() const { return static_cast<int>(elements.size()); }
  int GridNode(int i, int j, int k) const;
  // Nodes whose reference position satisfies |coordinate(axis) - value| < tolerance.
  std::vector<int> NodesOnPlane(int axis, double value_m, double tolerance_m = 1e-9) const;
};

// A box [x0, x1] x [y0, y1] x [z0, z1] meshed on the given coordinate lines (each strictly
// increasing, at least two values).
HexMesh MeshBox(std::vector<double> x_lines_m, std::vector<double> y_lines_m,
                std::vector<double> z_lines_m);

// Coordinate lines from `start_m` to `end_m`: spacing `fine_size_m` while within `fine_extent_m`
// of the start, then growing by `growth_ratio` per element up to `max_size_m`. The last spacing is
// stretched or merged so the line ends exactly at `end_m`.
std::vector<double> GradedLines(double start_m, double end_m, double fine_size_m,
                                double fine_extent_m, double growth_ratio, double max_size_m);

// Lines -l_n .. -l_1, l_0 = 0, l_1 .. l_n from half-axis lines 0 = l_0 < l_1 < ... < l_n.
std::vector<double> MirroredLines(const std::vector<double>& half_lines_m);
// Vertical lines from -depth_m up to the surface z = 0, graded like GradedLines downwards.
std::vector<double> DepthLines(double depth_m, double fine_size_m, double fine_depth_m,
                               double growth_ratio, double max_size_m);

// A soil bin for a wheel running along +x on the centre line y = 0. With `half_symmetric` only
// y >= 0 is meshed and y = 0 is a symmetry plane (rollers in y), which halves the cost of a wheel
// centred on the line.
struct SoilBinSpec {
  double length_m = 0;             // along x, from x = 0
  double width_m = 0;              // full width across y
  double depth_m = 0;              // soil depth below z = 0
  double element_size_m = 0;       // spacing along x, across the wheel path and near the surface
  double path_half_width_m = 0;    // |y| within which the spacing stays at element_size_m
  double fine_depth_m = 0;         // depth within which the spacing stays at element_size_m
  double growth_ratio = 1.3;       // grading away from the path and with depth
  double max_element_size_m = 0;   // 0: 4 x element_size_m
  bool half_symmetric = true;

  void Validate(const std::string& field_prefix) const;
};

HexMesh MeshSoilBin(const SoilBinSpec& spec);

}  // namespace gonogo::fe
