// kdmesh — edge length / target size statistics of a tet mesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/quality/size_fidelity.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "core/error.h"
#include "mesher/bucket_scatter.h"
#include "mesher/distinct_sorter.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"

namespace kdmesh {

SizeFidelity measure_size_fidelity(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                   const SizingField& sizing) {
  if (tets.size() % 4 != 0)
    throw UsageError("size fidelity: tet array length " + std::to_string(tets.size()) +
                     " is not a multiple of 4");
  const std::size_t np = points.size(), nt = tets.size() / 4;
  for (std::size_t k = 0; k < tets.size(); ++k)
    if (tets[k] >= np)
      throw UsageError("size fidelity: tet " + std::to_string(k / 4) + " refers to point " +
                       std::to_string(tets[k]) + " of " + std::to_string(np));
  // The unique edges (a < b), grouped by a: a counting sort on a, then each group sorted.
  // The order is (a, b) ascending, as a sort of all the edges would give.
  static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  auto ends = [&](std::size_t k) {  // edge k % 6 of tet k / 6, as (a, b), a < b
    const std::uint32_t p = tets[4 * (k / 6) + kEdge[k % 6][0]], q = tets[4 * (k / 6) + kEdge[k % 6][1]];
    return std::pair{std::min(p, q), std::max(p, q)};
  };
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> other(6 * nt);  // written by the scatter
  const std::vector<std::size_t> start = bucket_scatter(
      6 * nt, np, [&](std::size_t k) { return ends(k).first; },
      [&](std::size_t k, std::size_t at) { other[at] = ends(k).second; });
  // Each vertex's group sorted and made unique in place. uoff[v]: the rank of v's first unique
  // edge in the order (a, b) ascending; v's unique edges are other[start[v] ..) up to the next.
  std::vector<std::size_t> uoff(np + 1, 0);
  parallel_for(np, [&](std::size_t b, std::size_t e, unsigned) {
    DistinctSorter distinct;
    for (std::size_t v = b; v < e; ++v) uoff[v + 1] = distinct(other.data() + start[v], start[v + 1] - start[v]);
  }, 1024);
  for (std::size_t v = 0; v < np; ++v) uoff[v + 1] += uoff[v];
  const std::size_t ne = uoff[np];
  SizeFidelity r;
  r.edges = ne;
  if (ne == 0) return r;
  const double far = sizing.max_size();
  // Each vertex's reach: half its longest edge, so that the midpoints of its edges are within
  // it. An edge raises both ends' reach (a max: the same result on any number of threads). The
  // reach only bounds the ball of `clear` below, which has a margin, so it is not the figures'
  // hypot to the last bit.
  std::vector<double> reach(np, 0.0);
  auto raise = [&](std::uint32_t v, double x) {
    std::atomic_ref<double> at(reach[v]);
    double now = at.load(std::memory_order_relaxed);
    while (x > now && !at.compare_exchange_weak(now, x, std::memory_order_relaxed)) {
    }
  };
  parallel_for(np, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t v = b; v < e; ++v) {
      const double* a = points.p(std::uint32_t(v));
      double own = 0;
      for (std::size_t k = start[v]; k < start[v] + (uoff[v + 1] - uoff[v]); ++k) {
        const double* c = points.p(other[k]);
        const double d[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double half = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / 2;
        own = std::max(own, half);
        raise(other[k], half);
      }
      raise(std::uint32_t(v), own);
    }
  }, 1024);
  // The field is exactly h_max where nothing refines it (a min over terms that are all >= it).
  // `clear`: h_max over the whole ball of the vertex's reach (a lower bound of the field there,
  // taken over a ball a little larger than the reach so that the bound's rounding cannot matter),
  // so at the midpoint of each of its edges: most edges of a mesh at one size (1.3M edges
  // evaluated on pinion.ply, 98% of them h_max, where 200k vertex bounds decide most of them).
  // (Blocks taken by free workers, here and for the edges below: the field's cost follows the
  // zones, so halves of the ids differ in cost; split in two, the paper gear box's quality
  // stage ended on one core for 0.45 s.)
  std::vector<std::uint8_t> unrefined(np), clear(np);
  parallel_blocks(np, 4096, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t v = b; v < e; ++v) {
      const double* x = points.p(std::uint32_t(v));
      const double margin = 1e-6 * reach[v] + 1e-12 * (std::fabs(x[0]) + std::fabs(x[1]) + std::fabs(x[2]));
      const double hx = sizing(x);
      clear[v] = !(sizing.lower_bound(x, reach[v] + margin, hx) < far);
      unrefined[v] = clear[v] || !(hx < far);
    }
  });
  // Fixed blocks of edges, summed in order: the same figures on any number of threads.
  struct Part {
    double sum = 0, away_sum = 0, min_ratio = INFINITY, max_ratio = 0;
    std::size_t in = 0, lo = 0, hi = 0, away = 0;
  };
  constexpr std::size_t kBlock = 1 << 16;
  std::vector<Part> part((ne + kBlock - 1) / kBlock);
  parallel_blocks(part.size(), 1, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      Part p;
      // Edge i is v's (i - uoff[v])-th, v the vertex whose range holds i.
      const std::size_t i0 = k * kBlock, i1 = std::min(ne, (k + 1) * kBlock);
      std::size_t v = std::size_t(std::upper_bound(uoff.begin(), uoff.end(), i0) - uoff.begin()) - 1;
      for (std::size_t i = i0; i < i1; ++i) {
        while (i >= uoff[v + 1]) ++v;
        const std::uint32_t w = other[start[v] + (i - uoff[v])];
        const double* a = points.p(std::uint32_t(v));
        const double* c = points.p(w);
        const double m[3] = {(a[0] + c[0]) / 2, (a[1] + c[1]) / 2, (a[2] + c[2]) / 2};
        const double length = std::hypot(c[0] - a[0], c[1] - a[1], c[2] - a[2]);
        const double hm = clear[v] || clear[w] ? far : sizing(m);
        const double ratio = length / hm;
        p.sum += ratio;
        if (!(hm < far) && unrefined[v] && unrefined[w]) {
          ++p.away;
          p.away_sum += length / far;
        }
        if (ratio < 0.7) ++p.lo;
        else if (ratio > 1.4) ++p.hi;
        else ++p.in;
        p.min_ratio = std::min(p.min_ratio, ratio);
        p.max_ratio = std::max(p.max_ratio, ratio);
      }
      part[k] = p;
    }
  });
  double sum = 0, away_sum = 0;
  std::size_t in = 0, lo = 0, hi = 0;
  r.min_ratio = INFINITY;
  r.max_ratio = 0;
  for (const Part& p : part) {
    sum += p.sum;
    away_sum += p.away_sum;
    in += p.in, lo += p.lo, hi += p.hi, r.away_edges += p.away;
    r.min_ratio = std::min(r.min_ratio, p.min_ratio);
    r.max_ratio = std::max(r.max_ratio, p.max_ratio);
  }
  const double n = double(ne);
  r.mean_ratio = sum / n;
  r.in_range = double(in) / n;
  r.short_fraction = double(lo) / n;
  r.long_fraction = double(hi) / n;
  r.away_mean_ratio = r.away_edges ? away_sum / double(r.away_edges) : 0;
  return r;
}

}  // namespace kdmesh
