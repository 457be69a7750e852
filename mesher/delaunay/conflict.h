// kdmesh — the Bowyer–Watson conflict test, shared by the kernel and the validity checker.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>

#include "core/tet_mesh.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

/// Is point p (not a vertex of tet t) in conflict with tet t of a triangulation whose tet
/// records (8 uint32 per tet: 4 vertices, 4 face references) are `T` (see Triangulation)? Finite tet: p strictly inside the circumsphere (perturbed, never a
/// tie). Infinite tet: p strictly beyond its hull face, or in the plane of that face and inside
/// its circumcircle (perturbed). `xyz` holds 3 coordinates per point id.
inline bool tet_in_conflict(const double* xyz, const std::uint32_t* T, std::uint32_t t,
                            const double* p) {
  auto P = [xyz](std::uint32_t id) { return xyz + 3 * std::size_t(id); };
  const std::uint32_t* v = T + 8 * std::size_t(t);
  int inf = -1;
  for (int i = 0; i < 4; ++i)
    if (v[i] == kInfiniteVertex) inf = i;
  if (inf < 0) return pred::insphere_perturbed(P(v[0]), P(v[1]), P(v[2]), P(v[3]), p) > 0;
  const double* q[4];
  for (int i = 0; i < 4; ++i) q[i] = i == inf ? p : P(v[i]);
  const int o = pred::orient3d(q[0], q[1], q[2], q[3]);
  if (o != 0) return o > 0;
  // p lies in the plane of the hull face: in conflict iff inside its circumcircle. The apex of
  // the finite tet behind the face is a reference point off that plane.
  const std::uint32_t behind = v[4 + inf];  // face reference 4*u+j of the finite tet
  const std::uint32_t apex = T[8 * std::size_t(behind >> 2) + (behind & 3)];
  const double* f[3];
  for (int i = 0, k = 0; i < 4; ++i)
    if (i != inf) f[k++] = P(v[i]);
  return pred::incircle_coplanar_perturbed(f[0], f[1], f[2], p, P(apex)) > 0;
}

}  // namespace kdmesh
