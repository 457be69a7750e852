// kdmesh — the automatic curvature terms of the sizing field: a size per curved surface edge.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/surface_mesh.h"
#include "sizing/segment_bvh.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// Sizes from the curvature of the smooth (non-feature) surface, appended to `out` where
/// below max_size; `stats` says how many and how small. A radius of curvature r asks for
///   min(curvature_angle * r, max(sqrt(12 r chordal_deviation), d))   (each term only when its
///   option is > 0; below the facets' own spacing d a smaller size follows them no better),
/// clamped to [min_size, max_size]. r is measured scale by scale: on cubic cells of edge
/// max_size, then halved, from the mean normals of neighbouring cells; where the size r asks
/// for is at least the cell's edge, a point of that size is emitted and the cell's facets are
/// done (a scan's roughness averages out in a cell). Features, thin walls, strong curvature
/// and facets larger than the cells go on to finer cells, and what is left below the facets'
/// scale is measured per surface edge: r = d / deviation, d the distance across the edge
/// between its two facets' centroids (exact on a sphere of equilateral facets, 2/3 of the true
/// radius on a cylinder of long strips, so on the safe side), emitted as the edge itself.
void add_curvature_sizes(const SurfaceMesh& surface, const SizingOptions& options, double min_size,
                         WeightedSegments& out, SizingAutoStats& stats);

}  // namespace kdmesh
