// kdmesh — boundary caps of the quality-improvement pass: a flat tet lying on the surface with
// two boundary faces is taken out of the domain, flipping the boundary edge between those
// faces, when the two faces it exposes lie on the surface within tolerance.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>

#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// Removes tet t if it is a cap: exactly two of its faces are boundary faces, its four
/// vertices are surface nodes (no interior node), the boundary edge the two faces share has a
/// surface-kind end or keeps_feature says it is no feature edge, the edge between its other two vertices is
/// not a boundary edge already (the boundary stays a 2-manifold), and both faces it exposes
/// face outward (against the normal of the closest facet) within ctx.max_distance of the
/// surface. Also removes a tet with three boundary faces whose apex (the vertex they share) is
/// a surface node in no other tet, when the face it exposes lies on the surface likewise; the
/// apex is then unused (write_back drops it). Returns true if it removed t.
bool remove_cap(ImproveTets& m, std::uint32_t t, const BoundaryContext& ctx);

}  // namespace kdmesh
