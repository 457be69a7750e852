// kdmesh — boundary VTU writer: FeMesh faces and feature edges with per-group cell data.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

/// Writes the boundary of `mesh` (its faces and feature edges, not its tets) as binary,
/// zlib-compressed VTU through VTK's XML writer, atomically (temporary file + rename):
///  - points: only the points used by a face or an edge, in ascending FeMesh point id; point
///    data `node_id` (UInt32) holds that id (0-based: the volume VTU's point index for the
///    corner nodes, the MSH node tag - 1, the INP node number - 1);
///  - cells: every face in mesh order (cell f = face f), then every edge (cell F + e = edge e,
///    F = num_faces()): VTK_TRIANGLE / VTK_LINE for order 1, VTK_QUADRATIC_TRIANGLE /
///    VTK_QUADRATIC_EDGE for order 2. FeMesh's node order is VTK's for both (corners, then the
///    mid-edge nodes of (0,1) (1,2) (2,0); ends, then the middle node), so nodes are copied as
///    they are;
///  - cell data `dim` (Int8: 2 for faces, 1 for edges) and `entity` (UInt32: face_entity /
///    edge_entity, the patch or curve id);
///  - one Int8 cell-data array per group of dim 2 or 1 (mesh order), 1 on the elements of its
///    dimension whose entity it lists and 0 elsewhere (a face may be in several groups). The
///    array is named after the group, or "<name>.d<dim>" when the name is "dim", "entity", or
///    also the name of a group of the other dimension (group names cannot contain '.');
///  - field data: per such array, an Int32 array of the same name holding {physical tag, dim},
///    the physical tag being the group's position in mesh.groups + 1 as in write_msh (this is
///    meshio's field_data convention for Gmsh files). Groups of dim 3 are not written.
/// Memory: about (faces + edges) bytes per written group besides the geometry.
///
/// Throws UsageError for an invalid mesh (see index_fe_mesh, io/fe_mesh_index.h) or one with
/// neither faces nor edges; OutputError if VTK cannot encode it or the file cannot be written.
/// Nothing is left at `path` (nor a temporary beside it) when it throws.
void write_boundary_vtu(const FeMesh& mesh, const std::string& path);

}  // namespace kdmesh
