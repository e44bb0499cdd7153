// Linked-cell neighbour search with a Verlet skin in an orthogonal box, periodic per axis
// (minimum image). Pairs are listed once (i < j) in a fixed order, so per-pair work followed by
// a per-particle sum in pair order gives results that do not depend on the thread count.
#pragma once

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

// One candidate pair: x_j + shift_m is the image of j nearest to i at the last build.
struct NeighborPair {
  int i = 0;
  int j = 0;
  Vec3 shift_m = Vec3::Zero();
  // Image offset in unwrapped coordinates (shift + image_i - image_j, in box lengths); with (i, j)
  // it names the physical contact across wraps, so history survives rebuilds.
  std::array<int, 3> key_shift = {0, 0, 0};
};

class NeighborList {
 public:
  // Lists all pairs closer than r_i + r_j + skin_m. Positions must already be wrapped.
  void Build(const Particles& particles, const Box& box, double skin_m, int threads);

  // True when some particle moved more than skin / 2 since the last Build (or none was done).
  bool NeedsRebuild(const Particles& particles, int threads) const;

  const std::vector<NeighborPair>& pairs() const { return pairs_; }
  // Pairs touching particle p: incident_[incident_start_[p] .. incident_start_[p + 1]), each a
  // pair index, in ascending order; the sign says whether p is the pair's i (+) or j (-).
  const std::vector<std::int64_t>& incident_start() const { return incident_start_; }
  const std::vector<int>& incident_pairs() const { return incident_pairs_; }
  const std::vector<std::int8_t>& incident_is_i() const { return incident_is_i_; }

 private:
  void BinParticles(const Particles& particles, const Box& box, double cell_size_m);

  double skin_m_ = 0.0;
  bool built_ = false;
  std::vector<Vec3> position_at_build_m_;
  std::array<int, 3> cell_count_ = {1, 1, 1};
  Vec3 cell_size_m_ = Vec3::Ones();
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
