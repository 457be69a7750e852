// kdmesh — the sizing field h(x): target edge length at every point
// (pipeline stage: SurfaceMesh + SizingOptions -> SizingField).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/surface_mesh.h"

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
  /// Optional curvature bound: the size on curved surface parts is at most
  /// curvature_angle_deg (radians of it) times the local radius of curvature; 0 = off.
  /// Not implemented yet: build_sizing_field throws UsageError when it is not 0.
  double curvature_angle_deg = 0;
};

/// h(x) = max(h_min, min(h_max, min over zones (size_z + g * d(x, zone)))).
/// Immutable after build; thread-safe queries; cheap to copy (shared state).
class SizingField {
 public:
  SizingField() = default;
  /// Target edge length at x (xyz).
  double operator()(const double* x) const;
  double max_size() const;
  double min_size() const;
  const SizingOptions& options() const;

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
