// kdmesh — the sizing field h(x): target edge length at every point
// (pipeline stage: SurfaceMesh + SizingOptions -> SizingField).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/surface_mesh.h"
#include "sizing/segment_bvh.h"

namespace kdmesh {

/// A feature zone: a set where the element size is `size`, growing away from it.
struct SizingZone {
  enum class Kind {
    sharp_edges,  ///< surface edges whose dihedral deviation (angle between the two facet
                  ///< normals) is >= angle_deg
    polyline,     ///< user edges: coords = 3*k vertices, k >= 2, consecutive ones joined
    segment,      ///< coords = 6: the two end points
    plane,        ///< cross-section clipped to the solid: coords = origin(3) + normal(3)
    point,        ///< coords = 3
    box,          ///< coords = min(3) + max(3); the zone is the solid box
    ball,         ///< coords = center(3) + radius(1); the zone is the solid ball
  };
  Kind kind = Kind::point;
  std::string name;      ///< user's name (may be empty); boundary groups use it later
  double size = 0;       ///< target edge length on the zone (> 0)
  std::vector<double> coords;
  double angle_deg = 30;  ///< sharp_edges only
};

struct SizingOptions {
  double max_size = 0;     ///< h_max (> 0): the size far from every zone
  double min_size = 0;     ///< h_min floor; 0 means max_size / 1000
  double gradation = 0.3;  ///< g: size grows by g per unit distance from a zone (> 0)
  std::vector<SizingZone> zones;
  /// Curvature bound: on the smooth (non-feature) curved parts of the surface the size is at
  /// most curvature_angle_deg (in radians) times the local radius of curvature, so that a
  /// boundary facet of size h sags at most h * angle / 8 below the surface (0 = off).
  double curvature_angle_deg = 0;
  /// Chordal-deviation bound (model units; 0 = off): the mean depth h^2 / (12 r) of a
  /// boundary facet below a surface of radius r is at most this, i.e. h <= sqrt(12 r d). The
  /// mesher derives it from the volume tolerance of its check.
  double chordal_deviation = 0;
  /// Surface edges whose dihedral deviation is at least this are features, kept by nodes on
  /// them; the curvature terms ignore them (0: every edge counts as curvature).
  double feature_angle_deg = 0;
  /// Segments (or points, a == b) with sizes of their own that the caller derived, e.g. the
  /// mesher's wall-thickness term: each acts as a zone of its own size.
  WeightedSegments derived;
  /// Address space for the segments' per-cell candidate lists (bytes; 0 = none), paged in as
  /// they are made: past it, points search the segments' BVH, for the same value
  /// (sizing/segment_cells.h).
  std::size_t list_memory = std::size_t(256) << 20;
};

/// What the automatic (curvature) terms did, for the notices.
struct SizingAutoStats {
  std::size_t curvature_places = 0;  ///< surface cells and edges whose curvature size is below max_size
  double min_curvature_size = 0;    ///< the least of those sizes (0 when none)
  double min_radius = 0;            ///< the least radius of curvature estimated there
};

/// h(x) = max(h_min, min(h_max, min over zones (size_z + g * d(x, zone)))).
/// Immutable after build; thread-safe queries; cheap to copy (shared state).
class SizingField {
 public:
  SizingField() = default;
  /// Target edge length at x (xyz).
  double operator()(const double* x) const;
  /// A lower bound of h over the ball of the given radius around x, never above h anywhere
  /// in it: the larger of h(x) - g radius (h is g-Lipschitz) and the field with every zone's
  /// distance shortened by the radius (attained for a lone point zone; h_max far from every
  /// zone, where h(x) - g radius may be below h_min). Equals h(x) at radius 0, there found by
  /// the zones' own search alone (without operator()'s cell tables and lists, whose value is
  /// the same bit for bit: the tests' reference).
  double lower_bound(const double* x, double radius) const;
  /// lower_bound(x, radius) from h(x) the caller already has (`h_at_x`, exactly what
  /// operator() returned at x): one zone query fewer.
  double lower_bound(const double* x, double radius, double h_at_x) const;
  double max_size() const;
  double min_size() const;
  const SizingOptions& options() const;
  const SizingAutoStats& auto_stats() const;

  struct Impl;
  explicit SizingField(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

 private:
  std::shared_ptr<const Impl> impl_;
};

/// Builds the field for a prepared (closed, outward) surface. Throws UsageError naming the
/// zone (by index and name) for invalid options: non-positive sizes, a plane that misses the
/// solid, a degenerate segment or polyline, a box with min > max, ...
SizingField build_sizing_field(const SurfaceMesh& surface, const SizingOptions& options);

}  // namespace kdmesh
