// kdmesh — VTU (VTK XML unstructured grid) writer, through VTK's own XML writer.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/tet_mesh.h"

namespace kdmesh {

/// Writes `mesh` as binary, zlib-compressed VTU: points, VTK_TETRA cells, and every
/// mesh.point_data / mesh.cell_data array (Int32 or Float64). Atomic (temp file + rename).
/// Throws OutputError on failure, UsageError if a data array's length does not match.
void write_vtu(const TetMesh& mesh, const std::string& path);

}  // namespace kdmesh
