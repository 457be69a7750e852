// kdmesh — reference Delaunay tetrahedralizations (TetGen 1.5, CGAL 5.5) behind plain types.
// The third-party types stay in the .cpp adapters.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/ordering.h"
#include "core/point_set.h"

namespace kdmesh {

struct ReferenceResult {
  std::vector<std::uint32_t> tets;  ///< 4 point ids per finite tet, positively oriented
  std::size_t num_vertices = 0;     ///< distinct vertices actually in the triangulation
  double seconds = 0;               ///< time of the triangulation call itself
};

/// TetGen 1.5 (library) Delaunay tetrahedralization of the points ("Q" only, no refinement).
/// Duplicate points are merged by TetGen; tets refer to the first of each duplicate group
/// in input order.
ReferenceResult tetgen_delaunay(const PointSet& points);

/// CGAL Delaunay_triangulation_3 (Epick). With `order`: inserts one point at a time in that
/// order, each located from the vertex of its hint. Without: CGAL's own insert(first, last)
/// (spatial sort). Duplicates map to the first-inserted copy.
ReferenceResult cgal_delaunay(const PointSet& points, const Ordering* order);

/// Volume of the convex hull of `points`, from CGAL::convex_hull_3 (exact predicates),
/// independent of any tetrahedralization. 0 for fewer than 4 non-coplanar points.
double convex_hull_volume(const PointSet& points);

}  // namespace kdmesh
