// kdmesh — geometric queries against a closed surface: inside/outside, closest point.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <memory>

#include "core/surface_mesh.h"

namespace kdmesh {

/// An AABB tree over a closed, outward-oriented surface (CGAL inside the .cpp).
/// Queries are const and thread-safe. The surface must outlive the query object.
class SurfaceQuery {
 public:
  explicit SurfaceQuery(const SurfaceMesh& surface);
  ~SurfaceQuery();
  SurfaceQuery(const SurfaceQuery&) = delete;
  SurfaceQuery& operator=(const SurfaceQuery&) = delete;

  /// +1 strictly inside the solid, -1 strictly outside, 0 on the surface.
  int side(const double* p) const;
  /// Closest surface point to p: writes it to `out`, its facet to *facet (if not null), and
  /// returns the distance.
  double closest(const double* p, double* out, std::uint32_t* facet = nullptr) const;
  /// Distance from p to the surface.
  double distance(const double* p) const;
  /// The same, faster, given `hint`: a point on the surface near p (e.g. a mesh vertex on it)
  /// that bounds the search. The result is min(|p - hint|, the distance), so it may be low by
  /// at most hint's own distance from the surface.
  double distance(const double* p, const double* hint) const;
  /// distance(p, hint) <= r, the same answer, from the facet grid where no rounding can
  /// matter (the tree otherwise).
  bool within(const double* p, double r, const double* hint) const;
  /// distance(p) <= r, likewise.
  bool within(const double* p, double r) const;
  /// Distance from `origin` along the ray in direction `dir` (not necessarily unit) to its
  /// first crossing with a facet other than `skip` (kNoFacet: none skipped), in units of
  /// |dir|; +infinity when the ray meets no other facet. The facet hit goes to *hit (if not
  /// null; kNoFacet when none).
  double ray_distance(const double* origin, const double* dir, std::uint32_t skip,
                      std::uint32_t* hit = nullptr) const;
  /// True when the closed segment ab meets no closed facet (exact predicates; the facet
  /// grid first). Then a and b lie strictly on the same side: the way to carry a known side
  /// between nearby points.
  bool segment_clear(const double* a, const double* b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kdmesh
