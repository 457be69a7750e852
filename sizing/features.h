// kdmesh — sharp feature detection on a surface (edges and corners the mesh must keep).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// Feature edges of a surface, as surface point ids.
struct FeatureEdges {
  std::vector<std::uint32_t> edges;    ///< 2 per edge (a < b), sorted, unique
  std::vector<std::uint32_t> corners;  ///< points where != 2 feature edges meet (ends, junctions), sorted
  std::size_t num_edges() const { return edges.size() / 2; }
};

/// Edges whose two facets' normals differ by >= angle_deg (dihedral deviation from flat), on
/// a closed 2-manifold surface. angle_deg <= 0 or >= 180 selects no edges. Also marks as
/// corners the feature-edge end points and junctions, and points where a feature polyline turns by
/// more than angle_deg.
FeatureEdges detect_sharp_edges(const SurfaceMesh& surface, double angle_deg);

}  // namespace kdmesh
