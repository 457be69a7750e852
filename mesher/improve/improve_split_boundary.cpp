// kdmesh — boundary-edge splits of the quality-improvement pass (mesher/improve/improve_split_boundary.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_split_boundary.h"

#include <algorithm>
#include <cmath>

#include "mesher/improve/improve_quality.h"

namespace kdmesh {

bool split_boundary_edge(ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                         int max_ring, const BoundaryContext& ctx,
                         std::vector<std::uint32_t>* created) {
  if (!m.alive(t) || !ctx.query || !ctx.sizing) return false;
  const NodeSet& nodes = m.nodes();
  if (nodes.kind[a] == NodeKind::interior || nodes.kind[b] == NodeKind::interior) return false;
  // A feature edge is split on its curve: the new node is an edge node.
  const bool feature = nodes.kind[a] != NodeKind::surface && nodes.kind[b] != NodeKind::surface &&
                       keeps_feature(m, a, b, ctx);
  static thread_local std::vector<std::uint32_t> ring, tets, fresh;
  if (!m.open_edge_ring(t, a, b, max_ring, ring, tets)) return false;
  const double *pa = m.p(a), *pb = m.p(b);
  double mid[3], x[3], len2 = 0;
  for (int k = 0; k < 3; ++k) {
    mid[k] = (pa[k] + pb[k]) / 2;
    len2 += (pb[k] - pa[k]) * (pb[k] - pa[k]);
  }
  std::uint32_t facet = kNoFacet;
  if (feature) {
    if (!point_on_feature(pa, pb, ctx, x, &facet)) return false;
  } else {
    ctx.query->closest(mid, x, &facet);
  }
  double dist2 = 0;
  for (int k = 0; k < 3; ++k) dist2 += (x[k] - mid[k]) * (x[k] - mid[k]);
  if (facet == kNoFacet || !(dist2 <= len2 / 16)) return false;
  const double h = (*ctx.sizing)(x);
  if (!(len2 >= h * h)) return false;  // halves shorter than half the size: not a long edge
  double worst_old = 1;
  for (std::uint32_t r : tets) {
    const std::uint32_t* rv = m.v(r);
    worst_old = std::min(worst_old, tet_sine(m.p(rv[0]), m.p(rv[1]), m.p(rv[2]), m.p(rv[3])));
  }
  // Tet k of the ring is (a, b, r_k, r_k+1); its halves are (a, x, r_k, r_k+1) and
  // (x, b, r_k, r_k+1). The new node has no id yet: in inside_ok, which only counts surface
  // vertices, b stands for it in the first half and a in the second (all three are surface).
  const std::size_t n = tets.size();
  double worst_new = 1;
  for (std::size_t k = 0; k < n && worst_new > worst_old; ++k) {
    const std::uint32_t r0 = ring[k], r1 = ring[k + 1];
    const double* h1[4] = {pa, x, m.p(r0), m.p(r1)};
    const double* h2[4] = {x, pb, m.p(r0), m.p(r1)};
    const std::uint32_t i1[4] = {a, b, r0, r1}, i2[4] = {a, b, r0, r1};
    if (!tet_valid(h1[0], h1[1], h1[2], h1[3]) || !tet_valid(h2[0], h2[1], h2[2], h2[3]) ||
        !m.inside_ok(i1, h1) || !m.inside_ok(i2, h2))
      return false;
    worst_new = std::min({worst_new, tet_sine(h1), tet_sine(h2)});
  }
  if (!(worst_new > worst_old)) return false;
  // The four new boundary faces, outward (mesher/improve/improve_caps.cpp's kFace): of (a, x, r_0, r_1)
  // and (x, b, r_0, r_1) the faces opposite r_1, of the last two halves those opposite r_m-1.
  const double *p0 = m.p(ring.front()), *pm = m.p(ring.back());
  if (!face_on_surface(pa, p0, x, ctx) || !face_on_surface(x, p0, pb, ctx) ||
      !face_on_surface(pa, x, pm, ctx) || !face_on_surface(x, pb, pm, ctx))
    return false;
  const std::uint32_t xi = m.add_boundary_node(x, feature ? NodeKind::edge : NodeKind::surface, facet, float(h));
  fresh.clear();
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t r0 = ring[k], r1 = ring[k + 1];
    fresh.insert(fresh.end(), {a, xi, r0, r1, xi, b, r0, r1});
  }
  // The node stays unused if the faces do not match; write_back drops it.
  return m.replace(tets, fresh, created, /*boundary_may_change=*/true);
}

}  // namespace kdmesh
