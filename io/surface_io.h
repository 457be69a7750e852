// kdmesh — surface readers and writers: STL (ascii/binary) and PLY (ascii/binary LE/BE);
// OBJ and ascii OFF readers.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <array>
#include <cctype>
#include <string>
#include <string_view>

#include "core/surface_mesh.h"

namespace kdmesh {

/// The surface file extensions read_surface reads (lower case; matched case-insensitively), for
/// callers that check an input before reading it (the batch config).
inline constexpr std::array<std::string_view, 4> kSurfaceExtensions = {".stl", ".ply", ".obj", ".off"};

/// True if `ext` (with its dot, any case) is one of kSurfaceExtensions.
inline bool is_surface_extension(std::string_view ext) {
  return std::any_of(kSurfaceExtensions.begin(), kSurfaceExtensions.end(), [&](std::string_view e) {
    return e.size() == ext.size() && std::equal(e.begin(), e.end(), ext.begin(), [](char a, char b) {
             return a == std::tolower(static_cast<unsigned char>(b));
           });
  });
}

/// Reads an STL, PLY, OBJ or OFF surface (chosen by extension, case-insensitive; OpenMesh's
/// .om is refused with the reason, see surface_io.cpp). STL ascii vs binary is decided by the
/// size rule (84 + 50 * count == file size), never by the "solid" header. Polygons of PLY, OBJ
/// and OFF are triangulated in their plane (a convex one gives its fan from its first vertex).
/// Vertices with identical coordinates are welded into one point; facets keep the file's order
/// and orientation, degenerate, repeated and non-manifold ones included. No validation beyond
/// the file format (see prepare_surface).
/// Throws InputError (file, line or facet/byte offset, what is wrong).
SurfaceMesh read_surface(const std::string& path);
SurfaceMesh read_stl(const std::string& path);
SurfaceMesh read_ply(const std::string& path);
SurfaceMesh read_obj(const std::string& path);  ///< io/obj_reader.cpp
SurfaceMesh read_off(const std::string& path);  ///< io/off_reader.cpp

/// Writers (atomic: temp file + rename; OutputError on failure; UsageError for a mesh with
/// non-finite coordinates or out-of-range point ids). Binary STL stores float coordinates
/// (doubles are rounded); ascii STL and both PLY variants keep every double exactly.
/// write_ply(binary = true) writes binary_little_endian.
void write_stl(const SurfaceMesh& mesh, const std::string& path, bool binary = true);
void write_ply(const SurfaceMesh& mesh, const std::string& path, bool binary = true);

}  // namespace kdmesh
