// kdmesh — the parts of the flip stage's parallel phase: the mesh's vertices split into parts
// by a few median cuts, and the vertices whose whole star lies in their part (part of
// mesher/improve/flip_pass.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// No part: a vertex with a tet of its star reaching into another part.
inline constexpr std::uint8_t kNoPart = 0xFF;

struct FlipParts {
  unsigned count = 0;  ///< parts: 2^levels
  /// Per vertex: its part when every tet holding it has its four vertices in that part (the
  /// vertex is "deep" there), else kNoPart.
  std::vector<std::uint8_t> deep;
  /// The tet's four vertices are deep in part p. Every tet its flips read (the stars of its
  /// vertices) then has its four vertices in p, and so do the tets those flips make.
  bool holds(std::uint32_t p, const std::uint32_t* v) const {
    return deep[v[0]] == p && deep[v[1]] == p && deep[v[2]] == p && deep[v[3]] == p;
  }
};

/// Splits the vertices of m into 2^levels parts (levels <= 7): the positions of the first
/// vertices of the tets `seeds` cut at their median across their widest extent, then each half
/// likewise, `levels` deep; every vertex goes to the part its position falls in. Then marks
/// the deep vertices (one pass over the tets, on up to `threads` threads). The result depends
/// only on m and `seeds` (in their order).
FlipParts flip_parts(const ImproveTets& m, const std::vector<std::uint32_t>& seeds, unsigned levels,
                     unsigned threads);

}  // namespace kdmesh
