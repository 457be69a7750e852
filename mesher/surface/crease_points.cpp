// kdmesh — crease edges of a surface and closest points on them.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface/crease_points.h"

#include <algorithm>
#include <cmath>

#include "mesher/delaunay/predicates.h"

namespace kdmesh {

CreaseFinder::CreaseFinder(const SurfaceMesh& s) : surface_(&s) {
  const std::size_t nf = s.num_tris();
  neighbour_.assign(3 * nf, kNoFacet);
  crease_.assign(3 * nf, 0);
  struct E {
    std::uint64_t key;
    std::uint32_t slot;  // 3*facet + j
  };
  std::vector<E> e;
  e.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) {
      std::uint32_t a = s.tris[3 * f + j], b = s.tris[3 * f + (j + 1) % 3];
      if (a > b) std::swap(a, b);
      e.push_back({(std::uint64_t(a) << 32) | b, std::uint32_t(3 * f + j)});
    }
  std::sort(e.begin(), e.end(), [](const E& x, const E& y) { return x.key < y.key; });
  for (std::size_t i = 0; i + 1 < e.size();) {
    std::size_t j = i;
    while (j < e.size() && e[j].key == e[i].key) ++j;
    if (j - i == 2) {  // manifold edge (prepared surfaces have only these)
      const std::uint32_t s0 = e[i].slot, s1 = e[i + 1].slot;
      neighbour_[s0] = s1 / 3;
      neighbour_[s1] = s0 / 3;
      // Crease: the far vertex of the second facet is off the first facet's plane.
      const std::uint32_t* t0 = s.tri(s0 / 3);
      const std::uint32_t* t1 = s.tri(s1 / 3);
      const std::uint32_t far = t1[(s1 % 3 + 2) % 3];
      const bool c = pred::orient3d(s.points.p(t0[0]), s.points.p(t0[1]), s.points.p(t0[2]),
                                    s.points.p(far)) != 0;
      crease_[s0] = crease_[s1] = c;
    }
    i = j;
  }
}

namespace {
void closest_on_segment(const double* q, const double* a, const double* b, double* out) {
  const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double t = dd > 0 ? ((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1] + (q[2] - a[2]) * d[2]) / dd : 0;
  t = std::clamp(t, 0.0, 1.0);
  for (int k = 0; k < 3; ++k) out[k] = a[k] + t * d[k];
}
}  // namespace

bool CreaseFinder::closest_crease_point(const double* q, const std::uint32_t* facets, int n,
                                        double* out, std::uint32_t* facet) const {
  std::vector<std::uint32_t> cand;
  for (int i = 0; i < n; ++i) {
    if (facets[i] == kNoFacet || facets[i] >= surface_->num_tris()) continue;
    cand.push_back(facets[i]);
    for (int j = 0; j < 3; ++j)
      if (neighbour_[3 * std::size_t(facets[i]) + j] != kNoFacet)
        cand.push_back(neighbour_[3 * std::size_t(facets[i]) + j]);
  }
  bool found = false;
  double best = 0;
  for (std::uint32_t f : cand)
    for (int j = 0; j < 3; ++j) {
      if (!crease_[3 * std::size_t(f) + j]) continue;
      const std::uint32_t* t = surface_->tri(f);
      double p[3];
      closest_on_segment(q, surface_->points.p(t[j]), surface_->points.p(t[(j + 1) % 3]), p);
      const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
      if (!found || d2 < best) {
        found = true;
        best = d2;
        std::copy_n(p, 3, out);
        if (facet) *facet = f;
      }
    }
  return found;
}

}  // namespace kdmesh
