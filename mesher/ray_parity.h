// kdmesh — inside/outside of a closed triangle surface by the parity of a segment's crossings,
// decided by exact predicates only, at any magnitude (internal: CGAL types; included by the
// adapters surface_query.cpp and surface_prepare.cpp only).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <vector>

namespace kdmesh::ray_parity {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

/// +1 strictly inside the closed surface held by `tree` (nested shells: odd parity), -1
/// strictly outside, 0 on a facet (closed).
///
/// Why not CGAL's Point_inside_vertical_ray_cast (used up to issue 19): its rays are
/// p + (0, 0, +-1) and, where that ray grazes an edge, p + a random unit vector, and CGAL's
/// ray-triangle test then builds a + (q - p) at a facet vertex a
/// (Intersections_3/internal/Ray_3_Triangle_3_do_intersect.h:231) in double precision. A
/// direction of absolute length 1 is rounded to ulp(|x|) = 2^(e-52) there: from |x| = 2^52
/// (ulp 1, a half-unit step ties back to a) the direction is lost, a crossing missed and the
/// side wrong (a cube of side 2^52 answered "outside" at its centre), and from 2^53 even the
/// vertical ray is degenerate (z + 1 == z). Here the segment runs from p to a point q beyond
/// the bounding box, q is never derived from a unit vector, and every decision is an exact
/// orientation sign of the input doubles p, q and the facet vertices, so the answer is exact
/// and the same at every scale.
int side(const Tree& tree, const double* p);

}  // namespace kdmesh::ray_parity
