// kdmesh — MEDIT / Gamma Mesh Format (.mesh, ASCII) writer for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Writes `mesh` as an ASCII MEDIT file (libMeshb "GMF"), atomically:
///   MeshVersionFormatted 2 (double precision), Dimension 3,
///   Vertices       x y z 0                       (vertex v = point id + 1)
///   Tetrahedra     v1..v4  ref   | TetrahedraP2  v1..v10 ref   (order 2)
///   Triangles      v1..v3  ref   | TrianglesP2   v1..v6  ref
///   Edges          v1 v2   ref   | EdgesP2       v1..v3  ref
///   End
/// Element refs are entity id + 1 (tet_entity, face_entity, edge_entity), as Gmsh writes its
/// elementary tags; so ref 0, which MEDIT tools read as "no reference", is never used.
/// P2 node order is FeMesh's (VTK's): corners, then the mid-edge nodes of (1,2) (2,3) (3,1)
/// (1,4) (2,4) (3,4) for tets, (1,2) (2,3) (3,1) for triangles. The format fixes no P2 order
/// (libMeshb leaves it to optional *P2Ordering sections, not written); this is the order
/// Gmsh's MEDIT writer uses for tet10 (it swaps its own last two mid-edge nodes on output).
/// MEDIT has no named sets: groups are written as comment lines
///   # kdmesh-group <dim> <name> <ref> <ref> ...
/// (one group may span several lines) that other readers skip and read_medit reads back.
/// Throws UsageError for an invalid mesh (see index_fe_mesh) or an entity id above 2^31 - 2
/// (refs are ints); OutputError if the file cannot be written.
void write_medit(const FeMesh& mesh, const std::string& path);

}  // namespace kdmesh
