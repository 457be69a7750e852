// kdmesh — surface patches and feature curves, their transfer to the volume mesh's boundary,
// and named boundary groups (pipeline stage: VolumeMesh -> BoundaryGroups -> FeGroup list).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/fe_mesh.h"
#include "core/surface_mesh.h"
#include "mesher/surface/surface_query.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

inline constexpr std::uint32_t kNoEntity = std::numeric_limits<std::uint32_t>::max();

/// The input surface split at its sharp edges (patches) and its sharp edges chained into
/// curves. Numbering is deterministic: patch ids in the order of their smallest facet id;
/// curves in the order of mesher/placement/edge_sampling.h chain_feature_edges (smallest corner id,
/// then edge order; corner-free loops start at their smallest point id), i.e. the very
/// polylines along which node placement put the edge nodes.
struct SurfacePatches {
  std::uint32_t num_patches = 0;
  std::vector<std::uint32_t> facet_patch;  ///< per facet: its patch
  std::vector<double> patch_area;          ///< per patch: the sum of its facet areas
  /// per patch: 1 if all its points lie exactly in one plane (exact orient3d)
  std::vector<std::uint8_t> patch_planar;

  /// Curve c is the polyline curve_points[curve_start[c] .. curve_start[c+1]) (surface point
  /// ids, consecutive ones joined by feature edges). Open curves run between corners (feature
  /// corners, or points where != 2 feature edges meet); a closed curve (a corner-free loop)
  /// repeats its first point at the end.
  std::vector<std::uint32_t> curve_start{0};
  std::vector<std::uint32_t> curve_points;
  std::vector<std::uint8_t> curve_closed;   ///< per curve
  std::vector<double> curve_length;         ///< per curve
  /// 2 per curve: the patches on its two sides (smaller id first; equal when the curve runs
  /// inside one patch, e.g. a crease that ends inside a face).
  std::vector<std::uint32_t> curve_patches;
  std::vector<std::uint32_t> edge_curve;    ///< per feature edge (FeatureEdges order): its curve

  std::size_t num_curves() const { return curve_closed.size(); }
  std::size_t curve_size(std::size_t c) const { return curve_start[c + 1] - curve_start[c]; }
  const std::uint32_t* curve(std::size_t c) const { return curve_points.data() + curve_start[c]; }
};

/// Patches: facets flood-filled across non-feature edges. Curves: see SurfacePatches.
/// `surface` must be closed and 2-manifold (a prepared surface); throws UsageError if a
/// feature edge is not an edge of the surface.
SurfacePatches segment_surface(const SurfaceMesh& surface, const FeatureEdges& features);

/// Closest points restricted to one patch or one curve (CGAL AABB trees inside the .cpp, one
/// per patch / curve, built on first use). Not thread-safe (lazy building); the surface and
/// the patches must outlive it.
class PatchQuery {
 public:
  PatchQuery(const SurfaceMesh& surface, const SurfacePatches& patches);
  ~PatchQuery();
  PatchQuery(const PatchQuery&) = delete;
  PatchQuery& operator=(const PatchQuery&) = delete;

