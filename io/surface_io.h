// kdmesh — surface readers and writers: STL (ascii/binary) and PLY (ascii/binary LE/BE).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/surface_mesh.h"

namespace kdmesh {

/// Reads an STL or PLY surface (chosen by extension, case-insensitive). STL ascii vs binary
/// is decided by the size rule (84 + 50 * count == file size), never by the "solid" header.
/// Vertices with identical coordinates are welded into one point; facets keep the file's
/// order and orientation. No validation beyond the file format (see prepare_surface).
/// Throws InputError (file, line or facet/byte offset, what is wrong).
SurfaceMesh read_surface(const std::string& path);
SurfaceMesh read_stl(const std::string& path);
SurfaceMesh read_ply(const std::string& path);

/// Writers (atomic: temp file + rename; OutputError on failure; UsageError for a mesh with
/// non-finite coordinates or out-of-range point ids). Binary STL stores float coordinates
/// (doubles are rounded); ascii STL and both PLY variants keep every double exactly.
/// write_ply(binary = true) writes binary_little_endian.
void write_stl(const SurfaceMesh& mesh, const std::string& path, bool binary = true);
void write_ply(const SurfaceMesh& mesh, const std::string& path, bool binary = true);

}  // namespace kdmesh
