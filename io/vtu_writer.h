// kdmesh — VTU (VTK XML unstructured grid) writer: raw appended, zlib blocks compressed on all cores.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/tet_mesh.h"

namespace kdmesh {

/// Writes `mesh` as binary, zlib-compressed VTU: points, VTK_TETRA cells, and every
/// mesh.point_data / mesh.cell_data array (Int32 or Float64); the bytes VTK's own XML writer
/// makes for the same arrays (raw appended, UInt64 headers, zlib level 1, 32 KiB blocks).
/// Atomic (temp file + rename).
/// Throws OutputError on failure, UsageError if a data array's length does not match.
void write_vtu(const TetMesh& mesh, const std::string& path);

}  // namespace kdmesh
