// kdmesh — node placement (pipeline stage: PreparedSurface + SizingField -> NodeSet).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "mesher/node_set.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "sizing/features.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct PlacementOptions {
  std::uint64_t seed = 1;  ///< every random choice derives from it: same seed, same nodes
  /// Interior nodes keep at least this many local sizes h(x) away from the surface, so that
  /// the surface triangles stay Delaunay (no interior node inside their diametral balls).
  double interior_clearance = 0.8;
  /// Progress: stage name ("edges", "surface", "interior") and fraction done.
  std::function<void(const std::string&, double)> progress;
};

/// Places nodes spaced as `sizing` asks: feature corners, then nodes along feature edges,
/// then on the surface facets, then in the interior. Every surface node lies exactly on its
/// facet (up to rounding of its coordinates); interior nodes are strictly inside the solid.
/// Deterministic for equal inputs and seed.
NodeSet place_nodes(const PreparedSurface& surface, const SurfaceQuery& query,
                    const FeatureEdges& features, const SizingField& sizing,
                    const PlacementOptions& options = {});

}  // namespace kdmesh
