// kdmesh — sharp feature detection: dihedral-angle feature edges and their corners.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/features.h"

#include "sizing/surface_edges.h"
#include "sizing/vec3.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace kdmesh {
using vec3::Vec3, vec3::angle_between, vec3::sub;

namespace {

/// Corners: feature-edge points with != 2 incident feature edges, or where the two turn by
/// more than `threshold` (radians).
void find_corners(const SurfaceMesh& surface, double threshold, FeatureEdges& out) {
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
}

}  // namespace

FeatureEdges detect_sharp_edges(const SurfaceMesh& surface, double angle_deg,
                                const std::vector<std::uint32_t>& also) {
  FeatureEdges out;
  const bool sharp = angle_deg > 0 && angle_deg < 180;  // also rejects NaN
  if (!sharp && also.empty()) return out;
  // Exact in binary for 45, 90 (angle_deg / 180 is then a power of two).
  const double threshold = sharp ? angle_deg / 180.0 * std::numbers::pi : std::numbers::pi;

  if (sharp)
    for (const SurfaceEdge& e : surface_edges(surface))
      if (e.deviation >= threshold) {  // non-manifold and orientation-flipping edges: +inf
        out.edges.push_back(e.lo);
        out.edges.push_back(e.hi);
      }
  // surface_edges is sorted by (lo, hi): out.edges is already sorted and unique.
  if (!also.empty()) {
    std::vector<std::array<std::uint32_t, 2>> all;
    for (std::size_t k = 0; k < out.edges.size(); k += 2) all.push_back({out.edges[k], out.edges[k + 1]});
    for (std::size_t k = 0; k + 1 < also.size(); k += 2)
      all.push_back({std::min(also[k], also[k + 1]), std::max(also[k], also[k + 1])});
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    out.edges.clear();
    for (const auto& e : all) out.edges.insert(out.edges.end(), {e[0], e[1]});
  }
  find_corners(surface, threshold, out);
  return out;
}

double smallest_edge_angle(const SurfaceMesh& surface) {
  double smallest = 180;
  for (const SurfaceEdge& e : surface_edges(surface)) {
    if (!e.manifold() || !std::isfinite(e.deviation)) continue;
    // The vertex of f1 off the edge, against the plane of f0: below it (outward normals), the
    // edge is convex and the solid's angle there is pi - deviation; else pi + deviation.
    const std::uint32_t* t0 = surface.tri(e.f0);
    const std::uint32_t* t1 = surface.tri(e.f1);
    std::uint32_t off = t1[0];
    for (int k = 0; k < 3; ++k)
      if (t1[k] != e.lo && t1[k] != e.hi) off = t1[k];
    const double* p0 = surface.points.p(t0[0]);
    const Vec3 n = vec3::cross(sub(surface.points.p(t0[1]), p0), sub(surface.points.p(t0[2]), p0));
    const bool convex = vec3::dot(n, sub(surface.points.p(off), p0)) <= 0;
    const double angle = convex ? std::numbers::pi - e.deviation : std::numbers::pi + e.deviation;
    smallest = std::min(smallest, angle * 180 / std::numbers::pi);
  }
  return smallest;
}

}  // namespace kdmesh
