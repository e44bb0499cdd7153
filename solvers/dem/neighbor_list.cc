#include "solvers/dem/neighbor_list.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "solvers/common/errors.h"

namespace gonogo::dem {
namespace {

// A bin to search from a grain's home bin along one axis, and the image of its grains there.
struct BinReach {
  int index = 0;
  int wrap = 0;
};

}  // namespace

void Box::Validate() const {
  Require(lo_m.allFinite() && hi_m.allFinite(), "box", "corners must be finite");
  Require((hi_m - lo_m).minCoeff() > 0.0, "box", "hi_m must exceed lo_m on every axis");
}

Cell Cell::FromBox(const Box& box) {
  Cell cell;
  cell.origin_m = box.lo_m;
  cell.edges_m = box.LengthM().asDiagonal();
  cell.periodic = box.periodic;
  return cell;
}

Vec3 Cell::FaceSpacingM() const {
  const Eigen::Matrix3d inverse = edges_m.inverse();
  return Vec3(1.0 / inverse.row(0).norm(), 1.0 / inverse.row(1).norm(),
              1.0 / inverse.row(2).norm());
}

void NeighborList::BinParticles(const Particles& particles, const Cell& cell, double cell_size_m) {
  const Vec3 spacing = cell.FaceSpacingM();
  const int n = static_cast<int>(particles.size());
  // A sparse cloud in a large open box would need more cells than grains: coarsen the grid so
  // that there are at most about 8 cells per grain (cells only need to be at least the cutoff).
  const double max_cells = std::max(64.0, 8.0 * n);
  const double fine_cells = (spacing / cell_size_m).array().floor().max(1.0).prod();
  if (fine_cells > max_cells) cell_size_m *= std::cbrt(fine_cells / max_cells);
  int cells = 1;
  for (int d = 0; d < 3; ++d) {
    // Bins are slabs of fractional width 1 / count; each is at least cell_size_m thick in space,
    // so the 27 surrounding bins hold every grain within the cutoff, however the cell is sheared.
    cell_count_[d] = std::max(1, static_cast<int>(std::floor(spacing[d] / cell_size_m)));
    if (cell.periodic[d]) {
      // One bin thick at least: then a grain within reach of another is within reach of one of
      // its images j + w e_d, w in {-1, 0, 1} (|delta s_d| = |n_d . r| / spacing_d < 1).
      Require(spacing[d] >= cell_size_m, "box",
              "a periodic cell must be at least 2 r_max + skin thick on every axis (it was "
              "compressed or stretched too far for its grain count)");
    }
    cells *= cell_count_[d];
  }
  to_fraction_ = cell.edges_m.inverse();
  cell_of_particle_.resize(n);
  cell_start_.assign(cells + 1, 0);
  for (int p = 0; p < n; ++p) {
    const Vec3 fraction = to_fraction_ * (particles.position_m[p] - cell.origin_m);
    int index[3];
    for (int d = 0; d < 3; ++d) {
      const int c = static_cast<int>(std::floor(fraction[d] * cell_count_[d]));
      index[d] = std::clamp(c, 0, cell_count_[d] - 1);  // open axes: outliers in edge cells
    }
    const int bin = (index[2] * cell_count_[1] + index[1]) * cell_count_[0] + index[0];
    cell_of_particle_[p] = bin;
    ++cell_start_[bin + 1];
  }
  for (int c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  // Counting sort keeps particle indices ascending inside a cell.
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  cell_particles_.resize(n);
  for (int p = 0; p < n; ++p) cell_particles_[fill[cell_of_particle_[p]]++] = p;
}

void NeighborList::Build(const Particles& particles, const Cell& cell, double skin_m, int threads) {
  const int n = static_cast<int>(particles.size());
  double max_radius_m = 0.0;
  for (double r : particles.radius_m) max_radius_m = std::max(max_radius_m, r);
  skin_m_ = skin_m;
  max_radius_m_ = max_radius_m;
  BinParticles(particles, cell, 2.0 * max_radius_m + skin_m);
  per_particle_.resize(n);

  // Each particle i lists the j > i within reach from the 27 surrounding bins.
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    std::vector<NeighborPair>& list = per_particle_[i];
    list.clear();
    const int bin = cell_of_particle_[i];
    const int home[3] = {bin % cell_count_[0], (bin / cell_count_[0]) % cell_count_[1],
                         bin / (cell_count_[0] * cell_count_[1])};
    // Per axis, the bins to search and the image of j each one stands for. With 3 bins or more
    // on a periodic axis, the stencil home - 1 .. home + 1 meets each (j, image) once, through
    // the bin that holds j, so the stencil's wrap is the image. A periodic axis 1 or 2 bins thick
    // (a small RVE compressed or stretched) has every bin searched at each of the images -1, 0,
    // +1, which again meets each (j, image) once.
    BinReach reach_along[3][6];
    int reach_count[3] = {0, 0, 0};
    for (int d = 0; d < 3; ++d) {
      if (cell.periodic[d] && cell_count_[d] < 3) {
        for (int wrap = -1; wrap <= 1; ++wrap) {
          for (int b = 0; b < cell_count_[d]; ++b) reach_along[d][reach_count[d]++] = {b, wrap};
        }
        continue;
      }
      for (int offset = -1; offset <= 1; ++offset) {
        int index = home[d] + offset;
        int wrap = 0;
        if (index < 0 || index >= cell_count_[d]) {
          if (!cell.periodic[d]) continue;
          wrap = index < 0 ? -1 : 1;
          index -= wrap * cell_count_[d];
        }
        reach_along[d][reach_count[d]++] = {index, wrap};
      }
    }
    for (int kz = 0; kz < reach_count[2]; ++kz) {
      for (int ky = 0; ky < reach_count[1]; ++ky) {
        for (int kx = 0; kx < reach_count[0]; ++kx) {
          const BinReach& x = reach_along[0][kx];
          const BinReach& y = reach_along[1][ky];
          const BinReach& z = reach_along[2][kz];
          const std::array<int, 3> wrap = {x.wrap, y.wrap, z.wrap};  // j's image: + wrap edges
          const int other = (z.index * cell_count_[1] + y.index) * cell_count_[0] + x.index;
          const Vec3 shift = cell.edges_m * Vec3(wrap[0], wrap[1], wrap[2]);
          for (int k = cell_start_[other]; k < cell_start_[other + 1]; ++k) {
            const int j = cell_particles_[k];
            if (j <= i) continue;
            const Vec3 separation = particles.position_m[j] + shift - particles.position_m[i];
            const double reach = particles.radius_m[i] + particles.radius_m[j] + skin_m;
            if (separation.squaredNorm() >= reach * reach) continue;
            NeighborPair pair;
            pair.i = i;
            pair.j = j;
            pair.image = wrap;
            for (int d = 0; d < 3; ++d) {
              pair.key_shift[d] = wrap[d] + particles.image[i][d] - particles.image[j][d];
            }
            list.push_back(pair);
          }
        }
      }
    }
    std::sort(list.begin(), list.end(), [](const NeighborPair& a, const NeighborPair& b) {
      return std::tie(a.j, a.key_shift) < std::tie(b.j, b.key_shift);
    });
  }

  // Concatenate in particle order, then index the pairs by particle for the force sum.
  pairs_.clear();
  for (int i = 0; i < n; ++i)
    pairs_.insert(pairs_.end(), per_particle_[i].begin(), per_particle_[i].end());
  incident_start_.assign(n + 1, 0);
  for (const NeighborPair& pair : pairs_) {
    ++incident_start_[pair.i + 1];
    ++incident_start_[pair.j + 1];
  }
  for (int p = 0; p < n; ++p) incident_start_[p + 1] += incident_start_[p];
  incident_pairs_.resize(incident_start_[n]);
  incident_is_i_.resize(incident_start_[n]);
  std::vector<std::int64_t> fill(incident_start_.begin(), incident_start_.end() - 1);
  for (int k = 0; k < static_cast<int>(pairs_.size()); ++k) {
    const std::int64_t slot_i = fill[pairs_[k].i]++;
    incident_pairs_[slot_i] = k;
    incident_is_i_[slot_i] = 1;
    const std::int64_t slot_j = fill[pairs_[k].j]++;
    incident_pairs_[slot_j] = k;
    incident_is_i_[slot_j] = 0;
  }
  position_at_build_m_ = particles.position_m;
  cell_at_build_ = cell;
  built_ = true;
}

bool NeighborList::NeedsRebuild(const Particles& particles, const Cell& cell,
                                int threads) const {
  if (!built_ || position_at_build_m_.size() != particles.size()) return true;
  const int n = static_cast<int>(particles.size());
  if (cell.edges_m == cell_at_build_.edges_m && cell.origin_m == cell_at_build_.origin_m) {
    const double limit_sq = 0.25 * skin_m_ * skin_m_;
    int moved = 0;
#pragma omp parallel for schedule(static) reduction(max : moved) num_threads(threads)
    for (int p = 0; p < n; ++p) {
      if ((particles.position_m[p] - position_at_build_m_[p]).squaredNorm() > limit_sq) moved = 1;
    }
    return moved != 0;
  }
  // Deformed cell: a separation r at the build is now (1 + E) r + (u_i - u_j), with E the cell's
  // stretch since the build and u the displacements relative to the affinely deformed cell.
  const Eigen::Matrix3d stretch = cell.edges_m * cell_at_build_.edges_m.inverse();
  const double strain = (stretch - Eigen::Matrix3d::Identity()).norm();
  const double budget_m = skin_m_ - strain * (2.0 * max_radius_m_ + skin_m_);
  if (budget_m <= 0.0) return true;
  const double limit_sq = 0.25 * budget_m * budget_m;
  int moved = 0;
#pragma omp parallel for schedule(static) reduction(max : moved) num_threads(threads)
  for (int p = 0; p < n; ++p) {
    const Vec3 affine_m = cell.origin_m + stretch * (position_at_build_m_[p] - cell_at_build_.origin_m);
    if ((particles.position_m[p] - affine_m).squaredNorm() > limit_sq) moved = 1;
  }
  return moved != 0;
}

}  // namespace gonogo::dem
