// Test support: an icosphere (a curved solid whose facets are not axis-aligned).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh::test {

/// Icosahedron with each facet split into 4, `levels` times, vertices pushed to the unit sphere.
inline SurfaceMesh icosphere(int levels) {
  SurfaceMesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  const double v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) {
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    m.points.push_back(p[0] / r, p[1] / r, p[2] / r);
  }
  m.tris = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
            3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto [it, fresh] = mid.try_emplace(std::minmax(a, b), std::uint32_t(m.points.size()));
      if (fresh) {
        double p[3];
        for (int k = 0; k < 3; ++k) p[k] = (m.points.p(a)[k] + m.points.p(b)[k]) / 2;
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        m.points.push_back(p[0] / r, p[1] / r, p[2] / r);
      }
      return it->second;
    };
    std::vector<std::uint32_t> tris;
    for (std::size_t f = 0; f < m.num_tris(); ++f) {
      const std::uint32_t a = m.tris[3 * f], b = m.tris[3 * f + 1], c = m.tris[3 * f + 2];
      const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      tris.insert(tris.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.tris = std::move(tris);
  }
  return m;
}

}  // namespace kdmesh::test
