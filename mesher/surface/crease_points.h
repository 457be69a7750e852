// kdmesh — closest points on the creases (non-coplanar facet pairs) of a surface near given
// facets: where the volume mesher puts edge-kind Steiner points.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// Facet adjacency of a closed surface and its crease edges. Built once, const queries.
class CreaseFinder {
 public:
  explicit CreaseFinder(const SurfaceMesh& surface);

  /// Among the crease edges of `facets` (n ids; kNoFacet entries ignored) and of the facets
  /// adjacent to them, the point closest to q: written to out; returns false if there is none.
  /// A crease edge is one whose two facets are not coplanar (exact orient3d). *facet (if not
  /// null) receives one of the two facets of the chosen edge.
  bool closest_crease_point(const double* q, const std::uint32_t* facets, int n, double* out,
                            std::uint32_t* facet = nullptr) const;

  /// Edge j of facet f, from corner j to corner j+1: whether it is a crease, and the facet
  /// across it (kNoFacet on a boundary or non-manifold edge).
  bool is_crease(std::size_t f, int j) const { return crease_[3 * f + j] != 0; }
  std::uint32_t neighbour(std::size_t f, int j) const { return neighbour_[3 * f + j]; }

 private:
  const SurfaceMesh* surface_;
  std::vector<std::uint32_t> neighbour_;  ///< 3 per facet: facet across edge (t[j], t[j+1]), or kNoFacet
  std::vector<std::uint8_t> crease_;      ///< 3 per facet: that edge is a crease
};

}  // namespace kdmesh