  /// Closest point to p on the facets of `patch`: written to out, its facet to *facet (if not
  /// null); returns the distance.
  double closest_in_patch(const double* p, std::uint32_t patch, double* out,
                          std::uint32_t* facet = nullptr);
  /// Closest point to p on the polyline of `curve`; returns the distance.
  double closest_on_curve(const double* p, std::uint32_t curve, double* out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The volume mesh's boundary in terms of the input's patches and curves.
struct BoundaryGroups {
  std::vector<std::uint32_t> face_patch;  ///< per VolumeMesh boundary face: its patch
  /// The mesh's feature edges: 2 node ids each, ordered along their curve (by curve id, then
  /// arc length; the first node at the smaller arc length), one per pair of consecutive mesh
  /// nodes on an input curve. These are exactly the boundary edges whose two boundary faces
  /// lie in different patches, plus those along curves inside one patch (any other edge
  /// between patches is reported in `problems`).
  std::vector<std::uint32_t> edges;
  std::vector<std::uint32_t> edge_curve;   ///< per feature edge: its curve
  /// 2 per feature edge: the arc lengths of its nodes along the curve (the closing edge of a
  /// closed curve ends at the first node's arc length + the curve's length).
  std::vector<double> edge_arclength;

  // Verification.
  std::vector<std::size_t> patch_faces;    ///< per patch: boundary faces assigned to it
  std::vector<std::size_t> curve_edges;    ///< per curve: mesh feature edges on it
  std::size_t topological_faces = 0;  ///< faces decided by the patches their nodes lie on
  std::size_t geometric_faces = 0;    ///< faces decided by distance (all nodes on curves)
  std::size_t verified_faces = 0;     ///< faces checked against the closest surface facet
  std::vector<std::uint32_t> ambiguous_faces;  ///< boundary faces whose patch is not certain
  std::size_t relocated_nodes = 0;    ///< boundary nodes not on their own facet (located anew)
  std::size_t missing_curve_edges = 0;  ///< consecutive curve nodes not joined by a boundary edge
  std::size_t stray_patch_edges = 0;    ///< boundary edges between patches off every curve
  std::size_t empty_patches = 0;        ///< patches that received no boundary face
  std::size_t empty_curves = 0;         ///< curves with no mesh feature edge
  /// One line per defect (the first 20 of each kind), naming the face / edge / node and where.
  std::vector<std::string> problems;
  double seconds = 0;

  bool ok() const {
    return ambiguous_faces.empty() && missing_curve_edges == 0 && stray_patch_edges == 0 &&
           empty_patches == 0 && empty_curves == 0;
  }
};

/// Assigns a patch to every boundary face of `mesh` and finds its feature edges.
///
/// Every boundary node is located on the input surface from its facet (NodeSet::facet; a node
/// not on its facet is located by query.closest): inside a patch, on a feature edge (on a
/// curve, at some arc length) or at a feature vertex (on the curves through it). The tolerance
/// for "on an edge / at a vertex" is 1e-9 of the facet's longest edge (edge nodes are
/// interpolated along their segment, so they lie on it only up to rounding).
///  - A face's candidate patches are the intersection over its nodes of the patches each node
///    can belong to (its patch; the two sides of its curve; the patches around its vertex).
///    One candidate: the face is decided topologically.
///  - Otherwise (all three nodes on curves, e.g. three nodes of a circular edge) the patch
///    closest to the face centroid among the candidates is taken; it is certain when its
///    distance is at most half the runner-up's and the runner-up's is above rounding level
///    (1e-9 of the face's longest edge), otherwise the face is listed as ambiguous.
///  - Faces without a node inside a patch (all nodes on curves: along the feature edges) and
///    geometric decisions are then verified against query.closest(centroid): a face lying
///    farther from its patch than from another patch by more than 5% of its longest edge is
///    ambiguous. (A face with a node inside its patch touches the patch there; how far the
///    face strays from the surface is check_volume_mesh's Hausdorff test.)
/// Curve edges: the boundary nodes on each curve, sorted by arc length; consecutive ones must
/// be joined by a boundary edge of the mesh (else missing_curve_edges). Defects are counted
/// and described in `problems`; nothing is thrown for them (see ok()).
BoundaryGroups assign_boundary(const VolumeMesh& mesh, const SurfaceMesh& surface,
                               const SurfacePatches& patches, const SurfaceQuery& query);

/// A named group requested by the user. Proposed YAML (a job key `groups`, a list; `origin`
/// is the entry's "file:line"):
///
///   groups:
///     - {name: fixed, zone: fixed_edges}            # every zone named so; dim from its type
///     - {name: load, dim: 2, point: [50, 50, 100]}  # the patch nearest to the point
///     - {name: rim, dim: 1, point: [0, 40, 120]}    # the curve nearest to the point
///     - {name: top, dim: 2, box: {min: [-1, -1, 99], max: [101, 101, 101]}}
///     - {name: base, zone: base_plane}              # plane zone: the patches lying in it
///   group_options: {patches: true, curves: true}    # also patch_<i> / curve_<i> (optional)
///
/// Selection by zone (all zones of that name together): segment / polyline zones select the
/// curves lying on them (dim 1; default); plane zones the patches lying in the plane (dim 2;
/// default) or, with dim 1, the curves lying in it; box and ball zones the patches / curves
/// entirely inside; point zones the nearest patch / curve (box, ball and point zones need
/// `dim`). "Lying on" means every point of the curve or patch (its vertices and the midpoints
/// of its edges) is within GroupOptions::zone_tolerance * zone.size of the zone: tagging by
/// geometry, with the zone's own target size as the local size. Sharp-edge zones select
/// nothing (UsageError).
struct GroupSpec {
  enum class Select { zone, point, box };
  std::string name;       ///< [A-Za-z0-9_-]+, unique per dimension (automatic names included)
  int dim = 0;            ///< 1 curves or 2 patches; 0 = from the zone type (zone selection)
  Select by = Select::point;
  std::string zone;       ///< Select::zone: the sizing zones' name
  double point[3] = {0, 0, 0};                    ///< Select::point
  double box_min[3] = {0, 0, 0}, box_max[3] = {0, 0, 0};  ///< Select::box (closed box)
  std::string origin;     ///< where the spec was written, e.g. "block.yaml:21" (messages)
};

struct GroupOptions {
  bool patch_groups = false;   ///< add patch_<i> (dim 2, patch id i-1) for every patch
  bool curve_groups = false;   ///< add curve_<i> (dim 1, curve id i-1) for every curve
  double zone_tolerance = 0.25;  ///< in units of the zone's size (see GroupSpec)
  /// The names of the volume groups, one per body (a job's named `bodies`); empty: body_<i>.
  std::vector<std::string> body_names;
};

/// The named groups: one per body (dim 3, entity = tet_region i-1), `body_<i>` for each of
/// `num_bodies` bodies or options.body_names (then as many as num_bodies), then the user's specs in order, then the optional patch_<i> / curve_<i>.
/// Throws UsageError naming the spec (its name and origin) when it selects nothing, names an
/// unknown zone, has a bad dim or name, or repeats a name of its dimension. A point
/// selection equidistant (to 1e-9 relative) from two patches / curves is a UsageError too.
std::vector<FeGroup> make_groups(const std::vector<GroupSpec>& specs, const SurfaceMesh& surface,
                                 const SurfacePatches& patches,
                                 const std::vector<SizingZone>& zones, std::uint32_t num_bodies,
                                 const GroupOptions& options = {});

}  // namespace kdmesh
