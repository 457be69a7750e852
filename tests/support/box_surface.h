// kdmesh tests — the box [lo, hi] as a closed surface: 8 points, 12 outward triangles.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>

#include "core/surface_mesh.h"

namespace kdmesh::test {

inline SurfaceMesh box_surface(std::array<double, 3> lo, std::array<double, 3> hi) {
  SurfaceMesh s;
  for (int i = 0; i < 8; ++i)
    s.points.push_back((i & 1) ? hi[0] : lo[0], (i >> 1 & 1) ? hi[1] : lo[1], (i >> 2 & 1) ? hi[2] : lo[2]);
  for (std::uint32_t x : {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                          2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5})
    s.tris.push_back(x);
  return s;
}

}  // namespace kdmesh::test
