// kdmesh — boundary caps of the quality-improvement pass (mesher/improve/improve_caps.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_caps.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesher/improve/improve_quality.h"

namespace kdmesh {

namespace {

/// True if (a, b) is an edge of a boundary face.
bool boundary_edge(const ImproveTets& m, std::uint32_t a, std::uint32_t b) {
  static thread_local std::vector<std::uint32_t> star;
  m.star(a, star);
  for (std::uint32_t t : star) {
    const std::uint32_t* v = m.v(t);
    const int ib = index_in(v, b);
    if (ib < 0) continue;
    const int ia = index_in(v, a);
    // The two faces of t holding edge ab are those opposite its other two vertices.
    for (int f = 0; f < 4; ++f)
      if (f != ia && f != ib && m.adj(t, f) == kImproveNone) return true;
  }
  return false;
}

}  // namespace

bool remove_cap(ImproveTets& m, std::uint32_t t, const BoundaryContext& ctx) {
  if (!m.alive(t)) return false;
  const std::uint32_t* v = m.v(t);
  int bnd[3], inner[2], nb = 0, ni = 0;
  for (int f = 0; f < 4; ++f) {
    if (m.adj(t, f) == kImproveNone) {
      if (nb == 3) return false;
      bnd[nb++] = f;
    } else {
      if (ni == 2) return false;
      inner[ni++] = f;
    }
  }
  const NodeSet& nodes = m.nodes();
  for (int k = 0; k < 4; ++k)
    if (nodes.kind[v[k]] == NodeKind::interior) return false;
  if (nb == 3) {
    // Three boundary faces around the apex opposite the one inner face: when the apex is a
    // surface node in no other tet, taking t out drops the apex and exposes the inner face
    // (the removal of a neighbouring cap can leave such a tet, 1.3 deg on a sphere).
    static thread_local std::vector<std::uint32_t> star;
    const std::uint32_t apex = v[inner[0]];
    if (nodes.kind[apex] != NodeKind::surface) return false;
    m.star(apex, star);
    if (star.size() != 1) return false;
    const int f = inner[0];
    if (!face_on_surface(m.p(v[kTetFace[f][0]]), m.p(v[kTetFace[f][2]]), m.p(v[kTetFace[f][1]]), ctx)) return false;
    return m.remove(t, apex);
  }
  if (nb != 2) return false;
  // The boundary faces are opposite vertices bnd[0], bnd[1]; they share the edge of the two
  // other vertices (inner[0], inner[1]), which the removal flips to (bnd[0], bnd[1]).
  const std::uint32_t k0 = v[inner[0]], k1 = v[inner[1]];
  if (nodes.kind[k0] != NodeKind::surface && nodes.kind[k1] != NodeKind::surface &&
      keeps_feature(m, k0, k1, ctx))
    return false;
  if (boundary_edge(m, v[bnd[0]], v[bnd[1]])) return false;
  // The exposed faces: face `inner[j]` of t, oriented outward of the domain after the removal,
  // i.e. reversed from its orientation outward of t.
  for (int j = 0; j < 2; ++j) {
    const int f = inner[j];
    if (!face_on_surface(m.p(v[kTetFace[f][0]]), m.p(v[kTetFace[f][2]]), m.p(v[kTetFace[f][1]]), ctx)) return false;
  }
  return m.remove(t);
}

}  // namespace kdmesh
