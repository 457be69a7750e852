// kdmesh — sharp feature detection: dihedral-angle feature edges and their corners.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/features.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace kdmesh {
namespace {

using Vec3 = std::array<double, 3>;

Vec3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

/// Angle in radians between a and b, in [0, pi]; atan2 form, accurate near 0 and pi. A zero
/// vector (degenerate facet or edge) gives 0 when both are zero, pi/2 otherwise (atan2(0,0)=0).
double angle_between(const Vec3& a, const Vec3& b) { return std::atan2(norm(cross(a, b)), dot(a, b)); }

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

FeatureEdges detect_sharp_edges(const SurfaceMesh& surface, double angle_deg) {
  FeatureEdges out;
  if (!(angle_deg > 0 && angle_deg < 180)) return out;  // also rejects NaN
  // Exact in binary for 45, 90 (angle_deg / 180 is then a power of two).
  const double threshold = angle_deg / 180.0 * std::numbers::pi;

  const std::size_t nf = surface.num_tris();
  const std::size_t np = surface.points.size();
  std::vector<EdgeUse> uses;
  uses.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* t = surface.tri(f);
    // Facets with out-of-range ids are ignored (never read out of bounds).
    if (t[0] >= np || t[1] >= np || t[2] >= np) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;  // a degenerate facet's collapsed edge is not an edge
      uses.push_back({std::min(a, b), std::max(a, b), std::uint32_t(f), a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.facet < y.facet;
  });

  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    bool feature;
    if (j - i != 2) {
      feature = true;  // boundary or non-manifold edge: always kept
    } else if (uses[i].forward == uses[i + 1].forward) {
      feature = true;  // both facets run the edge the same way: orientation flips here
    } else {
      const double dev = angle_between(facet_normal(surface, uses[i].facet),
                                       facet_normal(surface, uses[i + 1].facet));
      feature = dev >= threshold;
    }
    if (feature) {
      out.edges.push_back(uses[i].lo);
      out.edges.push_back(uses[i].hi);
    }
    i = j;
  }
  // uses were sorted by (lo, hi): out.edges is already sorted and unique.

  // Corners: feature-edge points with != 2 incident feature edges, or where the two turn.
  std::vector<std::uint32_t> incident;  // (point, other end) pairs, sorted by point
  incident.reserve(2 * out.edges.size());
  for (std::size_t e = 0; e < out.num_edges(); ++e) {
    incident.push_back(out.edges[2 * e]);
    incident.push_back(out.edges[2 * e + 1]);
    incident.push_back(out.edges[2 * e + 1]);
    incident.push_back(out.edges[2 * e]);
  }
  std::vector<std::array<std::uint32_t, 2>> pairs(incident.size() / 2);
  for (std::size_t k = 0; k < pairs.size(); ++k) pairs[k] = {incident[2 * k], incident[2 * k + 1]};
  std::sort(pairs.begin(), pairs.end());
  for (std::size_t i = 0; i < pairs.size();) {
    std::size_t j = i + 1;
    while (j < pairs.size() && pairs[j][0] == pairs[i][0]) ++j;
    const std::uint32_t v = pairs[i][0];
    bool corner = j - i != 2;
    if (!corner) {
      const double* pv = surface.points.p(v);
      const Vec3 in = sub(pv, surface.points.p(pairs[i][1]));      // u -> v
      const Vec3 outdir = sub(surface.points.p(pairs[i + 1][1]), pv);  // v -> w
      corner = angle_between(in, outdir) >= threshold;
    }
    if (corner) out.corners.push_back(v);
    i = j;
  }
  return out;
}

}  // namespace kdmesh
