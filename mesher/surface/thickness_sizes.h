// kdmesh — the automatic local-feature-size term of the sizing field: walls thinner, and gaps
// narrower, than the size asked for (pipeline stage: PreparedSurface -> weighted segments).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>

#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "sizing/segment_bvh.h"

namespace kdmesh {

struct ThicknessOptions {
  double layers = 2;       ///< tets across a wall: size <= thickness / layers (0 = off)
  double gap_layers = 1;   ///< boundary nodes across a gap: size <= gap / gap_layers (0 = off)
  double max_size = 0;     ///< only sizes below this are kept (> 0)
};

struct ThicknessStats {
  std::size_t walls = 0, gaps = 0;  ///< facets whose wall / gap gives a size below max_size
  double min_wall = 0, min_gap = 0; ///< thinnest wall and narrowest gap found (0 = none)
};

/// From each facet's centroid, a ray inward (against its outward normal) to the first other
/// facet: the wall's thickness t there; and one outward: the gap g to the next facet. Each
/// gives a segment from the centroid to the hit point sized t / layers (g / gap_layers),
/// appended to `out` when below max_size. Deterministic; runs on all cores.
ThicknessStats add_thickness_sizes(const PreparedSurface& surface, const SurfaceQuery& query,
                                   const ThicknessOptions& options, WeightedSegments& out);

}  // namespace kdmesh
