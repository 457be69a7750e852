// kdmesh — the automatic curvature terms of the sizing field.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/curvature_sizes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "sizing/surface_edges.h"

namespace kdmesh {

void add_curvature_sizes(const SurfaceMesh& surface, const SizingOptions& options, double min_size,
                         WeightedSegments& out, SizingAutoStats& stats) {
  const double angle = options.curvature_angle_deg / 180.0 * std::numbers::pi;
  const double chord = options.chordal_deviation;
  if (!(angle > 0) && !(chord > 0)) return;
  const double feature = options.feature_angle_deg > 0
                             ? options.feature_angle_deg / 180.0 * std::numbers::pi
                             : std::numeric_limits<double>::infinity();
  const double h_max = options.max_size;
  auto centroid = [&](std::uint32_t f, double* c) {
    const std::uint32_t* t = surface.tri(f);
    for (int k = 0; k < 3; ++k)
      c[k] = (surface.points.p(t[0])[k] + surface.points.p(t[1])[k] + surface.points.p(t[2])[k]) / 3;
  };
  for (const SurfaceEdge& e : surface_edges(surface)) {
    if (!e.manifold() || !(e.deviation > 0) || !(e.deviation < feature)) continue;
    double c0[3], c1[3];
    centroid(e.f0, c0);
    centroid(e.f1, c1);
    // The centroids' distance across the edge (its component along the edge is no bending).
    const double* a = surface.points.p(e.lo);
    const double* b = surface.points.p(e.hi);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    if (!(uu > 0)) continue;
    double w[3] = {c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]};
    const double along = (w[0] * u[0] + w[1] * u[1] + w[2] * u[2]) / uu;
    for (int k = 0; k < 3; ++k) w[k] -= along * u[k];
    const double r = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / e.deviation;
    if (!(r > 0) || !std::isfinite(r)) continue;
    double h = h_max;
    if (angle > 0) h = std::min(h, angle * r);
    if (chord > 0) h = std::min(h, std::sqrt(12 * r * chord));
    h = std::max(h, min_size);
    if (!(h < h_max)) continue;
    out.push_back(surface.points.p(e.lo), surface.points.p(e.hi), h);
    if (stats.curvature_edges++ == 0 || h < stats.min_curvature_size) stats.min_curvature_size = h;
    if (stats.curvature_edges == 1 || r < stats.min_radius) stats.min_radius = r;
  }
}

}  // namespace kdmesh
