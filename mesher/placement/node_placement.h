// kdmesh — node placement (pipeline stage: PreparedSurface + SizingField -> NodeSet).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "mesher/node_set.h"
#include "mesher/domain.h"
#include "sizing/features.h"

namespace kdmesh {

struct PlacementOptions {
  std::uint64_t seed = 1;  ///< every random choice derives from it: same seed, same nodes
  /// Interior nodes keep at least this many local sizes h(x) away from the surface, so that
  /// the surface triangles stay Delaunay (no interior node inside their diametral balls).
  double interior_clearance = 0.8;
  /// Touching bodies: interface edges bent by this many degrees or more are feature curves
  /// (mesher/surface/surface_bodies.h, interface_inner_edges); 0 = only where interfaces meet
  /// or end.
  double interface_feature_angle = 0;
  /// Progress: stage name ("edges", "surface", "interior") and fraction done.
  std::function<void(const std::string&, double)> progress;
};

/// What place_nodes measured.
struct PlacementStats {
  double interface_seconds = 0;  ///< touching bodies: sampling the interfaces, the fill's combined surface
};

/// Places nodes spaced as `domain.sizing` asks: feature corners, then nodes along feature edges,
/// then on the surface facets, then in the interior. Every surface node lies exactly on its
/// facet (up to rounding of its coordinates); interior nodes are strictly inside the solid.
/// Deterministic for equal inputs and seed.
NodeSet place_nodes(const Domain& domain, const FeatureEdges& features,
                    const PlacementOptions& options = {}, PlacementStats* stats = nullptr);

}  // namespace kdmesh
