// kdmesh — the side of the surface of every tet's centroid, carried along clear segments.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/quality/centroid_sides.h"

#include <numeric>

#include "core/parallel_for.h"
#include "core/uninit_allocator.h"

namespace kdmesh {

namespace {

/// Both overloads: `clear(a, b, pair)` may carry an answer along the pair's centroid segment,
/// `answer(c, t)` is tet t's answer at its centroid c.
template <class Clear, class Answer>
std::vector<std::int8_t> carried(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                 const std::vector<std::pair<std::uint32_t, std::uint32_t>>& neighbours,
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
  parallel_for(neighbours.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i)
      clear[i] = clear_of(&cen[3 * neighbours[i].first], &cen[3 * neighbours[i].second], neighbours[i]);
  }, 1024);
  // Union-find over the clear pairs; each root is its set's lowest tet.
  std::vector<std::uint32_t> up(nt);
  std::iota(up.begin(), up.end(), 0u);
  auto root = [&](std::uint32_t t) {
    while (up[t] != t) t = up[t] = up[up[t]];
    return t;
  };
  for (std::size_t i = 0; i < neighbours.size(); ++i)
    if (clear[i]) {
      const std::uint32_t a = root(neighbours[i].first), b = root(neighbours[i].second);
      if (a != b) up[std::max(a, b)] = std::min(a, b);
    }
  std::vector<std::uint32_t> roots;
  for (std::uint32_t t = 0; t < nt; ++t)
    if (root(t) == t) roots.push_back(t);
  std::vector<std::int8_t> side(nt, 0);
  parallel_for(roots.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) side[roots[i]] = answer(&cen[3 * roots[i]], roots[i]);
  }, 64);
  for (std::uint32_t t = 0; t < nt; ++t) side[t] = side[root(t)];
  return side;
}

}  // namespace

std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        const std::vector<std::pair<std::uint32_t, std::uint32_t>>& neighbours,
                                        const SurfaceQuery& query) {
  return carried(
      points, tets, neighbours,
      [&](const double* a, const double* b, const std::pair<std::uint32_t, std::uint32_t>&) {
        return query.segment_clear(a, b);
      },
      [&](const double* c, std::uint32_t) { return std::int8_t(query.side(c)); });
}

std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        const std::vector<std::pair<std::uint32_t, std::uint32_t>>& neighbours,
                                        const SurfaceQuery& query, const RegionQuery& regions,
                                        const std::vector<std::uint32_t>& tet_region) {
  return carried(
      points, tets, neighbours,
      [&](const double* a, const double* b, const std::pair<std::uint32_t, std::uint32_t>& n) {
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
