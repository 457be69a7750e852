// kdmesh — how well a tet mesh's edge lengths follow the sizing field.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/point_set.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

struct SizeFidelity {
  std::size_t edges = 0;       ///< unique edges of the tets
  double mean_ratio = 0;       ///< mean over edges of length / h(edge midpoint)
  double in_range = 0;         ///< fraction of edges with ratio in [0.7, 1.4]
  double short_fraction = 0;   ///< fraction below 0.7
  double long_fraction = 0;    ///< fraction above 1.4
  double min_ratio = 0, max_ratio = 0;
  /// The edges away from every refinement: the field is its far size h_max (the user's size;
  /// SizingField::max_size) at both ends and at the midpoint, so no zone and no automatic term
  /// (curvature, thickness) shrinks it there. Their mean length / h_max is what "the mesh
  /// follows the size the user asked for" means; 0 edges when the refinement covers the part.
  std::size_t away_edges = 0;
  double away_mean_ratio = 0;
};

/// Edge length / target size over the unique edges of `tets` (4 point ids each, into
/// `points`), the target taken at each edge's midpoint; and the same over the edges away from
/// every refinement (away_edges, away_mean_ratio). All zero for no tets.
/// Throws UsageError if tets.size() is not a multiple of 4 or an id is out of range.
SizeFidelity measure_size_fidelity(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                   const SizingField& sizing);

}  // namespace kdmesh
