// kdmesh — the side of the surface of every tet's centroid, carried along clear segments.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/quality/centroid_sides.h"

#include <atomic>
#include <utility>

#include "core/parallel_collect.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"

namespace kdmesh {

namespace {

/// Both overloads: `clear(a, b, pair)` may carry an answer along the pair's centroid segment,
/// `answer(c, t)` is tet t's answer at its centroid c.
template <class Clear, class Answer>
std::vector<std::int8_t> carried(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                 std::span<const TetPair> neighbours,
                                 const Clear& clear_of, const Answer& answer) {
  const std::size_t nt = tets.size() / 4;
  // Unwritten until the parallel loops below fill them: zeroing them first was a serial
  // memset of 24 bytes per tet (the gear box's 23.6M tets: 1.1 s on one core, its pages
  // faulted there too).
  std::vector<double, UninitAllocator<double>> cen(3 * nt);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      for (int k = 0; k < 3; ++k)
        cen[3 * t + k] = (points.p(tets[4 * t])[k] + points.p(tets[4 * t + 1])[k] + points.p(tets[4 * t + 2])[k] +
                          points.p(tets[4 * t + 3])[k]) / 4;
  });
  std::vector<std::uint8_t, UninitAllocator<std::uint8_t>> clear(neighbours.size());
  // In blocks taken by free workers: segments near the surface cost most, and the pairs come
  // in tet order, so one chunk per worker left a core idle for 0.5 s of the paper gear box's.
  parallel_blocks(neighbours.size(), 16384, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i)
      clear[i] = clear_of(&cen[3 * neighbours[i].first], &cen[3 * neighbours[i].second], neighbours[i]);
  });
  // Union-find over the clear pairs, on all cores; each root is its set's lowest tet. A root
  // is linked only under a lower one, by compare-and-swap on its own entry (which fails if
  // another thread linked it first: the union is then tried again from the new roots), so a
  // set's root is its lowest tet whatever the order of the unions: the same sets and roots
  // on any thread count. Entries only ever move towards their root.
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> up(nt);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) up[t] = std::uint32_t(t);
  });
  auto entry = [&up](std::uint32_t t) { return std::atomic_ref<std::uint32_t>(up[t]); };
  auto root = [&](std::uint32_t t) {
    for (;;) {
      const std::uint32_t p = entry(t).load(std::memory_order_relaxed);
      if (p == t) return t;
      const std::uint32_t g = entry(p).load(std::memory_order_relaxed);
      if (g != p) {  // path halving: t skips to its grandparent
        std::uint32_t expect = p;
        entry(t).compare_exchange_weak(expect, g, std::memory_order_relaxed);
      }
      t = g;
    }
  };
  parallel_for(neighbours.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) {
      if (!clear[i]) continue;
      std::uint32_t x = neighbours[i].first, y = neighbours[i].second;
      for (;;) {
        x = root(x);
        y = root(y);
        if (x == y) break;
        if (x > y) std::swap(x, y);
        std::uint32_t expect = y;  // link y (still a root?) under x
        if (entry(y).compare_exchange_strong(expect, x, std::memory_order_relaxed)) break;
      }
    }
  }, 4096);
  std::vector<std::int8_t> side(nt, 0);
  const std::vector<std::uint32_t> roots =
      parallel_collect(nt, [&up](std::size_t t) { return up[t] == t; }, 65536);
  parallel_for(roots.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) side[roots[i]] = answer(&cen[3 * roots[i]], roots[i]);
  }, 64);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)  // (a root's entry is another thread's to read)
      if (const std::uint32_t r = root(std::uint32_t(t)); r != t) side[t] = side[r];
  }, 4096);
  return side;
}

}  // namespace

std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        std::span<const TetPair> neighbours,
                                        const SurfaceQuery& query) {
  return carried(
      points, tets, neighbours,
      [&](const double* a, const double* b, const TetPair&) {
        return query.segment_clear(a, b);
      },
      [&](const double* c, std::uint32_t) { return std::int8_t(query.side(c)); });
}

std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        std::span<const TetPair> neighbours,
                                        const SurfaceQuery& query, const RegionQuery& regions,
                                        const std::vector<std::uint32_t>& tet_region) {
  return carried(
      points, tets, neighbours,
      [&](const double* a, const double* b, const TetPair& n) {
        // A body's surface lies in the outer surface and the interfaces.
        return tet_region[n.first] == tet_region[n.second] && query.segment_clear(a, b) &&
               regions.interfaces().segment_clear(a, b);
      },
      [&](const double* c, std::uint32_t t) {
        if (regions.in_body(c, tet_region[t])) return std::int8_t(1);
        const int s = query.side(c);
        return std::int8_t(s == 1 ? 2 : s);
      });
}

}  // namespace kdmesh
