// kdmesh — boundary caps of the quality-improvement pass (mesher/improve_caps.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve_caps.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesher/improve_quality.h"

namespace kdmesh {

namespace {

constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};


/// The face (a, b, c), oriented outward of the domain, lies on the surface: within
/// max_distance x h(centroid) at the mesh check's 7 sample points, and facing the way the
/// closest facet to its centroid faces.
bool face_on_surface(const double* a, const double* b, const double* c, const CapContext& ctx) {
  static constexpr double kBary[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.5, 0}, {0, 0.5, 0.5},
                                         {0.5, 0, 0.5}, {2.0 / 3, 1.0 / 6, 1.0 / 6},
                                         {1.0 / 6, 2.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 2.0 / 3}};
  double cen[3];
  for (int q = 0; q < 3; ++q) cen[q] = (a[q] + b[q] + c[q]) / 3;
  const double limit = ctx.max_distance * (*ctx.sizing)(cen);
  for (const auto& w : kBary) {
    double s[3];
    for (int q = 0; q < 3; ++q) s[q] = w[0] * a[q] + w[1] * b[q] + w[2] * c[q];
    if (!(ctx.query->distance(s) <= limit)) return false;
  }
  double cp[3];
  std::uint32_t facet = kNoFacet;
  ctx.query->closest(cen, cp, &facet);
  if (facet == kNoFacet) return false;
  const SurfaceMesh& sm = ctx.surface->mesh;
  const std::uint32_t* ft = sm.tri(facet);
  double n[3], fn[3];
  tri_normal(a, b, c, n);
  tri_normal(sm.points.p(ft[0]), sm.points.p(ft[1]), sm.points.p(ft[2]), fn);
  return n[0] * fn[0] + n[1] * fn[1] + n[2] * fn[2] > 0;
}

double segment_distance2(const double* x, const double* a, const double* b) {
  const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const double t = dd > 0 ? std::clamp((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd, 0.0, 1.0) : 0.0;
  double r = 0;
  for (int k = 0; k < 3; ++k) r += (w[k] - t * d[k]) * (w[k] - t * d[k]);
  return r;
}

/// True if the mesh edge (a, b) may run along a feature edge: its midpoint lies within 5% of
/// its length of a feature edge of the facet closest to the midpoint (or no features known).
bool along_feature(const double* a, const double* b, const CapContext& ctx) {
  if (!ctx.features) return true;
  const double m[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
  double cp[3];
  std::uint32_t facet = kNoFacet;
  ctx.query->closest(m, cp, &facet);
  if (facet == kNoFacet) return true;
  const SurfaceMesh& sm = ctx.surface->mesh;
  const std::vector<std::uint32_t>& fe = ctx.features->edges;  // (lo, hi) pairs, sorted
  const double len2 = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]);
  for (int j = 0; j < 3; ++j) {
    std::uint32_t p = sm.tri(facet)[j], q = sm.tri(facet)[(j + 1) % 3];
    if (p > q) std::swap(p, q);
    std::size_t lo = 0, hi = fe.size() / 2;  // binary search over the pairs
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if (fe[2 * mid] < p || (fe[2 * mid] == p && fe[2 * mid + 1] < q)) lo = mid + 1;
      else hi = mid;
    }
    if (lo < fe.size() / 2 && fe[2 * lo] == p && fe[2 * lo + 1] == q &&
        segment_distance2(m, sm.points.p(p), sm.points.p(q)) <= 0.0025 * len2)
      return true;
  }
  return false;
}

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

bool remove_cap(ImproveTets& m, std::uint32_t t, const CapContext& ctx) {
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
    if (!face_on_surface(m.p(v[kFace[f][0]]), m.p(v[kFace[f][2]]), m.p(v[kFace[f][1]]), ctx)) return false;
    return m.remove(t, apex);
  }
  if (nb != 2) return false;
  // The boundary faces are opposite vertices bnd[0], bnd[1]; they share the edge of the two
  // other vertices (inner[0], inner[1]), which the removal flips to (bnd[0], bnd[1]).
  const std::uint32_t k0 = v[inner[0]], k1 = v[inner[1]];
  if (nodes.kind[k0] != NodeKind::surface && nodes.kind[k1] != NodeKind::surface &&
      along_feature(m.p(k0), m.p(k1), ctx))
    return false;
  if (boundary_edge(m, v[bnd[0]], v[bnd[1]])) return false;
  // The exposed faces: face `inner[j]` of t, oriented outward of the domain after the removal,
  // i.e. reversed from its orientation outward of t.
  for (int j = 0; j < 2; ++j) {
    const int f = inner[j];
    if (!face_on_surface(m.p(v[kFace[f][0]]), m.p(v[kFace[f][2]]), m.p(v[kFace[f][1]]), ctx)) return false;
  }
  return m.remove(t);
}

}  // namespace kdmesh
