// kdmesh — node insertion of the quality-improvement pass: a sliver that no flip, cap removal
// or edge split can fix (typically a flat tet on two boundary faces folded along a feature
// edge, whose four vertices cannot move) is replaced, with its face neighbours, by a fan of
// tets around a new interior node placed where the fan's worst tet is best.
// (elephant.ply at diag/20: a 20 deg fold between two feature curves held an 11.1 deg cap;
// 18.5 deg after.)
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// Cavities tried in turn: tet t and its neighbours across its interior faces (all of t's
/// region); those and theirs; then the Delaunay cavities (the tets reachable from t whose
/// circumsphere holds the point, at most 64) of t's centroid and of points beneath t's
/// boundary faces (each face's centroid moved inward by 0.4 and 0.7 x its mean edge: a cap
/// folded along a feature edge wants a node beneath the fold). A new interior node x is joined
/// to every face of the cavity's boundary (its faces on the domain's boundary stay boundary
/// faces). x starts at the best of the seed point and the centroids of the cavity's vertices
/// and tets, and moves by a pattern search (26 directions, halving steps) that keeps the fan
/// valid (exactly positive, not flat, ImproveTets::inside_ok). A cavity is refused when one of
/// its vertices is on no face of its boundary (it would be lost), or the fan's worst tet
/// (tet_sine) is not better than the cavity's. Returns true (the new tets in *created, if not
/// null) at the first cavity accepted; false with nothing changed.
bool insert_in_cavity(ImproveTets& m, std::uint32_t t, std::vector<std::uint32_t>* created = nullptr);

}  // namespace kdmesh
