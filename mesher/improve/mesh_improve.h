// kdmesh — quality improvement of a volume mesh (pipeline stage: VolumeMesh -> VolumeMesh):
// flips (edge removal, face removal), smart-Laplacian relaxation and optimisation-based
// smoothing, keeping the boundary conforming, every tet valid, regions and determinism.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mesher/domain.h"
#include "mesher/volume/volume_mesh.h"

namespace kdmesh {

struct ImproveOptions {
  /// Tets whose smallest dihedral-angle sine is below sin(work_angle) are worked on (the
  /// objective is min(theta_min, 180 - theta_max); the issue asks for >= 12 and <= 165 deg).
  double work_angle = 30;
  double smooth_angle = 25;       ///< vertices of tets below it are smoothed
  int rounds = 3;                 ///< rounds of flips, [relaxation,] smoothing
  /// More rounds, up to this many in all, while tets below target_angle remain (by tet_sine:
  /// min dihedral under it, or max dihedral over 165 deg for 12) and their count keeps
  /// reaching new lows (stopping after three rounds without one). The handle at diag/20 had
  /// 62 such tets after 3 rounds and none after 15 (min dihedral 12.1 deg; 5.1 with 3 rounds).
  int max_rounds = 20;
  double target_angle = 12;
  int relax_rounds = 1;           ///< of those, the first ones also relax vertices (mean quality)
  double relax_below = 0.7;       ///< ... of tets whose radius ratio is below this
  int max_ring = 10;              ///< largest edge ring tried by edge removal
  bool smooth_surface = true;     ///< move surface nodes within planar patches
  /// ... and on curved parts of the surface too: the smoothing slides them on the input
  /// surface, each boundary face at them staying within hausdorff_tolerance (as for caps).
  bool slide_curved = true;
  /// ... and feature nodes (not corners) along their feature curve, between their two
  /// neighbours on it (needs feature_angle > 0; mesher/improve/improve_smooth.h).
  bool slide_features = true;
  /// Flip boundary edges within the surface where that improves the worst tet
  /// (boundary_edge_removal, mesher/improve/improve_flips.h; new faces within hausdorff_tolerance).
  bool flip_boundary = true;
  /// Take boundary caps (flat tets with two boundary faces, mesher/improve/improve_caps.h) below this
  /// angle out of the domain; 0 = never (the boundary face list then stays unchanged).
  double cap_angle = 15;
  /// Tets below this angle whose four vertices are all on the surface (which the smoothing
  /// cannot move apart) get a new interior node on their longest interior edge
  /// (mesher/improve/improve_split.h); 0 = never (no node is then added).
  double split_angle = 12;
  /// ... and where no interior edge of such a tet can be split, its longest boundary edge that
  /// is no feature edge and at least the local size long gets a new surface node at the
  /// surface point closest to its midpoint (mesher/improve/improve_split_boundary.h; new faces within
  /// hausdorff_tolerance). Long boundary edges are chords the Delaunay tets drew over nearly
  /// coplanar surface nodes (handle.ply's faceted cylinder: faces 10-23 h long). Where neither
  /// split applies (and, in the last stage, for any tet below split_angle), the tet and its
  /// neighbours become a fan around a new interior node (mesher/improve/improve_insert.h: caps folded
  /// along feature edges, whose feature nodes cannot move; triceratops.ply 4.6 -> 12.0 deg).
  bool split_boundary = true;
  /// The fans around new interior nodes (mesher/improve/improve_insert.h) of the split pass.
  bool insert_nodes = true;
  /// Faces a cap removal exposes must lie within 0.8 x this many local sizes of the surface
  /// (the mesh check's tolerance, with the mesher's margin).
  double hausdorff_tolerance = 0.1;
  /// The dihedral angle of the surface's feature edges (sizing/features.h), for the caps: a cap
  /// may flip a boundary edge between two feature nodes only if it runs along no feature edge.
  /// 0: unknown, such caps are kept.
  double feature_angle = 0;
  bool measure_stages = true;     ///< quality summary after each stage (costs a pass each)
  /// Worker threads for the vertex passes and the flips' choices (0 = available_cpus()). The result
  /// does not depend on it.
  unsigned threads = 0;
  /// Progress: stage name and fraction done.
  std::function<void(const std::string&, double)> progress;
};

/// The mesh's quality after one stage of the pass.
struct ImproveStage {
  std::string name;
  double seconds = 0;             ///< of this stage alone
  std::size_t operations = 0;     ///< flips or vertex moves it made
  std::size_t tets = 0;
  double min_dihedral = 0, max_dihedral = 0, mean_radius_ratio = 0;
  std::size_t under5 = 0, under10 = 0, under12 = 0;  ///< tets with min dihedral below
  std::size_t over165 = 0;        ///< tets with max dihedral above 165 deg
};

struct ImproveStats {
  /// "input" (its seconds: building the adjacency), then "flip k", "relax k", "smooth k";
  /// the quality figures only with measure_stages.
  std::vector<ImproveStage> stages;
  std::size_t edge_removals = 0, face_removals = 0, smoothed = 0, relaxed = 0;
  std::size_t feature_slides = 0;    ///< moves of feature nodes along their curve (in smoothed)
  std::size_t boundary_flips = 0;    ///< boundary edges flipped within the surface
  std::size_t caps_removed = 0;      ///< boundary caps taken out of the domain
  std::size_t splits = 0;            ///< sliver edges split (interior nodes added)
  std::size_t boundary_splits = 0;   ///< long boundary edges split (surface nodes added)
  std::size_t insertions = 0;        ///< slivers replaced by a fan around a new interior node
  int rounds = 0;                    ///< rounds run (rounds .. max_rounds)
  std::size_t boundary_changes = 0;  ///< boundary faces replaced (0: the boundary list is unchanged)
  /// Tets left below target_angle at the end (by tet_sine, so a max dihedral over 165 deg counts
  /// too), the sine of the worst tet (1 if there is none), and the centroids of up to
  /// kBelowTargetPlaces of them, worst first (ties by slot), 3 coordinates each.
  std::size_t below_target = 0;
  double worst_sine = 1;
  std::vector<double> below_target_at;
  static constexpr std::size_t kBelowTargetPlaces = 64;
  double seconds = 0;
};

/// Improves `mesh` in place. Every tet stays exactly positively oriented and not flat; the
/// boundary faces stay on the surface (surface nodes slide on the input surface, within planar
/// patches or within the tolerance on curved ones, feature nodes along their feature curve,
/// corners never move; the boundary face
/// list changes only where a cap is taken out or a boundary edge flipped, and then within the
/// tolerance of the local size `domain.sizing` gives; boundary_tet is recomputed); regions are kept;
/// nodes are added only by sliver and boundary-edge splits; the result depends only on the input and the
/// options (not on the thread count: the pass makes no random choice). Throws UsageError for
/// bad options.
ImproveStats improve_mesh(VolumeMesh& mesh, const Domain& domain,
                          const ImproveOptions& options = {});

}  // namespace kdmesh
