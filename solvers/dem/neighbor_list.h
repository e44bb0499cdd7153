// Linked-cell neighbour search with a Verlet skin in a periodic cell (orthogonal, or any
// parallelepiped once deformed), periodic per axis. Grains are binned in fractional coordinates,
// so a sheared cell is searched like a cubic one. Pairs are listed once (i < j) in a fixed order,
// so per-pair work followed by a per-particle sum in pair order gives results that do not depend
// on the thread count.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "solvers/dem/particles.h"

namespace gonogo::dem {

// Orthogonal box [lo, hi]; an axis is either periodic or bounded by walls (or open).
struct Box {
  Vec3 lo_m = Vec3::Zero();
  Vec3 hi_m = Vec3::Ones();
  std::array<bool, 3> periodic = {true, true, true};

  void Validate() const;
  Vec3 LengthM() const { return hi_m - lo_m; }
};

// The current cell: a corner and three edge vectors (the columns of edges_m). It starts as the
// Box; a deforming simulation updates edges_m (seed 000: X_{n+1} = X_n + dX_n). A point x has
// fractional coordinates s = edges_m^-1 (x - origin_m); a periodic axis k wraps s_k into [0, 1).
struct Cell {
  Vec3 origin_m = Vec3::Zero();
  Eigen::Matrix3d edges_m = Eigen::Matrix3d::Identity();
  std::array<bool, 3> periodic = {true, true, true};

  static Cell FromBox(const Box& box);
  double VolumeM3() const { return edges_m.determinant(); }
  // Distance between the two faces crossed by axis k: V / |e_i x e_j| = 1 / |row k of edges^-1|.
  Vec3 FaceSpacingM() const;
};

// One candidate pair: x_j + edges_m * image is the image of j nearest to i at the last build
// (in the current cell, so the pair follows the cell as it deforms).
struct NeighborPair {
  int i = 0;
  int j = 0;
  std::array<int, 3> image = {0, 0, 0};
  // Image offset in unwrapped coordinates (image + image_i - image_j, in cell edges); with (i, j)
  // it names the physical contact across wraps, so history survives rebuilds.
  std::array<int, 3> key_shift = {0, 0, 0};

  Vec3 ShiftM(const Eigen::Matrix3d& edges_m) const {
    return edges_m * Vec3(image[0], image[1], image[2]);
  }
};

class NeighborList {
 public:
  // Lists all pairs closer than r_i + r_j + skin_m. Positions must already be wrapped.
  void Build(const Particles& particles, const Cell& cell, double skin_m, int threads);

  // True when a pair not listed could now be in contact (or no Build was done). In a fixed cell:
  // some grain moved more than skin / 2. In a deforming one, with d the largest displacement
  // relative to the cell and e = |edges edges_build^-1 - I| (Frobenius, bounds the stretch of any
  // separation): 2 d + e (2 r_max + skin) >= skin.
  bool NeedsRebuild(const Particles& particles, const Cell& cell, int threads) const;

  double skin_m() const { return skin_m_; }
  bool built() const { return built_; }
  // What the last Build saw; building again from these gives the same list.
  const std::vector<Vec3>& position_at_build_m() const { return position_at_build_m_; }
  const Cell& cell_at_build() const { return cell_at_build_; }

  const std::vector<NeighborPair>& pairs() const { return pairs_; }
  // Pairs touching particle p: incident_[incident_start_[p] .. incident_start_[p + 1]), each a
  // pair index, in ascending order; the sign says whether p is the pair's i (+) or j (-).
  const std::vector<std::int64_t>& incident_start() const { return incident_start_; }
  const std::vector<int>& incident_pairs() const { return incident_pairs_; }
  const std::vector<std::int8_t>& incident_is_i() const { return incident_is_i_; }

 private:
  void BinParticles(const Particles& particles, const Cell& cell, double cell_size_m);

  double skin_m_ = 0.0;
  double max_radius_m_ = 0.0;
  bool built_ = false;
  Cell cell_at_build_;
  std::vector<Vec3> position_at_build_m_;
  std::array<int, 3> cell_count_ = {1, 1, 1};
  Eigen::Matrix3d to_fraction_ = Eigen::Matrix3d::Identity();  // edges_m^-1 at the build
  std::vector<int> cell_of_particle_;
  std::vector<int> cell_start_;      // (cells + 1)
  std::vector<int> cell_particles_;  // particle indices, ascending within a cell
  std::vector<std::vector<NeighborPair>> per_particle_;
  std::vector<NeighborPair> pairs_;
  std::vector<std::int64_t> incident_start_;
  std::vector<int> incident_pairs_;
  std::vector<std::int8_t> incident_is_i_;
};

}  // namespace gonogo::dem
