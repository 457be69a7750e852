// kdmesh — Gmsh MSH writer (format 4.1 or 2.2, ASCII or binary) for FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

struct MshOptions {
  int version = 41;     ///< 41 (MSH 4.1) or 22 (MSH 2.2)
  bool binary = false;  ///< binary instead of ASCII (native byte order, 8-byte size_t)
  /// MSH 4.1: also write the elements of entities in no group (Gmsh's Mesh.SaveAll = 1).
  bool save_all = false;
};

/// Writes `mesh` as a Gmsh MSH file, atomically (temporary file + rename).
///
/// Numbering (all 1-based, as Gmsh requires):
///  - node tag = point id + 1;
///  - element tags: tets 1..T in mesh order, then faces T+1..T+F, then edges;
///  - elementary entity tag = entity id + 1 (volumes from tet_entity, surfaces from face_entity,
///    curves from edge_entity);
///  - physical tag = position in mesh.groups + 1 (unique over all dimensions); $PhysicalNames
///    names every group.
/// Element types: tet4 = 4, tet10 = 11, tri3 = 2, tri6 = 9, line2 = 1, line3 = 8. Node order
/// is converted from FeMesh's (VTK's) to Gmsh's: they differ only in tet10, whose last two
/// mid-edge nodes Gmsh takes as edges (2,3) then (1,3) where VTK has (1,3) then (2,3).
///
/// MSH 4.1: $Entities lists every volume, surface and curve with its bounding box (over its
/// elements' nodes) and physical tags, no bounding entities and no point entities. Each node
/// is written in the $Nodes block of exactly one entity: the curve of an edge using it if any,
/// else the surface of a face using it, else the volume of a tet (lowest entity id first);
/// points used by no element go to the first volume (else surface, else curve).
/// Elements of MSH 4.1: when the mesh has groups, only the elements of entities that belong to
/// a group of their dimension are written, unless options.save_all (Gmsh does the same by
/// default; meshio 5 cannot read a 4.1 file mixing element blocks with and without physical
/// tags). Element tags keep their numbering, so they may have gaps; $Entities and $Nodes still
/// list every entity and every point.
/// MSH 2.2: physical and elementary tags per element; as Gmsh itself does, an element whose
/// entity belongs to k > 1 groups is written k times (once per physical tag; the copies get
/// tags after all others), and an element of an entity in no group once with physical 0.
/// Gmsh 4.8 and meshio 5 read such copies as distinct elements (so would a solver): for a
/// solver, write 2.2 only with groups that share no entity of their dimension, or use 4.1.
/// read_msh merges the copies again.
///
/// Throws UsageError for an invalid mesh (see index_fe_mesh), a version other than 41 / 22, an
/// entity id above 2^31 - 2 (Gmsh tags are ints) or points without any element to hold them;
/// OutputError if the file cannot be written.
void write_msh(const FeMesh& mesh, const std::string& path, MshOptions options = {});

}  // namespace kdmesh
