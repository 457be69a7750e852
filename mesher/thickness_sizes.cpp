// kdmesh — wall thickness and gap width from rays cast at every facet's centroid.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/thickness_sizes.h"

#include <cmath>
#include <limits>
#include <vector>

#include "mesher/parallel_for.h"

namespace kdmesh {

ThicknessStats add_thickness_sizes(const PreparedSurface& surface, const SurfaceQuery& query,
                                   const ThicknessOptions& options, WeightedSegments& out) {
  ThicknessStats st;
  const SurfaceMesh& sm = surface.mesh;
  const std::size_t nf = sm.num_tris();
  if (!(options.layers > 0) && !(options.gap_layers > 0)) return st;
  auto unit_normal = [&](std::size_t f, double* n) {
    const std::uint32_t* t = sm.tri(f);
    const double *a = sm.points.p(t[0]), *p = sm.points.p(t[1]), *q = sm.points.p(t[2]);
    const double u[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    const double v[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1], n[1] = u[2] * v[0] - u[0] * v[2], n[2] = u[0] * v[1] - u[1] * v[0];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0) || !std::isfinite(len)) return false;
    for (int k = 0; k < 3; ++k) n[k] /= len;
    return true;
  };
  auto centroid = [&](std::size_t f, double* c) {
    const std::uint32_t* t = sm.tri(f);
    for (int k = 0; k < 3; ++k)
      c[k] = (sm.points.p(t[0])[k] + sm.points.p(t[1])[k] + sm.points.p(t[2])[k]) / 3;
  };
  // A wall or a gap only counts where the facet hit faces back (normals more than 120 deg
  // apart): the two sides of a plate or a slot, not the flanks of an open groove or a bump.
  auto faces_back = [&](const double* n, std::uint32_t hit) {
    double m[3];
    return hit != kNoFacet && unit_normal(hit, m) && n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < -0.5;
  };
  // Per facet: the inward and outward hit distances along the unit normal (inf: none).
  std::vector<double> in(nf, std::numeric_limits<double>::infinity()), gap(nf, in[0]);
  parallel_for(nf, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t f = b; f < e; ++f) {
      double n[3];
      if (!unit_normal(f, n)) continue;
      double c[3];
      centroid(f, c);
      if (options.layers > 0) {
        const double d[3] = {-n[0], -n[1], -n[2]};
        std::uint32_t hit;
        const double x = query.ray_distance(c, d, std::uint32_t(f), &hit);
        if (faces_back(n, hit)) in[f] = x;
      }
      if (options.gap_layers > 0) {
        std::uint32_t hit;
        const double x = query.ray_distance(c, n, std::uint32_t(f), &hit);
        if (faces_back(n, hit)) gap[f] = x;
      }
    }
  }, 256);
  auto add = [&](std::size_t f, double dist, double sign, double layers) {
    const double size = dist / layers;
    double n[3];
    if (!(size < options.max_size) || !(dist > 0) || !unit_normal(f, n)) return false;
    double c[3], e[3];
    centroid(f, c);
    for (int k = 0; k < 3; ++k) e[k] = c[k] + sign * dist * n[k];
    out.push_back(c, e, size);
    return true;
  };
  for (std::size_t f = 0; f < nf; ++f) {
    if (std::isfinite(in[f]) && add(f, in[f], -1, options.layers)) {
      if (st.walls++ == 0 || in[f] < st.min_wall) st.min_wall = in[f];
    }
    if (std::isfinite(gap[f]) && add(f, gap[f], +1, options.gap_layers)) {
      if (st.gaps++ == 0 || gap[f] < st.min_gap) st.min_gap = gap[f];
    }
  }
  return st;
}

}  // namespace kdmesh
