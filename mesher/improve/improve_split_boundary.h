// kdmesh — boundary-edge splits of the quality-improvement pass: a sliver next to a long
// boundary edge (a chord the Delaunay tets drew over nearly coplanar surface nodes) gets a new
// surface node on that edge, at the surface point closest to its midpoint.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// Splits the boundary edge (a, b) of tet t: every tet of its open ring is cut in two through
/// a new surface node x, the point of the input surface closest to the edge's midpoint (for a
/// feature edge the mesh keeps, keeps_feature: an edge node, the midpoint's closest point on
/// the input's feature edge, point_on_feature), and the edge's two boundary faces become four.
/// Refused (false, nothing changed) when a or b is interior, the edge is shorter than
/// the size at x, x is farther from the midpoint than a quarter of the edge (another sheet of
/// the surface), the ring is longer than max_ring, a new tet is not valid (exactly positive,
/// not flat, ImproveTets::inside_ok), a new boundary face is not on the surface
/// (face_on_surface), or the ring's worst tet (tet_sine) does not get better. The new tets go
/// to *created (if not null).
bool split_boundary_edge(ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                         int max_ring, const BoundaryContext& ctx,
                         std::vector<std::uint32_t>* created = nullptr);

}  // namespace kdmesh
