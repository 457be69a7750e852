// kdmesh — Gmsh MSH reader (4.1 and 2.x, ASCII and binary) into FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Reads a Gmsh MSH 4.1 or 2.x file (ASCII or binary, either byte order) with linear or
/// quadratic tetrahedra, triangles and lines; the inverse of write_msh:
///  - points are ordered by node tag (tags 1..n give point id = tag - 1);
///  - tets, faces and edges are ordered by element tag and converted to FeMesh's (VTK's) node
///    order; point elements (type 15) are ignored;
///  - entity id = elementary tag - 1 (tags must be >= 1);
///  - one FeGroup per physical group of dimension 1..3 that has elements, named from
///    $PhysicalNames (or "physical_<tag>" when unnamed), ordered by physical tag then dimension;
///    groups of dimension 0 are dropped;
///  - MSH 2.x: copies of an element (same type, elementary tag and nodes, written once per
///    physical group) are read as one element, the earliest tag's.
/// Throws InputError(path, line, what) for anything it cannot read: malformed or truncated
/// data, counts that exceed the file, unknown node tags, duplicate node tags, element types
/// other than 1, 2, 4, 8, 9, 11, 15, mixed element orders, MSH 4.0 or partitioned files. In
/// binary data the message gives the byte offset.
FeMesh read_msh(const std::string& path);

}  // namespace kdmesh
