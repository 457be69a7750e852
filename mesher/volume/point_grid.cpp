// kdmesh — hash grid for "is a point within r of p" (mesher/volume/point_grid.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/point_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel_for.h"
#include "mesher/bucket_scatter.h"

namespace kdmesh {

PointGrid::PointGrid(double cell, const double* origin, const PointSet& points,
                     const std::vector<std::uint8_t>& skip)
    : cell_(cell), points_(&points) {
  for (int k = 0; k < 3; ++k) origin_[k] = origin[k];
  const std::size_t n = points.size();
  if (n >= (std::size_t(1) << 32)) throw UsageError("PointGrid: 2^32 points or more");
  if (!skip.empty() && skip.size() != n)
    throw UsageError("PointGrid: " + std::to_string(skip.size()) + " skip flags for " + std::to_string(n) + " points");
  std::vector<std::uint32_t> kept;
  kept.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (skip.empty() || !skip[i]) kept.push_back(std::uint32_t(i));
  // About 4 points per bucket: 4 bytes of start per bucket, and a handful of distance tests
  // per cell asked.
  const std::size_t buckets = std::bit_ceil(std::max<std::size_t>(1, kept.size() / 4));
  mask_ = buckets - 1;
  std::vector<std::uint32_t> bucket(kept.size());
  parallel_for(kept.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) bucket[i] = std::uint32_t(hash(cell_of(points.p(kept[i]))) & mask_);
  }, 65536);
  ids_.resize(kept.size());
  const std::vector<std::size_t> start = bucket_scatter(
      kept.size(), buckets, [&](std::size_t i) { return bucket[i]; },
      [&](std::size_t i, std::size_t at) { ids_[at] = kept[i]; });
  start_.assign(start.begin(), start.end());
}

PointGrid::Cell PointGrid::cell_of(const double* p) const {
  Cell c{};
  for (int k = 0; k < 3; ++k) c[k] = std::int64_t(std::floor((p[k] - origin_[k]) / cell_));
  return c;
}

std::uint64_t PointGrid::hash(const Cell& c) {
  std::uint64_t h = 0x9E3779B97F4A7C15ULL;
  for (std::int64_t x : c) h = (h ^ std::uint64_t(x)) * 0xFF51AFD7ED558CCDULL + 0x632BE59BD9B4E5F5ULL;
  return h ^ (h >> 29);  // the bucket takes the low bits
}

void PointGrid::add(const double* p) {
  added_.insert(added_.end(), p, p + 3);
  added_cells_[hash(cell_of(p))].push_back(std::uint32_t(added_.size() / 3 - 1));
}

bool PointGrid::any_within(const double* p, double r) const {
  const double r2 = r * r;
  const Cell c = cell_of(p);
  const double span = std::ceil(r / cell_);
  const double cells = double(ids_.size() + added_.size() / 3);  // at least the cells holding points
  if (span > 8 && (2 * span + 1) * (2 * span + 1) * (2 * span + 1) > cells) {
    // Fewer points than cells to visit: test them all.
    for (std::uint32_t i : ids_)
      if (near(p, points_->p(i), r2)) return true;
    for (std::size_t i = 0; i < added_.size(); i += 3)
      if (near(p, &added_[i], r2)) return true;
    return false;
  }
  const int k = std::max(1, int(span));
  for (int dx = -k; dx <= k; ++dx)
    for (int dy = -k; dy <= k; ++dy)
      for (int dz = -k; dz <= k; ++dz) {
        const std::uint64_t h = hash({c[0] + dx, c[1] + dy, c[2] + dz});
        const std::uint64_t b = h & mask_;
        for (std::uint32_t j = start_[b]; j < start_[b + 1]; ++j)
          if (near(p, points_->p(ids_[j]), r2)) return true;
        if (added_cells_.empty()) continue;
        const auto it = added_cells_.find(h);
        if (it == added_cells_.end()) continue;
        for (std::uint32_t i : it->second)
          if (near(p, &added_[3 * std::size_t(i)], r2)) return true;
      }
  return false;
}

}  // namespace kdmesh
