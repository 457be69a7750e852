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
};

/// Edge length / target size over the unique edges of `tets` (4 point ids each, into
/// `points`), the target taken at each edge's midpoint. All zero for no tets.
/// Throws UsageError if tets.size() is not a multiple of 4 or an id is out of range.
SizeFidelity measure_size_fidelity(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                   const SizingField& sizing);

}  // namespace kdmesh
