// kdmesh — the edges of a triangle surface with their two facets and dihedral deviation
// (shared by sharp-feature detection and the curvature term of the sizing field).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// One edge of a surface: its end points (lo < hi), the facets on either side and the angle
/// between their outward normals (0 = flat, pi = folded back).
struct SurfaceEdge {
  std::uint32_t lo = 0, hi = 0;
  std::uint32_t f0 = kNoFacet, f1 = kNoFacet;  ///< f1 == kNoFacet: not shared by exactly two facets
  /// Radians in [0, pi]; for an edge that is not manifold (boundary, more than two facets) or
  /// where the two facets run it the same way (orientation flips), +infinity: such an edge is
  /// a feature at every angle.
  double deviation = 0;
  bool manifold() const { return f1 != kNoFacet; }
};

/// Every edge of `surface` once, sorted by (lo, hi). Facets with out-of-range ids are ignored;
/// a degenerate facet's collapsed edge is not an edge.
std::vector<SurfaceEdge> surface_edges(const SurfaceMesh& surface);

}  // namespace kdmesh
