// kdmesh — what the quality-improvement pass must respect when it changes the boundary: faces
// it creates or moves lie on the surface within tolerance and face outward, and edges that run
// along a feature edge stay. Shared by the boundary caps and the sliding of surface nodes.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once

#include <cstdint>

#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "sizing/features.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct BoundaryContext {
  const PreparedSurface* surface = nullptr;
  const SurfaceQuery* query = nullptr;
  const SizingField* sizing = nullptr;
  /// A changed boundary face must lie within this many local sizes of the surface (at the 7
  /// points the mesh check samples, and its formula h(centroid)).
  double max_distance = 0.08;
  /// The surface's feature edges (the mesh keeps them). Null: unknown.
  const FeatureEdges* features = nullptr;
};

/// The face (a, b, c) (its corners on the surface), oriented outward of the domain, lies on
/// the surface: within
/// ctx.max_distance x h(centroid) at the mesh check's 7 sample points, and facing the way the
/// closest facet to its centroid faces.
bool face_on_surface(const double* a, const double* b, const double* c, const BoundaryContext& ctx);

/// True if the mesh edge (a, b) may run along a feature edge: its midpoint lies within 5% of
/// its length of a feature edge of the facet closest to the midpoint (or no features known).
bool along_feature(const double* a, const double* b, const BoundaryContext& ctx);

/// The test of along_feature with features known: when the midpoint of (a, b) lies within 5%
/// of |ab| of a feature edge of the facet closest to it, true, with x the midpoint's closest
/// point on that feature edge. *facet gets the closest facet (kNoFacet: none found).
bool point_on_feature(const double* a, const double* b, const BoundaryContext& ctx, double* x,
                      std::uint32_t* facet);

class ImproveTets;

/// True if the mesh edge (a, b) of m is a feature edge the pass must keep: along_feature holds
/// and the edge is no chord of the feature curve. A chord skips feature nodes: a feature node
/// c, a mesh neighbour of a or b, lies within 5% of |ab| of the segment strictly between its
/// ends, and (a, c) or (c, b) runs along a feature. The curve keeps its nodes and its shorter
/// edges when such a chord goes (helmet.ply at diag/40: a boundary face spanning 17 rim nodes
/// of a flat bottom face sat under a stack of 0.01 deg tets).
bool keeps_feature(const ImproveTets& m, std::uint32_t a, std::uint32_t b, const BoundaryContext& ctx);

}  // namespace kdmesh
