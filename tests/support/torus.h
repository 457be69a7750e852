// Test support: a tessellated torus with seeded radial roughness (a "scan"), as STL stores it.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cmath>
#include <cstdint>
#include <numbers>

#include "core/rng.h"
#include "core/surface_mesh.h"

namespace kdmesh::test {

/// A torus: tube radius r around a circle of radius R in the xy plane, nu x nv quads (u around
/// the z axis, v around the tube), each split along its (i,j)-(i+1,j+1) diagonal: 2 nu nv
/// triangles. The tube radius of each grid point is r + roughness * step * U(-1, 1), step the
/// grid step around the tube; with roughness well below 1 the surface stays embedded (facets
/// tilt by at most atan(2 roughness)). Coordinates rounded to float, as an STL file stores them.
inline SurfaceMesh rough_torus(double R, double r, int nu, int nv, double roughness, std::uint64_t seed) {
  SurfaceMesh m;
  Rng rng(seed);
  const double step = 2 * std::numbers::pi * r / nv;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
      const double rr = r + roughness * step * rng.uniform(-1, 1);
      m.points.push_back(float((R + rr * std::cos(v)) * std::cos(u)),
                         float((R + rr * std::cos(v)) * std::sin(u)), float(rr * std::sin(v)));
    }
  auto id = [&](int i, int j) { return std::uint32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const std::uint32_t p = id(i, j), q = id(i + 1, j), s = id(i + 1, j + 1), t = id(i, j + 1);
      m.tris.insert(m.tris.end(), {p, q, s, p, s, t});
    }
  return m;
}

}  // namespace kdmesh::test
