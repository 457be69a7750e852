// kdmesh — surface edges with their facets and dihedral deviation.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/surface_edges.h"

#include "sizing/vec3.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace kdmesh {
namespace {

using vec3::Vec3, vec3::cross, vec3::dot, vec3::sub;

/// Unnormalised outward normal of facet f: (b-a) x (c-a), following the facet's orientation.
Vec3 facet_normal(const SurfaceMesh& s, std::size_t f) {
  const std::uint32_t* t = s.tri(f);
  const double* a = s.points.p(t[0]);
  return cross(sub(s.points.p(t[1]), a), sub(s.points.p(t[2]), a));
}

/// One directed use of an edge by a facet: the edge (lo, hi) and whether the facet runs lo->hi.
struct EdgeUse {
  std::uint32_t lo, hi, facet;
  bool forward;
};

}  // namespace

std::vector<SurfaceEdge> surface_edges(const SurfaceMesh& surface) {
  const std::size_t nf = surface.num_tris();
  const std::size_t np = surface.points.size();
  std::vector<EdgeUse> uses;
  uses.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* t = surface.tri(f);
    if (t[0] >= np || t[1] >= np || t[2] >= np) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      uses.push_back({std::min(a, b), std::max(a, b), std::uint32_t(f), a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.facet < y.facet;
  });
  std::vector<SurfaceEdge> out;
  out.reserve(uses.size() / 2 + 1);
  constexpr double kAlways = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    SurfaceEdge e;
    e.lo = uses[i].lo;
    e.hi = uses[i].hi;
    e.f0 = uses[i].facet;
    if (j - i != 2 || uses[i].forward == uses[i + 1].forward) {
      e.deviation = kAlways;
      if (j - i == 2) e.f1 = uses[i + 1].facet;
    } else {
      e.f1 = uses[i + 1].facet;
      // atan2 form: accurate near 0 and pi; a degenerate facet gives 0 or pi/2.
      const Vec3 a = facet_normal(surface, e.f0), b = facet_normal(surface, e.f1);
      const Vec3 c = cross(a, b);
      e.deviation = std::atan2(std::sqrt(dot(c, c)), dot(a, b));
    }
    out.push_back(e);
    i = j;
  }
  return out;
}

}  // namespace kdmesh
