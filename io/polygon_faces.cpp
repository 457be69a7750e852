// kdmesh — polygon triangulation for the indexed surface formats (see polygon_faces.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/polygon_faces.h"

#include <cmath>

namespace kdmesh {

bool ear_clip(const std::vector<std::uint32_t>& poly, const std::vector<double>& xyz, std::uint32_t* out) {
  const std::size_t n = poly.size();
  double nrm[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const double* a = &xyz[3 * std::size_t(poly[i])];
    const double* b = &xyz[3 * std::size_t(poly[(i + 1) % n])];
    nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
    nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
    nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
  }
  int drop = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(nrm[k]) > std::fabs(nrm[drop])) drop = k;
  if (!(std::fabs(nrm[drop]) > 0)) return false;
  const int ix = (drop + 1) % 3, iy = (drop + 2) % 3;
  const double sign = nrm[drop] > 0 ? 1 : -1;  // counter-clockwise in the projection
  auto x = [&](std::uint32_t v) { return xyz[3 * std::size_t(v) + std::size_t(ix)]; };
  auto y = [&](std::uint32_t v) { return xyz[3 * std::size_t(v) + std::size_t(iy)]; };
  auto cross = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return sign * ((x(b) - x(a)) * (y(c) - y(a)) - (y(b) - y(a)) * (x(c) - x(a)));
  };
  std::vector<std::uint32_t> ring = poly;
  std::size_t written = 0;
  while (ring.size() > 3) {
    bool clipped = false;
    const std::size_t m = ring.size();
    for (std::size_t k = 0; k < m && !clipped; ++k) {
      const std::size_t i = (k + 1) % m;  // from the second vertex: a convex polygon gives its fan
      const std::uint32_t a = ring[(i + m - 1) % m], b = ring[i], c = ring[(i + 1) % m];
      if (!(cross(a, b, c) > 0)) continue;  // reflex or flat corner: not an ear
      bool empty = true;
      for (std::size_t k = 0; k < m && empty; ++k) {
        const std::uint32_t p = ring[k];
        if (p == a || p == b || p == c) continue;
        empty = !(cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0);
      }
      if (!empty) continue;
      out[written++] = a;
      out[written++] = b;
      out[written++] = c;
      ring.erase(ring.begin() + long(i));
      clipped = true;
    }
    if (!clipped) return false;
  }
  out[written++] = ring[0];
  out[written++] = ring[1];
  out[written++] = ring[2];
  return true;
}

}  // namespace kdmesh
