// kdmesh — nodes on the surface facets, off the features (part of node placement).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>

#include "core/surface_mesh.h"
#include "mesher/node_set.h"
#include "mesher/spacing_grid.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct SurfaceSamplingOptions {
  std::uint64_t seed = 1;
  /// Spacing: a new node keeps |p - q| >= beta * (h_p + h_q) / 2 from every node in the grid.
  double beta = 0.8;
  /// Candidates tried around each accepted node before it is retired (Bridson's k).
  int tries = 24;
};

/// Variable-radius Poisson-disk sampling of the surface, in three passes:
///  1. creases (edges whose two facets are not coplanar, decided exactly): their surface
///     vertices, then points at about h steps along them (facet = the first facet of the edge);
///  2. each facet in id order with its own RNG stream (seed, facet): a few random darts, each
///     followed by Bridson's advancing step (candidates in the annulus [r, 2r] around accepted
///     nodes, r = beta h, in the facet's plane, kept when inside the facet);
///  3. within the same facet loop, a sweep over a grid of steps <= r/2 (edges and corners
///     included) so that the sampling is near-maximal even on thin facets.
/// A node is kept only if it keeps beta * (h_p + h_q) / 2 from every node in `grid` (corners,
/// edge nodes, earlier surface nodes). Each node is the barycentric combination u a + v b + w c
/// of its facet's corners (u, v, w >= 0, summing to 1 up to rounding). Appends to `nodes`
/// (kind surface) and to `grid`. `progress(fraction)` is called now and then (may be empty).
void place_surface_nodes(const SurfaceMesh& surface, const SizingField& sizing,
                         const SurfaceSamplingOptions& options, SpacingGrid& grid, NodeSet& nodes,
                         const std::function<void(double)>& progress = {});

}  // namespace kdmesh
