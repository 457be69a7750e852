// kdmesh — a surface with internal walls (non-manifold only where a wall meets the outside or
// other walls) split into the closed surfaces of its cells, one region each (pipeline stage:
// SurfaceMesh -> bodies, before mesher/surface/surface_bodies.h joins them).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// True if an edge of `mesh` (by point ids) has more than two facets.
bool has_nonmanifold_edges(const SurfaceMesh& mesh);

/// The cells of a surface whose non-manifold edges are where internal walls meet: around every
/// edge the facets are ordered by angle (exact predicates), and the two sides of each facet are
/// linked to the facing sides of its angular neighbours; each class of linked sides bounds one
/// region of space. The bounded ones (positive volume) are the cells: each is returned as a
/// closed surface oriented outward (its own points), in the order of their smallest facet id.
/// A wall facet is in two cells, once each way; a wall written twice (the same corners, facing
/// opposite ways: two touching parts exported into one file) counts once. Throws SurfaceError
/// (naming `source` and facets) for duplicated facets facing the same way (Defect::duplicates),
/// when two facets overlap around an edge, when a facet has the same cell on both sides (a
/// dangling fin), or when a cell holds another cell or a void (nested cells are not supported
/// here: list such parts as separate bodies). Facet ids in messages are the input's.
std::vector<SurfaceMesh> split_cells(const SurfaceMesh& mesh, const std::string& source);

}  // namespace kdmesh
