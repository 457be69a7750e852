// kdmesh — topological operations of the quality-improvement pass: edge removal (the optimal
// triangulation of an edge's ring: 3-2, 4-4, 5-6, ... flips), its boundary form (a boundary
// edge flipped within the surface) and face removal (the 2-3 flip).
// Each is evaluated into a FlipCandidate first, so that a caller can pick the best one.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <vector>

#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_tets.h"

namespace kdmesh {

/// A local retriangulation: the tets `old` replaced by `fresh` (4 vertex ids per tet, each
/// exactly positively oriented and not flat), with the smallest tet_sine before and after.
struct FlipCandidate {
  std::vector<std::uint32_t> old, fresh;
  double q_old = 0, q_new = -1;
  bool improves() const { return q_new > q_old; }
};

/// The vertices whose stars an evaluation may read: all, or (the flip stage's parallel phase,
/// where other threads change the rest of the mesh) those with part_of[v] == part.
struct StarAccess {
  const std::uint8_t* part_of = nullptr;
  std::uint8_t part = 0;
  bool ok(std::uint32_t v) const { return !part_of || part_of[v] == part; }
};

/// Edge removal (Shewchuk 2003): the interior edge (a, b) of tet t, its ring r_0..r_{m-1}
/// (3 <= m <= max_ring) triangulated to maximise the smallest tet_sine of the tets
/// (r_i r_k r_j a) and (r_i r_j r_k b) (dynamic programme over sub-polygons). False if the edge
/// is on the boundary, the ring is too large, or no triangulation gives valid tets whose
/// smallest tet_sine exceeds both `floor` and that of the ring's tets (so a true result
/// improves the mesh).
/// `sines`, if given, holds tet_sine of every live slot of m (saves recomputing the old tets').
/// With validate = false the new tets' validity (tet_valid, ImproveTets::inside_ok) is left
/// to the caller (flip_valid), who may check only the candidate it picks.
bool edge_removal(const ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                  int max_ring, FlipCandidate& out, double floor = -1,
                  const double* sines = nullptr, bool validate = true);

/// Boundary edge removal: edge removal of an edge (a, b) on the boundary, whose open ring
/// r_0..r_m (m + 1 >= 3 vertices, at most max_ring) is triangulated with the closing edge
/// (r_0, r_m): the boundary faces (a, b, r_0) and (a, b, r_m) become (r_0, r_m, a) and
/// (r_0, b, r_m), the boundary edge flip within the surface. Only where the surface allows
/// it: (a, b) runs along no feature edge (an end is a surface node, or keeps_feature says
/// no), (r_0, r_m) is not an edge yet, and both new faces lie on the surface within the
/// context's tolerance (face_on_surface). Validated (flip_valid); the caller replaces with
/// boundary_may_change. `floor` and `sines` as for edge_removal. If it reads the star of a
/// vertex other than a and b (the ring end r_0), that vertex goes to *star_read; false,
/// without reading it, if `access` does not allow it (a and b's stars are the caller's).
bool boundary_edge_removal(const ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                           int max_ring, const BoundaryContext& ctx, FlipCandidate& out,
                           double floor = -1, const double* sines = nullptr,
                           std::uint32_t* star_read = nullptr, const StarAccess& access = {});

/// Face removal: face i of tet t (opposite p) shared with tet u (opposite q) replaced by the
/// three tets around the new edge pq (a 2-3 flip). False on a boundary face or if pq does not
/// cross the face's interior (a new tet would not be valid).
/// `sines` and `validate` as for edge_removal. Also false, as soon as one is found, if a new
/// tet's tet_sine is not above `floor` (the rest are not evaluated).
bool face_removal(const ImproveTets& m, std::uint32_t t, int i, FlipCandidate& out,
                  const double* sines = nullptr, bool validate = true, double floor = 0);

/// Every new tet of `c` exactly positively oriented, not flat, and inside the solid where
/// ImproveTets::inside_ok asks (the check edge_removal and face_removal make by default).
bool flip_valid(const ImproveTets& m, const FlipCandidate& c);

/// Smallest tet_sine over the tets `ids` of m.
double min_sine(const ImproveTets& m, const std::vector<std::uint32_t>& ids);

/// tet_sine of tet t of m.
double sine_of(const ImproveTets& m, std::uint32_t t);

}  // namespace kdmesh
