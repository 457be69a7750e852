// kdmesh — conforming volume mesh of a solid from its nodes
// (pipeline stage: NodeSet -> Ordering -> Delaunay -> inside tets -> VolumeMesh).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/tet_mesh.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/node_set.h"
#include "mesher/order/order.h"
#include "mesher/domain.h"
#include "mesher/tet_quality.h"

namespace kdmesh {

struct VolumeMeshOptions {
  OrderOptions order;                ///< insertion order of the nodes (kd-bfs-hilbert by default)
  /// Delaunay inserting threads (0 = available_cpus()). The mesh is the same for any count: the
  /// triangulation is put in canonical order (mesher/delaunay/canonical_order.h).
  unsigned threads = 0;
  int max_steiner_rounds = 12;       ///< rounds of surface Steiner insertion before giving up
  /// A boundary face must lie within hausdorff_tolerance * h (local target size) of the
  /// input surface; farther faces get a Steiner point on the surface.
  double hausdorff_tolerance = 0.1;
  /// Progress: stage name and fraction done.
  std::function<void(const std::string&, double)> progress;
};

struct VolumeMeshStats {
  std::size_t input_nodes = 0;
  std::size_t steiner_points = 0;     ///< surface points added to recover the boundary
  std::size_t dropped_nodes = 0;      ///< interior nodes too close to the surface, removed
  /// Flat tets of four interface nodes kept inside the solid (touching bodies), each given a
  /// Steiner point on the interface to split it, summed over rounds.
  std::size_t interface_slivers = 0;
  int rounds = 0;                     ///< Steiner rounds used
  int insert_rounds = 0;              ///< of those, rounds that inserted the Steiner points into the
                                      ///< existing triangulation (the others, with dropped nodes, rebuilt it)
  std::size_t unused_nodes = 0;       ///< nodes no inside tet uses (e.g. exact duplicates), removed
  /// Surface-kind nodes (placed on the surface) that the recovered boundary passes over: they
  /// are in no boundary face, so they are interior nodes of the mesh and get that kind (the
  /// quality pass may then move them off the surface; fandisk.ply at diag/40 kept a 0.04 deg
  /// tet on such a node).
  std::size_t buried_nodes = 0;
  DelaunayStats delaunay;             ///< of the first (full) tetrahedralization
  /// Summed over all rounds (the Delaunay / order time of the first round is delaunay.seconds).
  double order_seconds = 0, delaunay_seconds = 0, classify_seconds = 0, recover_seconds = 0;
  double region_seconds = 0;          ///< region flood fill and output compaction
  double interface_seconds = 0;       ///< touching bodies: tet regions, faces between them judged
  double total_seconds = 0;           ///< all of mesh_volume
  std::size_t classified_tets = 0;    ///< tets classified, summed over rounds
  std::size_t side_queries = 0;       ///< exact inside/outside queries made by the classification
  std::size_t rim_flips = 0;          ///< tets with an interior vertex whose own query said outside
};

/// The tets inside the solid. `nodes` are the input nodes that are kept, in input order
/// (interior nodes dropped for being too close to the surface and nodes no inside tet uses
/// are removed), followed by the Steiner points; point ids refer to `nodes`. Every tet is
/// positively oriented.
inline constexpr std::uint32_t kNoAdjacentTet = 0xFFFFFFFFu;

struct VolumeMesh {
  NodeSet nodes;                          ///< input nodes + Steiner points (kind surface/edge)
  std::vector<std::uint32_t> tets;        ///< 4 node ids per tet
  std::vector<std::uint32_t> tet_region;  ///< body id (PreparedSurface) per tet
  std::vector<std::uint32_t> boundary;    ///< 3 node ids per boundary face, normal outward
  std::vector<std::uint32_t> boundary_tet;  ///< the tet each boundary face belongs to
  /// The face adjacency the Delaunay already had, 4 per tet: tet_adj[4 t + i] = 4 u + j when
  /// face i of t (opposite its vertex i) is face j of tet u, kNoAdjacentTet on the boundary.
  /// The quality pass takes it instead of matching 4 x tets faces again (pinion.ply: 0.17 s),
  /// and frees it (its tets change). Empty also means "unknown": consumers rebuild it.
  std::vector<std::uint32_t> tet_adj;
  VolumeMeshStats stats;

  std::size_t num_tets() const { return tets.size() / 4; }
};

/// Tetrahedralizes `nodes` (Delaunay, in options.order) and keeps the tets inside the solid;
/// inserts Steiner points on the surface where boundary faces miss it. Throws
/// BoundaryRecoveryError (a GeometryError carrying the bad places) if the boundary cannot be
/// recovered within max_steiner_rounds.
VolumeMesh mesh_volume(const Domain& domain, NodeSet nodes,
                       const VolumeMeshOptions& options = {});

/// The mesh as writers take it: points, tets, point data "node_kind" (ints) and "target_size"
/// (floats), cell data "region" (ints), "min_dihedral" and "radius_ratio" (floats: each tet's
/// measure rounded to 32 bits; the summary is of the doubles). The cell data's per-tet measures
/// also give their summary (to *summary if not null) and go to `each` if set: one pass.
TetMesh to_tet_mesh(const VolumeMesh& mesh, QualitySummary* summary = nullptr,
                    const TetQualityVisitor& each = {});

}  // namespace kdmesh
