// kdmesh — the domain the stages after sizing work on: the prepared surface, its queries and
// the sizing field, bundled (placement, resource estimate, volume mesh, improvement, check).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once

#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// What to mesh, and how fine: the prepared surface (facets, bodies, volumes), the queries
/// built on it (closest point, inside, facet lookup) and the sizing field h(x). A view: it
/// owns none of the three, which must outlive it. Built in place at the call,
/// `place_nodes({surface, query, sizing}, features)`, or kept by a caller that runs several
/// stages on the same domain.
struct Domain {
  const PreparedSurface& surface;
  const SurfaceQuery& query;
  const SizingField& sizing;
  /// Touching bodies (surface.interfaces not empty): which body holds a point, and the
  /// interfaces between them. Null otherwise.
  const RegionQuery* regions = nullptr;
};

}  // namespace kdmesh
