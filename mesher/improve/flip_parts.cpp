// kdmesh — the parts of the flip stage's parallel phase (mesher/improve/flip_parts.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/flip_parts.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>

#include "core/error.h"
#include "core/parallel_for.h"

namespace kdmesh {

namespace {

/// The cuts of a complete binary tree over the points: node i (children 2i+1, 2i+2) sends a
/// point with coordinate `axis` below `at` left, else right.
using Point = std::array<double, 3>;

struct Cut {
  int axis = 0;
  double at = 0;
};

/// Where to cut the points [b, e) (their box lo..hi): across the axis and at the boundary of
/// bins of one width (1/64 of the box's longest side) that leave 35-65 % of the points on each
/// side with the fewest points in the two bins beside it (ties: the nearest the middle, then the
/// lower axis). The tets at a cut are left to the serial phase: a median cut across the widest
/// extent falls where the mesh is densest when that is its middle (the gear box's refined
/// cross-section x = 0: 29 % of the tets below the threshold left with one cut there).
Cut sparse_cut(const Point* b, const Point* e, const double* lo, const double* hi) {
  constexpr int kBins = 64;
  const double width = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) / kBins;
  const double n = double(e - b);
  Cut best;
  std::size_t best_cost = 0;
  double best_off = 0;
  bool found = false;
  for (int a = 0; a < 3 && width > 0; ++a) {
    const int bins = std::max(1, std::min(kBins, int(std::ceil((hi[a] - lo[a]) / width))));
    std::size_t count[kBins] = {};
    for (const Point* v = b; v != e; ++v) ++count[std::min(bins - 1, std::max(0, int(((*v)[a] - lo[a]) / width)))];
    std::size_t below = 0;
    for (int k = 1; k < bins; ++k) {
      below += count[k - 1];
      if (double(below) < 0.35 * n || double(below) > 0.65 * n) continue;
      const std::size_t cost = count[k - 1] + count[k];
      const double off = std::abs(double(below) - n / 2);
      if (!found || cost < best_cost || (cost == best_cost && off < best_off)) {
        found = true;
        best = {a, lo[a] + width * k};
        best_cost = cost;
        best_off = off;
      }
    }
  }
  if (found) return best;
  // No such boundary (the points bunched in a few bins): the median across the widest extent.
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[best.axis] - lo[best.axis]) best.axis = a;
  std::vector<double> x;
  for (const Point* v = b; v != e; ++v) x.push_back((*v)[best.axis]);
  std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(x.size() / 2), x.end());
  best.at = x[x.size() / 2];
  return best;
}

void split(Point* b, Point* e, std::size_t node, unsigned depth, std::vector<Cut>& cuts) {
  if (depth == 0) return;
  Cut& cut = cuts[node];
  if (e - b >= 2) {
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = (*b)[k];
    for (const Point* v = b; v != e; ++v)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], (*v)[k]);
        hi[k] = std::max(hi[k], (*v)[k]);
      }
    cut = sparse_cut(b, e, lo, hi);
  } else if (e - b == 1) {
    cut.at = (*b)[0];
  }
  // The halves as the rule sends them (ties at the cut go right).
  Point* mid = std::partition(b, e, [&](const Point& x) { return x[cut.axis] < cut.at; });
  split(b, mid, 2 * node + 1, depth - 1, cuts);
  split(mid, e, 2 * node + 2, depth - 1, cuts);
}

}  // namespace

FlipParts flip_parts(const ImproveTets& m, const std::vector<std::uint32_t>& seeds, unsigned levels,
                     unsigned threads) {
  if (levels > 7) throw UsageError("flip_parts: at most 7 levels (128 parts)");
  FlipParts parts;
  parts.count = 1u << levels;
  std::vector<Point> pts(seeds.size());  // (copied once: the cuts read them levels x 4 times)
  parallel_for(seeds.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) std::copy_n(m.p(m.v(seeds[k])[0]), 3, pts[k].begin());
  }, 1 << 16, threads);
  std::vector<Cut> cuts(parts.count);  // parts.count - 1 inner nodes
  split(pts.data(), pts.data() + pts.size(), 0, levels, cuts);
  const std::size_t np = m.nodes().size_count();
  std::vector<std::uint8_t> owner(np);
  parallel_for(np, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t v = b; v < e; ++v) {
      const double* x = m.p(std::uint32_t(v));
      std::size_t node = 0;
      for (unsigned l = 0; l < levels; ++l) node = 2 * node + 1 + (x[cuts[node].axis] < cuts[node].at ? 0 : 1);
      owner[v] = std::uint8_t(node - (parts.count - 1));
    }
  }, 1 << 16, threads);
  parts.deep = owner;
  const std::size_t cap = m.capacity();
  parallel_for(cap, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      if (!m.alive(std::uint32_t(t))) continue;
      const std::uint32_t* v = m.v(std::uint32_t(t));
      const std::uint8_t o = owner[v[0]];
      if (owner[v[1]] == o && owner[v[2]] == o && owner[v[3]] == o) continue;
      for (int i = 0; i < 4; ++i)  // (other threads may write the same value)
        std::atomic_ref<std::uint8_t>(parts.deep[v[i]]).store(kNoPart, std::memory_order_relaxed);
    }
  }, 1 << 16, threads);
  return parts;
}

}  // namespace kdmesh
