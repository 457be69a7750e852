// kdmesh — surface validation and orientation (pipeline stage: SurfaceMesh -> PreparedSurface).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/surface_mesh.h"

namespace kdmesh {

/// The interfaces of an assembly: where named bodies touch along faces (mesher/surface/
/// surface_bodies.h), the facets between two bodies, inside the solid. Empty for one body and
/// for bodies that lie apart.
struct BodyInterfaces {
  /// One facet per piece of interface (imprinted: the same triangles for both bodies), oriented
  /// out of bodies[f][0] into bodies[f][1].
  SurfaceMesh mesh;
  std::vector<std::array<std::uint32_t, 2>> bodies;  ///< per facet: the body behind, the body in front
  /// Each body's own closed, outward surface (as prepared, scaled): which body holds a point.
  std::vector<SurfaceMesh> body_surfaces;
  /// Imprints made (CGAL corefinements of a pair of bodies): each pair in contact once, and
  /// again while an imprint of a third body adds a vertex on its contact.
  std::size_t imprints = 0;
  bool empty() const { return mesh.num_tris() == 0; }
};

/// A surface that bounds a solid: closed, 2-manifold, without degenerate triangles or
/// self-intersections, every facet oriented outward (away from the solid).
/// Shells are the connected components; a shell nested in another bounds a void (or an
/// island inside a void). Bodies are the disjoint solids: an outer shell plus its voids.
struct PreparedSurface {
  SurfaceMesh mesh;
  std::vector<std::uint32_t> tri_shell;     ///< shell id of each facet
  std::vector<std::uint32_t> shell_body;    ///< body id of each shell
  std::vector<std::uint32_t> shell_parent;  ///< innermost enclosing shell, or kNoFacet if none
  std::vector<double> shell_volume;         ///< signed volume each shell encloses (> 0 outer, < 0 void)
  std::uint32_t num_bodies = 0;
  double volume = 0;                        ///< volume of the solid (sum of shell_volume)
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  std::vector<std::string> notices;         ///< what was changed (e.g. "shell 2 flipped ...")
  /// Touching bodies: `mesh` is then the outer surface of their union, and the interfaces
  /// between them are here.
  BodyInterfaces interfaces;
};

struct SurfaceOptions {
  double scale = 1;                        ///< coordinates are multiplied by this (units)
  bool check_self_intersections = true;    ///< CGAL PMP; O(n log n)
  /// Called once per notice as it happens (e.g. a flipped shell); may be empty.
  std::function<void(const std::string&)> notice;
};

/// A surface that bounds no solid. The message names the file, the defect and the first
/// offending facets (0-based ids, as in the file) or edges (point ids and coordinates).
class SurfaceError : public GeometryError {
 public:
  /// The defects an opt-in repair (mesher/surface/surface_repair.h) can fix, and the rest.
  enum class Defect { degenerate, duplicates, orientation, other };
  SurfaceError(const std::string& msg, std::vector<std::uint32_t> facets, Defect defect = Defect::other)
      : GeometryError(msg), facets_(std::move(facets)), defect_(defect) {}
  const std::vector<std::uint32_t>& facets() const { return facets_; }
  Defect defect() const { return defect_; }

 private:
  std::vector<std::uint32_t> facets_;
  Defect defect_;
};

/// Validates `mesh` (read from `source`, used in messages) and orients it:
/// checks in this order, each failure a SurfaceError naming up to 10 offenders:
///   empty / non-finite coordinates; degenerate (zero-area) triangles; duplicated facets;
///   open (boundary edges); non-manifold edges (> 2 facets); non-manifold vertices;
///   inconsistent orientation within a shell; self-intersections.
/// Shells facing inward are flipped (a notice says which); nesting decides outer vs void.
/// Points that no facet uses are dropped (a notice says how many); the others keep their order.
/// Throws UsageError if options.scale is not finite and > 0.
PreparedSurface prepare_surface(SurfaceMesh mesh, const std::string& source,
                                const SurfaceOptions& options = {});

}  // namespace kdmesh
