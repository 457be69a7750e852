// kdmesh — point-set readers and writers (.xyz, TetGen .node, PLY vertices).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

#include "core/point_set.h"

namespace kdmesh {

/// Reads a point set, choosing the format by extension (.xyz, .node, .ply; case-insensitive).
/// Throws InputError (file, line, reason) on any malformed input; never returns partial data.
PointSet read_points(const std::string& path);

/// `.xyz`: "x y z" per line, whitespace separated; '#' starts a comment; blank lines ignored.
PointSet read_xyz(const std::string& path);
/// TetGen `.node`: header "<n> <dim=3> <#attr> <#bmarker>", then "<id> x y z [attrs] [marker]".
PointSet read_tetgen_node(const std::string& path);
/// PLY (ascii, binary_little_endian, binary_big_endian): the x, y, z properties of `vertex`.
PointSet read_ply_points(const std::string& path);

/// Writes `.xyz` with shortest round-trip digits (read_xyz(write_xyz(p)) == p bit for bit).
/// Atomic: written to a temporary file and renamed.
void write_xyz(const PointSet& points, const std::string& path);

}  // namespace kdmesh
