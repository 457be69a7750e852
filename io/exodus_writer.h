// kdmesh — Exodus II writer for FeMesh (MOOSE and other Sandia-lineage codes, ParaView).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Writes `mesh` as an Exodus II file (netCDF classic 64-bit offset, 32-bit integers, double
/// coordinates), through the Exodus C API (VTK's build of SEACAS exodus 8.11), atomically
/// (temporary file + rename; only a regular file is ever replaced). Contents:
///  - title "kdmesh", 3 dimensions, coordinate names x y z; node n = point id + 1.
///  - One element block per region (distinct tet_entity value), in ascending region id:
///    block id = region id + 1, type TETRA (4 nodes; the manual's name, which every reader
///    takes; meshio 5 rejects "TETRA4") or TETRA10 (order 2). Elements are
///    numbered 1.. block after block, each block's tets in mesh order; the element number map
///    (the element id map, elem_num_map) gives each element's tet index + 1, i.e. kdmesh's own tet numbering.
///    Block name: the name of the first group of dim 3 whose entities are exactly that region,
///    else "region_<id>".
///  - One side set per group of dim 2: id = position in mesh.groups + 1 (the MSH physical tag),
///    named after the group; one (element, side) pair per face of the group's patches, in
///    ascending face index; no distribution factors. A face shared by two tets (an interface)
///    is given on the tet its normal points out of (as the INP writer's *SURFACE).
///  - One node set per group (every dimension, as the INP writer's NSETs): id = position in
///    mesh.groups + 1, named after the group, its nodes ascending (for order 2 the mid-edge
///    nodes of its elements too).
///
/// Node order: Exodus TETRA10 is corners 1-4, then the mid-edge nodes of (1,2) (2,3) (3,1)
/// (1,4) (2,4) (3,4) (Exodus II manual, "element types"): FeMesh's (VTK's) order, written as
/// is, unlike Gmsh's tet10.
/// Side numbers of a tet (Exodus II manual; 1-based corners, each listed counterclockwise seen
/// from outside):  side 1 = (1,2,4)   side 2 = (2,3,4)   side 3 = (1,4,3)   side 4 = (1,3,2)
/// i.e. side s is the face opposite corner 3, 1, 2, 4 for s = 1..4. That is VTK's vtkTetra
/// face order (faces 0..3 = (0,1,3) (1,2,3) (2,0,3) (0,2,1)) plus one, and not Abaqus's:
/// Exodus side = Abaqus label S1..S4 -> 4, 1, 2, 3.
///
/// Throws UsageError for an invalid mesh (see index_fe_mesh), a count or id beyond 32-bit
/// Exodus integers, or a group face that is not a face of any tet; OutputError naming `path`
/// if the file cannot be written.
void write_exodus(const FeMesh& mesh, const std::string& path);

/// Exodus side number (1..4) of the tet face with corners {a, b, c} among the tet's corners
/// `tet[0..3]`, or 0 if the three are not all corners of it.
int exodus_side_number(const std::uint32_t* tet, std::uint32_t a, std::uint32_t b, std::uint32_t c);

}  // namespace kdmesh
