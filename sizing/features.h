// kdmesh — sharp feature detection on a surface (edges and corners the mesh must keep).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// Feature edges of a surface, as surface point ids.
struct FeatureEdges {
  std::vector<std::uint32_t> edges;    ///< 2 per edge (a < b), sorted, unique
  std::vector<std::uint32_t> corners;  ///< points where != 2 feature edges meet (ends, junctions), sorted
  std::size_t num_edges() const { return edges.size() / 2; }
  /// True if (a, b), in either order, is a feature edge (binary search).
  bool has_edge(std::uint32_t a, std::uint32_t b) const {
    if (a > b) std::swap(a, b);
    std::size_t lo = 0, hi = edges.size() / 2;
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if (edges[2 * mid] < a || (edges[2 * mid] == a && edges[2 * mid + 1] < b)) lo = mid + 1;
      else hi = mid;
    }
    return lo < edges.size() / 2 && edges[2 * lo] == a && edges[2 * lo + 1] == b;
  }
};

/// Edges whose two facets' normals differ by >= angle_deg (dihedral deviation from flat), on
/// a closed 2-manifold surface, and the edges `also` lists (point id pairs: e.g. where an
/// interface between touching bodies meets the outer surface). angle_deg <= 0 or >= 180
/// selects no edges by angle. Also marks as corners the feature-edge end points and
/// junctions, and points where a feature polyline turns by more than angle_deg.
FeatureEdges detect_sharp_edges(const SurfaceMesh& surface, double angle_deg,
                                const std::vector<std::uint32_t>& also = {});

/// The smallest dihedral angle of the solid at an edge of its outward-oriented surface, in
/// degrees (90 for a box; a wedge's angle at its sharp edge; over 180 at a re-entrant edge),
/// over the edges shared by exactly two facets; 180 if there is none. No tet of a conforming
/// mesh can have a smaller largest-possible dihedral at that edge: the tets around it share
/// this angle.
double smallest_edge_angle(const SurfaceMesh& surface);

}  // namespace kdmesh
