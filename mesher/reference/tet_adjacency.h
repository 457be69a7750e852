// kdmesh — rebuild a closed Triangulation (adjacency + infinite tets) from a list of finite
// tets, so that any kernel's output (CGAL, TetGen, a file) can go through the exact checker.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "core/tet_mesh.h"

namespace kdmesh {

/// `tets`: 4 point ids per positively oriented finite tet. Each hull face gets an infinite tet.
/// Throws CheckError if a face is shared by more than two tets or the hull is not closed.
Triangulation triangulation_from_tets(const std::vector<std::uint32_t>& tets);

}  // namespace kdmesh
