// kdmesh — nodes on the surface facets, off the features (part of node placement).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>

#include "core/surface_mesh.h"
#include "mesher/node_set.h"
#include "mesher/placement/spacing_grid.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct SurfaceSamplingOptions {
  std::uint64_t seed = 1;
  /// Spacing: a new node keeps |p - q| >= beta * (h_p + h_q) / 2 from every node in the grid.
  double beta = 0.8;
  /// Candidates tried around each accepted node before it is retired (Bridson's k).
  int tries = 24;
};

/// The sweep's work, for tests and benchmarks: pieces swept and points tried.
struct SurfaceSamplingStats {
  std::size_t sweep_pieces = 0;
  std::size_t sweep_points = 0;
};

/// Variable-radius Poisson-disk sampling of the surface, in three passes:
///  1. creases (edges whose two facets are not coplanar, decided exactly): their surface
///     vertices, then points at about h steps along them (facet = the first facet of the edge);
///  2. each facet in id order with its own RNG stream (seed, facet): a few random darts, each
///     followed by Bridson's advancing step (candidates in the annulus [r, 2r] around accepted
///     nodes, r = beta h, in the facet's plane, kept when inside the facet);
///  3. within the same facet loop, a sweep: the facet is bisected (longest edge) into pieces
///     small against h, each swept by rows of points <= r/2 apart (edges and corners
///     included), so that the sampling is near-maximal even on thin facets. Its work is
///     proportional to the facet's area / r^2 plus its length / r.
/// A node is kept only if it keeps beta * (h_p + h_q) / 2 from every node in `grid` (corners,
/// edge nodes, earlier surface nodes). Each node is the barycentric combination u a + v b + w c
/// of its facet's corners (u, v, w >= 0, summing to 1 up to rounding). Appends to `nodes`
/// (kind surface) and to `grid`. `progress(fraction)` is called now and then (may be empty).
/// If `feature_balls` is given (place_edge_nodes' segment_balls), no node is placed strictly
/// inside the diametral ball of a segment between consecutive feature-curve nodes, so that
/// every such segment stays an edge of the Delaunay tetrahedralization. (The spacing alone
/// does not ensure it: beta = 0.7 < 1/sqrt(2) leaves a shell of each ball near the segment's
/// midpoint outside both end nodes' spacing, and a node there took the gear box's feature edge
/// out of the mesh.)
SurfaceSamplingStats place_surface_nodes(const SurfaceMesh& surface, const SizingField& sizing,
                                         const SurfaceSamplingOptions& options, SpacingGrid& grid,
                                         NodeSet& nodes, const std::function<void(double)>& progress = {},
                                         const SpacingGrid* feature_balls = nullptr);

}  // namespace kdmesh
