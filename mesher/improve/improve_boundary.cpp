// kdmesh — boundary constraints of the quality-improvement pass (mesher/improve/improve_boundary.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_boundary.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/face_samples.h"
#include "mesher/improve/improve_quality.h"
#include "mesher/improve/improve_tets.h"
#include "sizing/segment_bvh.h"

namespace kdmesh {

namespace {

/// x lies within 5% of |ab| (len2 = |ab|^2) of the segment ab: "along" it, for feature tests.
bool within_tube(const double* x, const double* a, const double* b, double len2) {
  return std::pow(segment_distance(x, a, b), 2) <= 0.0025 * len2;
}

}  // namespace

bool face_on_surface(const double* a, const double* b, const double* c, const BoundaryContext& ctx) {
  double cen[3];
  for (int q = 0; q < 3; ++q) cen[q] = (a[q] + b[q] + c[q]) / 3;
  const double limit = ctx.max_distance * (*ctx.sizing)(cen);
  const double* corner[3] = {a, b, c};  // on the surface: each bounds its samples' search
  for (const auto& w : kFaceSamples) {  // the mesh check's samples
    double s[3];
    for (int q = 0; q < 3; ++q) s[q] = w[0] * a[q] + w[1] * b[q] + w[2] * c[q];
    const int near = int(std::max_element(w, w + 3) - w);
    if (!ctx.query->within(s, limit, corner[near])) return false;
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

bool along_feature(const double* a, const double* b, const BoundaryContext& ctx) {
  if (!ctx.features) return true;
  double on_curve[3];
  std::uint32_t facet = kNoFacet;
  // No facet found: nothing to contradict the edge.
  return point_on_feature(a, b, ctx, on_curve, &facet) || facet == kNoFacet;
}

bool point_on_feature(const double* a, const double* b, const BoundaryContext& ctx, double* x,
                      std::uint32_t* facet_out) {
  *facet_out = kNoFacet;
  if (!ctx.features) return false;
  const double m[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
  double cp[3];
  std::uint32_t facet = kNoFacet;
  ctx.query->closest(m, cp, &facet);
  *facet_out = facet;
  if (facet == kNoFacet) return false;
  const SurfaceMesh& sm = ctx.surface->mesh;
  const double len2 = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]);
  for (int j = 0; j < 3; ++j) {
    std::uint32_t p = sm.tri(facet)[j], q = sm.tri(facet)[(j + 1) % 3];
    if (p > q) std::swap(p, q);
    const double *pp = sm.points.p(p), *pq = sm.points.p(q);
    if (ctx.features->has_edge(p, q) && within_tube(m, pp, pq, len2)) {
      // m's closest point on the segment pq.
      double d[3], t = 0, dd = 0;
      for (int k = 0; k < 3; ++k) d[k] = pq[k] - pp[k], t += (m[k] - pp[k]) * d[k], dd += d[k] * d[k];
      t = dd > 0 ? std::clamp(t / dd, 0.0, 1.0) : 0.0;
      for (int k = 0; k < 3; ++k) x[k] = pp[k] + t * d[k];
      return true;
    }
  }
  return false;
}

namespace {

/// A feature node c next to `from` (a mesh neighbour) lies strictly between a and b, within 5%
/// of |ab| of the segment, and the edge (from, c) runs along a feature.
bool skips_feature_node(const ImproveTets& m, std::uint32_t from, std::uint32_t a, std::uint32_t b,
                        const BoundaryContext& ctx) {
  static thread_local std::vector<std::uint32_t> star;
  const double *pa = m.p(a), *pb = m.p(b);
  double ab[3], len2 = 0;
  for (int i = 0; i < 3; ++i) {
    ab[i] = pb[i] - pa[i];
    len2 += ab[i] * ab[i];
  }
  if (!(len2 > 0)) return false;
  m.star(from, star);
  for (std::uint32_t t : star)
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t c = m.v(t)[k];
      if (c == a || c == b || m.nodes().kind[c] == NodeKind::surface ||
          m.nodes().kind[c] == NodeKind::interior)
        continue;
      const double* pc = m.p(c);
      double s = 0;
      for (int i = 0; i < 3; ++i) s += (pc[i] - pa[i]) * ab[i];
      s /= len2;
      if (!(s > 0.02 && s < 0.98)) continue;
      if (!within_tube(pc, pa, pb, len2)) continue;
      if (along_feature(m.p(from), pc, ctx)) return true;
    }
  return false;
}

}  // namespace

bool keeps_feature(const ImproveTets& m, std::uint32_t a, std::uint32_t b, const BoundaryContext& ctx) {
  if (!along_feature(m.p(a), m.p(b), ctx)) return false;
  if (!ctx.features) return true;
  return !skips_feature_node(m, a, a, b, ctx) && !skips_feature_node(m, b, a, b, ctx);
}

}  // namespace kdmesh
