// kdmesh — finite-element meshes from the volume mesh: linear (C3D4) with boundary patches,
// feature curves and named groups, and quadratic (C3D10) with mid-edge nodes on the surface
// (pipeline stage: VolumeMesh + BoundaryGroups -> FeMesh).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/fe_mesh.h"
#include "core/surface_mesh.h"
#include "mesher/fe/boundary_groups.h"
#include "mesher/surface/surface_query.h"
#include "mesher/volume/volume_mesh.h"

namespace kdmesh {

/// The order-1 FeMesh: points = mesh.nodes.points, tets and tet_entity = tets and tet_region,
/// faces = the boundary faces (outward) with face_entity = their patch, edges = the mesh's
/// feature edges with edge_entity = their curve, and `groups`. Throws UsageError when `bg`
/// belongs to another mesh (sizes differ) or a face has no patch.
FeMesh make_fe_mesh(const VolumeMesh& mesh, const BoundaryGroups& bg, std::vector<FeGroup> groups);

struct QuadraticOptions {
  /// Put boundary mid-edge nodes on the input surface (false: every mid-edge node at the
  /// midpoint of its edge, i.e. straight-sided C3D10).
  bool curved = true;
  /// A projection moving a mid-edge node farther than this fraction of its edge's length is
  /// not trusted: the node stays at the midpoint (counted in far_projections).
  double max_move = 0.25;
  /// An element is valid when det J >= min_jacobian_ratio * 6 V (V its straight volume) at its
  /// 4 corners and 4 Gauss points; > 0 is required in any case. Straight elements have ratio 1.
  /// The default keeps curving from shrinking det J below a tenth of the straight element's
  /// anywhere (with 0, partial curving left a gearbox element at 3e-14: valid, but useless).
  double min_jacobian_ratio = 0.1;
  /// An element failing that test first has the displacement (from the midpoint) of its
  /// curved mid-edge nodes halved, up to this many times, before they go back to the
  /// straight midpoints. 0: straight at once.
  int halving_steps = 2;
};

struct QuadraticStats {
  std::size_t mid_nodes = 0;          ///< one per mesh edge
  std::size_t curve_mid_nodes = 0;    ///< on feature edges (projected onto their curve)
  std::size_t patch_mid_nodes = 0;    ///< on other boundary edges (projected into their patch)
  std::size_t moved_mid_nodes = 0;    ///< of those, nodes the projection moved off the midpoint
  std::size_t far_projections = 0;    ///< projections rejected for moving too far
  std::size_t reduced_elements = 0;   ///< elements that failed the validity test when curved
  std::size_t straightened_elements = 0;  ///< of those, elements that ended all straight
  std::size_t reduced_edges = 0;      ///< mid-edge nodes left partly curved (1/2, 1/4, ...)
  std::size_t straightened_edges = 0; ///< moved mid-edge nodes put back at their midpoint
  std::size_t invalid_linear = 0;     ///< straight elements with volume <= 0 (never expected)
  double max_move = 0;                ///< largest mid-node displacement / edge length
  double min_jacobian_ratio = 0;      ///< min over elements and sample points of det J / (6 V)
  double seconds = 0;
};

/// Turns the order-1 `fe` (from make_fe_mesh) into order 2: one mid-edge node per mesh edge,
/// shared by every element that has the edge, numbered after the corner nodes in the order of
/// the edges' (smaller node id, larger node id). Element node order as core/fe_mesh.h says.
/// Positions (options.curved): feature edges (fe.edges) -> the closest point on their curve's
/// polyline; other boundary edges whose faces lie in one curved patch -> the closest point of
/// that patch (query.closest when it lands in the patch, else PatchQuery); every other edge
/// (interior, between patches, in a planar patch, on an interface between bodies: faces whose
/// entity is num_patches or more, mesher/fe/body_groups.h) -> its midpoint. Then every tet is checked (det J at its corners and 4 Gauss points, see the .cpp
/// for the shape functions); an element that fails has its curved mid-edge nodes moved
/// halfway back to their midpoints (options.halving_steps times), then onto them (which only
/// ever straightens its neighbours), repeated until every element passes.
/// Throws UsageError if fe is not order 1 or its curves do not match `patches`.
QuadraticStats make_quadratic(FeMesh& fe, const SurfaceMesh& surface, const SurfaceQuery& query,
                              const SurfacePatches& patches, const QuadraticOptions& options = {});

/// det J of the quadratic tet with nodes x[0..9] (order of core/fe_mesh.h) at barycentric
/// coordinates L[0..3]; equals 6 V everywhere when the mid-edge nodes are the midpoints.
double quadratic_tet_jacobian(const double* const x[10], const double L[4]);

/// Minimum of det J / (6 V) over the 4 corners and the 4 Gauss points (V: the straight tet's
/// volume; returns -inf when V <= 0).
double quadratic_tet_min_jacobian_ratio(const double* const x[10]);

/// The volume of a quadratic tet: the integral of det J (cubic in L), exact with the
/// degree-3 rule of Stroud (centroid weight -4/5, (1/2,1/6,1/6,1/6) weights 9/20).
double quadratic_tet_volume(const double* const x[10]);

/// The volume of an FeMesh of either order (sum over tets).
double fe_mesh_volume(const FeMesh& fe);

}  // namespace kdmesh
