// kdmesh — sliver splits of the quality-improvement pass (mesher/improve/improve_split.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_split.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "mesher/improve/improve_quality.h"

namespace kdmesh {

std::array<std::pair<double, int>, 6> edges_longest_first(const ImproveTets& m, std::uint32_t t) {
  const std::uint32_t* v = m.v(t);
  std::array<std::pair<double, int>, 6> by_length;
  for (int e = 0; e < 6; ++e) {
    const double *a = m.p(v[kTetEdge[e][0]]), *b = m.p(v[kTetEdge[e][1]]);
    by_length[e] = {(a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]), e};
  }
  std::sort(by_length.begin(), by_length.end(), [](const auto& x, const auto& y) {
    return x.first != y.first ? x.first > y.first : x.second < y.second;
  });
  return by_length;
}

bool split_sliver(ImproveTets& m, std::uint32_t t, int max_ring, std::uint32_t* node,
                  std::vector<std::uint32_t>* created) {
  if (!m.alive(t)) return false;
  const std::uint32_t* v = m.v(t);
  const std::array<std::pair<double, int>, 6> by_length = edges_longest_first(m, t);
  static thread_local std::vector<std::uint32_t> ring, tets, fresh;
  constexpr double kClearance = 0.15;  // of the split edge's length
  // The normal of the sliver's plane: across its two opposite edges (a flat tet's four
  // vertices lie nearly in one plane, which both cross).
  double nrm[3];
  {
    const double *p0 = m.p(v[0]), *p1 = m.p(v[1]), *p2 = m.p(v[2]), *p3 = m.p(v[3]);
    const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const double w[3] = {p3[0] - p2[0], p3[1] - p2[1], p3[2] - p2[2]};
    nrm[0] = u[1] * w[2] - u[2] * w[1], nrm[1] = u[2] * w[0] - u[0] * w[2], nrm[2] = u[0] * w[1] - u[1] * w[0];
    const double l = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    if (!(l > 0)) return false;
    for (double& c : nrm) c /= l;
  }
  for (const auto& [len2, e] : by_length) {
    const std::uint32_t a = v[kTetEdge[e][0]], b = v[kTetEdge[e][1]];
    if (!m.edge_ring(t, a, b, ring, tets) || int(ring.size()) > max_ring) continue;  // boundary edge
    const double *pa = m.p(a), *pb = m.p(b);
    const std::size_t n = ring.size();
    double worst_old = 1;
    for (std::uint32_t r : tets) {
      const std::uint32_t* rv = m.v(r);
      worst_old = std::min(worst_old, tet_sine(m.p(rv[0]), m.p(rv[1]), m.p(rv[2]), m.p(rv[3])));
    }
    // Tet k of the ring is (a, b, r_k, r_k+1); its halves are (a, x, r_k, r_k+1) and
    // (x, b, r_k, r_k+1). x: the midpoint of ab moved off the sliver's plane, where the worst
    // half is best; every half valid (exact orientation, not flat) and, with a surface
    // vertex, centroid inside (inside_ok counts surface vertices by id: standing in a or b
    // for the interior node can only ask for that test more often).
    const double L = std::sqrt(len2);
    double best_x[3] = {0, 0, 0}, best_q = worst_old;
    for (double s : {0.0, 0.1, -0.1, 0.2, -0.2, 0.3, -0.3, 0.4, -0.4}) {
      double x[3];
      for (int k = 0; k < 3; ++k) x[k] = (pa[k] + pb[k]) / 2 + s * L * nrm[k];
      // The new node is interior: clear of the surface by a share of the edge. On the midpoint
      // of an edge between two nodes of a flat face it would lie on that face, and the halves
      // are flat again (helmet.ply at diag/40: interior nodes 1e-6 from its base, 0.01 deg tets).
      if (m.inside_query && !(m.inside_query->distance(x) >= kClearance * L)) continue;
      double q = 1;
      for (std::size_t k = 0; k < n && q > best_q; ++k) {
        const std::uint32_t r0 = ring[k], r1 = ring[(k + 1) % n];
        const double* h1[4] = {pa, x, m.p(r0), m.p(r1)};
        const double* h2[4] = {x, pb, m.p(r0), m.p(r1)};
        const std::uint32_t i1[4] = {a, a, r0, r1}, i2[4] = {b, b, r0, r1};
        if (!tet_valid(h1[0], h1[1], h1[2], h1[3]) || !tet_valid(h2[0], h2[1], h2[2], h2[3]) ||
            !m.inside_ok(i1, h1) || !m.inside_ok(i2, h2)) {
          q = -1;
          break;
        }
        q = std::min({q, tet_sine(h1[0], h1[1], h1[2], h1[3]), tet_sine(h2[0], h2[1], h2[2], h2[3])});
      }
      if (q > best_q) best_q = q, std::copy_n(x, 3, best_x);
    }
    if (!(best_q > worst_old)) continue;  // no position makes the ring's worst tet better
    const std::uint32_t x = m.add_interior_node(best_x, std::max(m.nodes().size[a], m.nodes().size[b]));
    fresh.clear();
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t r0 = ring[k], r1 = ring[(k + 1) % n];
      fresh.insert(fresh.end(), {a, x, r0, r1, x, b, r0, r1});
    }
    if (!m.replace(tets, fresh, created)) return false;  // the node stays unused; write_back drops it
    if (node) *node = x;
    return true;
  }
  return false;
}

}  // namespace kdmesh
