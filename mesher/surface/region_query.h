// kdmesh — which body of an assembly holds a point, and where the interfaces between touching
// bodies are (queries for the stages after the surface, when bodies touch).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {

/// Built on a prepared surface with interfaces (PreparedSurface::interfaces): one inside test
/// per body (exact ray parity on the body's own surface) and an AABB tree over the interface
/// facets. The surface must outlive it; queries are const and thread-safe.
class RegionQuery {
 public:
  static constexpr int kOutside = -1;    ///< in no body
  static constexpr int kOnSurface = -2;  ///< on a body's surface (an interface or the outside)

  explicit RegionQuery(const PreparedSurface& surface);
  ~RegionQuery();
  RegionQuery(const RegionQuery&) = delete;
  RegionQuery& operator=(const RegionQuery&) = delete;

  /// The body whose solid holds p strictly, kOnSurface when p is on a body's surface, else
  /// kOutside.
  int region(const double* p) const;
  /// True when body r holds p strictly: region(p) == r, with one inside test instead of one per
  /// body before r (the bodies are checked not to overlap when they are joined).
  bool in_body(const double* p, std::uint32_t r) const;
  /// The interface facets (distance, closest point; facet ids of surface.interfaces.mesh).
  const SurfaceQuery& interfaces() const { return *interfaces_; }
  /// The two bodies interface facet f lies between (behind, in front).
  const std::array<std::uint32_t, 2>& bodies(std::uint32_t f) const { return surface_.interfaces.bodies[f]; }
  std::uint32_t num_bodies() const { return std::uint32_t(body_.size()); }

 private:
  const PreparedSurface& surface_;
  std::vector<std::unique_ptr<SurfaceQuery>> body_;
  std::vector<std::array<double, 6>> box_;  // per body: min, max
  std::unique_ptr<SurfaceQuery> interfaces_;
};

}  // namespace kdmesh
