// kdmesh — optimisation-based vertex smoothing of the quality-improvement pass: a vertex moves
// along the steepest ascent direction of the smallest tet_sine of its star (the min-norm point
// of the active tets' gradients, Freitag & Ollivier-Gooch), with a halving line search; a move
// is kept only if the star's smallest quality rises and every tet stays valid. Interior nodes
// move freely. Feature nodes slide along their feature curve (SmoothContext::slide_features).
// Surface nodes slide on the surface: within the plane of
// their facet when every boundary face at them lies in that plane (the fan of boundary faces
// keeps its outer polygon and every face its orientation, so it covers the same part of the
// surface as before); else, given a BoundaryContext, along the fan's tangent plane and back
// onto the closest point of the input surface, each boundary face at them keeping its
// orientation and lying on the surface within the context's tolerance.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>

#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_tets.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {

struct SmoothContext {
  const PreparedSurface* surface = nullptr;  ///< null: surface nodes stay fixed
  const SurfaceQuery* query = nullptr;
  double on_surface = 0;       ///< a moved surface node must stay this close to the surface
  /// Set: surface nodes on curved fans slide on the surface too (smooth_vertex only; the
  /// relaxation keeps them). Null: only within planar fans.
  const BoundaryContext* boundary = nullptr;
  /// With boundary and its features set: feature nodes (not corners) slide along their curve,
  /// between their two neighbours on it, projected onto the input's feature edges; the edges
  /// to those neighbours keep running along the feature (smooth_vertex only).
  bool slide_features = true;
  int iterations = 4;          ///< ascent steps per call
};

/// A vertex's star as ImproveTets::star gives it (the same tets in the same order), when the
/// caller walked it already: the moves below then do not walk it again.
struct KnownStar {
  const std::uint32_t* tets = nullptr;
  std::size_t size = 0;
};

/// Tries to move vertex v. Returns true if it moved; *before / *after get the star's smallest
/// tet_sine (if not null). `star`, if given, is v's star.
bool smooth_vertex(ImproveTets& m, std::uint32_t v, const SmoothContext& ctx,
                   double* before = nullptr, double* after = nullptr, const KnownStar* star = nullptr);

/// Smart Laplacian: moves v towards the centroid of its neighbours (the whole way, half or a
/// quarter) if that raises the sum of the star's radius ratios and keeps the star's smallest
/// tet_sine at least min(its old value, floor). For the mean quality of the bulk.
///
/// `known`, if given, holds tet_sine and tet_radius_ratio of every tet slot of v's star (the
/// star as it stands): they are read instead of computed, and a move writes its star's new
/// values there. Vertices that share no tet may relax at once with one `known`.
struct StarValues {
  double* sine = nullptr;   ///< per tet slot: tet_sine
  double* ratio = nullptr;  ///< per tet slot: tet_radius_ratio
};
/// `star`, if given, is v's star.
bool relax_vertex(ImproveTets& m, std::uint32_t v, const SmoothContext& ctx, double floor,
                  const StarValues* known = nullptr, const KnownStar* star = nullptr);

}  // namespace kdmesh
