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

/// All results use canonical ids (canonical_point_ids: the smallest id of each group of
/// identical points) and positively oriented tets.
///
/// TetGen 1.5 (library) Delaunay tetrahedralization of the points (switches "zQJF": no
/// refinement, input numbering kept). Debian's TetGen 1.5.0 cannot fail cleanly (it aborts or
/// crashes the process), so input it would reject is refused here first with GeometryError:
/// fewer than 4 points, non-finite coordinates, all points coplanar, or a set flatter than
/// TetGen's internal tolerance (relative thickness below ~1e-7 of the bounding-box diagonal).
ReferenceResult tetgen_delaunay(const PointSet& points);

/// CGAL Delaunay_triangulation_3 (Epick). With `order`: inserts one point at a time in that
/// order, each located from the vertex of its hint. Without: CGAL's own insert(first, last)
/// (spatial sort). Throws GeometryError when the points span no volume, UsageError for an
/// ordering that is not a permutation.
ReferenceResult cgal_delaunay(const PointSet& points, const Ordering* order);

/// Volume of the convex hull of `points`, from CGAL::convex_hull_3 (exact predicates),
/// independent of any tetrahedralization. 0 for fewer than 4 non-coplanar points.
double convex_hull_volume(const PointSet& points);

}  // namespace kdmesh
