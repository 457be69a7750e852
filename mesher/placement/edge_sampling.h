// kdmesh — nodes on feature corners and along feature edges (part of node placement).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/surface_mesh.h"
#include "mesher/node_set.h"
#include "mesher/placement/spacing_grid.h"
#include "sizing/features.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// A feature polyline: surface point ids, consecutive ones joined by feature edges. Open
/// polylines run between corners; a closed loop (no corner on it) repeats its first point
/// at the end and starts at its smallest point id.
struct FeaturePolyline {
  std::vector<std::uint32_t> points;
  bool closed = false;
};

/// Chains `features` into polylines: one per run of feature edges between corners (in the
/// order of the smallest corner id, then edge order) and one per corner-free loop. A point
/// where != 2 feature edges meet is treated as a corner even when `features.corners` misses
/// it. Throws UsageError if an edge refers to a point id outside the surface.
std::vector<FeaturePolyline> chain_feature_edges(const SurfaceMesh& surface,
                                                 const FeatureEdges& features);

/// Appends to `nodes` and to `grid`: a corner node at every corner of `features` (facet = the
/// smallest incident facet), then along every polyline the nodes that split it into
/// n = max(1, round(I)) pieces of equal I/n, I = integral of ds / h(s) (the ends are corners,
/// or the loop start, which is added as an edge node). Edge nodes lie on the surface edge
/// segment that contains them (facet = its smallest incident facet). An edge node closer than
/// `beta` x (h_p + h_q) / 2 to a node already placed (a corner, or a node of an earlier
/// polyline) is left out: two curves that leave a corner at a small angle, or run side by side,
/// would otherwise get nodes a hundredth of h apart (homer.ply, femur.ply, lever.stl: tets
/// under 5 deg on such pairs). beta = 0 keeps every node.
///
/// If `segment_balls` is given, it receives the diametral ball of every segment between
/// consecutive nodes of a polyline: its midpoint, stored with h = the segment's length, so
/// that segment_balls->conflicts(p, 0, 1) says whether p is strictly inside one. A segment
/// whose ball holds no other node is an edge of every Delaunay tetrahedralization (Gabriel),
/// which is how the surface sampling keeps the feature curves in the mesh.
///
/// With `skip_placed_corners`, a corner at the place of a node already in `grid` (1e-9 of the
/// size apart) is not added again: the curves inside an assembly's interfaces end at corners of
/// the outer surface's curves, placed before them.
void place_edge_nodes(const SurfaceMesh& surface, const FeatureEdges& features,
                      const SizingField& sizing, double beta, SpacingGrid& grid, NodeSet& nodes,
                      SpacingGrid* segment_balls = nullptr, bool skip_placed_corners = false);

}  // namespace kdmesh
