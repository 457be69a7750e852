// kdmesh — the automatic curvature terms of the sizing field: a size per curved surface edge.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/surface_mesh.h"
#include "sizing/segment_bvh.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// For every surface edge that is manifold, not a feature (deviation below
/// options.feature_angle_deg, when that is > 0) and bent (deviation > 0): the local radius of
/// curvature r = |c0 - c1| / deviation (c0, c1 the centroids of its two facets; exact on a
/// sphere of equilateral facets, 2/3 of the true radius on a cylinder of long strips, so on
/// the safe side), and the size
///   min(curvature_angle * r, sqrt(12 r chordal_deviation))   (each term only when its option is > 0),
/// clamped to [min_size, max_size]. Edges whose size is below max_size are appended to `out`
/// as segments weighted by that size; `stats` says how many and how small.
void add_curvature_sizes(const SurfaceMesh& surface, const SizingOptions& options, double min_size,
                         WeightedSegments& out, SizingAutoStats& stats);

}  // namespace kdmesh
