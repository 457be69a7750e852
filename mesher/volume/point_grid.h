// kdmesh — "is a point within r of p": a hash grid over a fixed point set, built on all cores,
// and the points added to it one at a time (the boundary recovery's Steiner points).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

/// Cells of side `cell` from `origin`. The fixed points are a PointSet (with the ids to leave
/// out); they are bucketed by a hash of their cell in one counting sort on all cores: flat
/// arrays, about 4 points per bucket, no allocation per cell. The recovery builds one grid per
/// round over every node to place a few Steiner points (the paper gear box: 4.2M nodes for 32
/// points), where a hash map of per-cell vectors took 5.6 s on one core, and freeing it most
/// likely 2 s more (perf samples of glibc's free lists right after it). Points added later go
/// to a small map of cells. The answers are exact and do not depend on the buckets: a hash
/// collision only adds candidates, distances decide. `points` must outlive the grid and stay
/// unchanged.
class PointGrid {
 public:
  /// `skip` is empty or has one entry per point; points whose entry is not 0 are left out.
  PointGrid(double cell, const double* origin, const PointSet& points, const std::vector<std::uint8_t>& skip);

  /// Adds p (copied).
  void add(const double* p);
  /// True when a fixed or added point q has |p - q|^2 < r^2.
  bool any_within(const double* p, double r) const;

 private:
  using Cell = std::array<std::int64_t, 3>;
  Cell cell_of(const double* p) const;
  static std::uint64_t hash(const Cell& c);
  static bool near(const double* p, const double* q, double r2) {
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]) < r2;
  }

  double cell_;
  double origin_[3];
  const PointSet* points_;
  std::uint64_t mask_ = 0;                 // buckets - 1 (a power of two)
  std::vector<std::uint32_t> start_;       // bucket b's ids: ids_[start_[b] .. start_[b+1])
  std::vector<std::uint32_t> ids_;         // the fixed points kept, by bucket, ascending in each
  std::vector<double> added_;              // 3 per added point
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> added_cells_;
};

}  // namespace kdmesh
