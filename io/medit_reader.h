// kdmesh — MEDIT / Gamma Mesh Format (.mesh, ASCII) reader into FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Reads an ASCII MEDIT .mesh file with Vertices and Tetrahedra / Triangles / Edges (or their
/// P2 variants, all of one order): the inverse of write_medit. Points and elements keep file
/// order; entity id = element ref - 1 (refs must be >= 1); P2 nodes are taken in write_medit's
/// order; groups come from "# kdmesh-group" comment lines (other comments are ignored).
/// Corners, Ridges, Required*, Normals, Tangents, NormalAtVertices and TangentAtVertices
/// sections are skipped; anything after End is ignored.
/// Throws InputError(path, line, what) on malformed or truncated data, counts that exceed the
/// file, vertex indices out of range, Dimension other than 3, other element kinds
/// (quadrilaterals, hexahedra, ...), unknown keywords and mixed orders.
FeMesh read_medit(const std::string& path);

}  // namespace kdmesh
