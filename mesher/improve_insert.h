// kdmesh — node insertion of the quality-improvement pass: a sliver that no flip, cap removal
// or edge split can fix (typically a flat tet on two boundary faces folded along a feature
// edge, whose four vertices cannot move) is replaced, with its face neighbours, by a fan of
// tets around a new interior node placed where the fan's worst tet is best.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "mesher/improve_tets.h"

namespace kdmesh {

/// The cavity is tet t and its neighbours across its interior faces (all of t's region). A new
/// interior node x is joined to every face of the cavity's boundary (its boundary faces on the
/// domain's boundary stay boundary faces). x starts at the best of a few candidates (the
/// centroids of t, of the cavity's vertices and of each cavity tet) and moves by a compass
/// search that keeps the fan valid (exactly positive, not flat, ImproveTets::inside_ok). Refused
/// (false, nothing changed) when a cavity vertex is on no boundary face of the cavity (it would
/// be lost), no candidate gives a valid fan, or the fan's worst tet (tet_sine) is not better
/// than the cavity's. The new tets go to *created (if not null).
bool insert_in_cavity(ImproveTets& m, std::uint32_t t, std::vector<std::uint32_t>* created = nullptr);

}  // namespace kdmesh
