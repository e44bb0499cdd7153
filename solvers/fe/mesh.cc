#include "solvers/fe/mesh.h"

#include <algorithm>
#include <cmath>

#include "solvers/common/errors.h"

namespace gonogo::fe {

int HexMesh::GridNode(int i, int j, int k) const {
  const int nx = static_cast<int>(x_lines_m.size());
  const int ny = static_cast<int>(y_lines_m.size());
  return i + nx * (j + ny * k);
}

std::vector<int> HexMesh::NodesOnPlane(int axis, double value_m, double tolerance_m) const {
  std::vector<int> nodes;
  for (int n = 0; n < num_nodes(); ++n) {
    if (std::abs(reference_positions_m[n][axis] - value_m) < tolerance_m) nodes.push_back(n);
  }
  return nodes;
}

HexMesh MeshBox(std::vector<double> x_lines_m, std::vector<double> y_lines_m,
                std::vector<double> z_lines_m) {
  for (const auto* lines : {&x_lines_m, &y_lines_m, &z_lines_m}) {
    Require(lines->size() >= 2, "mesh", "every axis needs at least two coordinate lines");
    for (size_t i = 1; i < lines->size(); ++i) {
      Require((*lines)[i] > (*lines)[i - 1], "mesh", "coordinate lines must increase strictly");
    }
  }
  HexMesh mesh;
  mesh.x_lines_m = std::move(x_lines_m);
  mesh.y_lines_m = std::move(y_lines_m);
  mesh.z_lines_m = std::move(z_lines_m);
  const int nx = static_cast<int>(mesh.x_lines_m.size());
  const int ny = static_cast<int>(mesh.y_lines_m.size());
  const int nz = static_cast<int>(mesh.z_lines_m.size());
  mesh.reference_positions_m.reserve(static_cast<size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        mesh.reference_positions_m.emplace_back(mesh.x_lines_m[i], mesh.y_lines_m[j],
                                                mesh.z_lines_m[k]);
      }
    }
  }
  mesh.elements.reserve(static_cast<size_t>(nx - 1) * (ny - 1) * (nz - 1));
  for (int k = 0; k + 1 < nz; ++k) {
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        std::array<int, 8> element{};
        for (int a = 0; a < 8; ++a) {
          element[a] = mesh.GridNode(i + (kHexNodeSigns[a][0] > 0), j + (kHexNodeSigns[a][1] > 0),
                                     k + (kHexNodeSigns[a][2] > 0));
        }
        mesh.elements.push_back(element);
      }
    }
  }
  return mesh;
}

std::vector<double> GradedLines(double start_m, double end_m, double fine_size_m,
                                double fine_extent_m, double growth_ratio, double max_size_m) {
  Require(end_m > start_m, "mesh", "a graded axis must have positive length");
  Require(fine_size_m > 0, "mesh.element_size_m", "must be positive");
  Require(growth_ratio >= 1, "mesh.growth_ratio", "must be at least 1");
  std::vector<double> lines{start_m};
  double size = fine_size_m;
  while (lines.back() < end_m - 1e-12) {
    const double here = lines.back() - start_m;
    if (here >= fine_extent_m - 1e-12) size = std::min(size * growth_ratio, max_size_m);
    size = std::max(size, fine_size_m);
    lines.push_back(std::min(lines.back() + size, end_m));
  }
  // A sliver at the end (under half the spacing before it) is merged into its neighbour.
  if (lines.size() > 2) {
    const size_t n = lines.size();
    if (lines[n - 1] - lines[n - 2] < 0.5 * (lines[n - 2] - lines[n - 3])) {
      lines.erase(lines.end() - 2);
    }
  }
  lines.back() = end_m;
  return lines;
}

std::vector<double> MirroredLines(const std::vector<double>& half_lines_m) {
  std::vector<double> lines;
  for (size_t k = half_lines_m.size() - 1; k > 0; --k) lines.push_back(-half_lines_m[k]);
  lines.insert(lines.end(), half_lines_m.begin(), half_lines_m.end());
  return lines;
}

std::vector<double> DepthLines(double depth_m, double fine_size_m, double fine_depth_m,
                               double growth_ratio, double max_size_m) {
  const std::vector<double> depth =
      GradedLines(0, depth_m, fine_size_m, fine_depth_m, growth_ratio, max_size_m);
  std::vector<double> lines;
  for (auto it = depth.rbegin(); it != depth.rend(); ++it) lines.push_back(-*it);
  lines.back() = 0.0;
  return lines;
}

void SoilBinSpec::Validate(const std::string& p) const {
  Require(length_m > 0, p + "length_m", "must be positive");
  Require(width_m > 0, p + "width_m", "must be positive");
  Require(depth_m > 0, p + "depth_m", "must be positive");
  Require(element_size_m > 0, p + "element_size_m", "must be positive");
  Require(element_size_m <= std::min({length_m, 0.5 * width_m, depth_m}),
          p + "element_size_m", "must not exceed the bin's length, half width or depth");
  Require(path_half_width_m >= 0 && path_half_width_m <= 0.5 * width_m, p + "path_half_width_m",
          "must lie within the half width");
  Require(fine_depth_m >= 0 && fine_depth_m <= depth_m, p + "fine_depth_m",
          "must lie within the depth");
  Require(growth_ratio >= 1 && growth_ratio <= 2, p + "growth_ratio", "must lie in [1, 2]");
  Require(max_element_size_m >= 0, p + "max_element_size_m", "must not be negative");
}

HexMesh MeshSoilBin(const SoilBinSpec& spec) {
  spec.Validate("soil_bin.");
  const double max_size =
      spec.max_element_size_m > 0 ? spec.max_element_size_m : 4 * spec.element_size_m;
  // x: uniform along the whole run of the wheel.
  const int nx = std::max(1, static_cast<int>(std::lround(spec.length_m / spec.element_size_m)));
  std::vector<double> x_lines(nx + 1);
  for (int i = 0; i <= nx; ++i) x_lines[i] = spec.length_m * i / nx;
  // y: fine across the path, graded to the side wall; mirrored when the full width is meshed.
  std::vector<double> y_half = GradedLines(0, 0.5 * spec.width_m, spec.element_size_m,
                                           spec.path_half_width_m, spec.growth_ratio, max_size);
  std::vector<double> y_lines = spec.half_symmetric ? y_half : MirroredLines(y_half);
  // z: fine below the surface, graded towards the floor.
  std::vector<double> z_lines = DepthLines(spec.depth_m, spec.element_size_m, spec.fine_depth_m,
                                           spec.growth_ratio, max_size);
  return MeshBox(std::move(x_lines), std::move(y_lines), std::move(z_lines));
}

}  // namespace gonogo::fe
