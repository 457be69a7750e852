// kdmesh — sliver splits of the quality-improvement pass: a flat tet that flips and caps
// cannot remove gets a new interior node on its longest interior edge, moved off the sliver's
// plane (the smoothing then refines its position).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// Tet t's edges as (squared length, index into kTetEdge), longest first, ties by index: the
/// order in which both splits try them.
std::array<std::pair<double, int>, 6> edges_longest_first(const ImproveTets& m, std::uint32_t t);

/// Splits tet t's longest edge that is not on the boundary (both ends may be surface nodes):
/// every tet around the edge is cut in two through a new interior node, placed at the edge's
/// midpoint or moved off t's plane by up to 0.4 x the edge's length, wherever the worst new
/// tet is best. Refused (false, nothing changed) when every edge of t is on the boundary, the
/// ring is larger than max_ring, or no position gives valid tets (exactly positive, not flat,
/// and with a surface vertex the centroid strictly inside the solid,
/// ImproveTets::inside_ok) whose worst is better than the ring's worst before. The new node's id goes to
/// *node and the new tets to *created (if not null).
bool split_sliver(ImproveTets& m, std::uint32_t t, int max_ring, std::uint32_t* node = nullptr,
                  std::vector<std::uint32_t>* created = nullptr);

}  // namespace kdmesh
