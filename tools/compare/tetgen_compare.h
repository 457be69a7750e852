// kdmesh — the same surface meshed by kdmesh and by TetGen 1.5 (-pq) at a matching size,
// measured by the same code (`kdmesh compare-tetgen`).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/point_set.h"
#include "core/tet_mesh.h"
#include "mesher/surface/surface_prepare.h"
#include "sizing/sizing_field.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {

class SurfaceQuery;

/// How TetGen is told the target size.
enum class TetgenSizing {
  /// -m with a background mesh: the Delaunay tetrahedralization of kdmesh's final nodes and
  /// the surface's points, with h(x) of the job's sizing field at every node (the default).
  mtr,
  /// -a<V>: one volume bound for every tet, V = h_max^3 / (6 sqrt 2), the volume of the
  /// regular tet of edge h_max (ignores the zones).
  volume,
  /// Only what the switches say.
  none,
};

/// "mtr", "volume", "none"; parse_tetgen_sizing throws UsageError for anything else.
const char* tetgen_sizing_name(TetgenSizing s);
TetgenSizing parse_tetgen_sizing(const std::string& name);

struct TetgenCompareOptions {
  /// TetGen switches chosen by the user (quality, e.g. "pq" or "pq1.414/12", optimisation
  /// level, ...). Must contain p; kdmesh appends z (0-based ids) and the sizing switch.
  std::string switches = "pq";
  TetgenSizing sizing = TetgenSizing::mtr;
  /// With mtr: the background mesh carries size_factor * h(x). TetGen reads a node's size as
  /// the largest circumradius allowed for the tets at it (it splits a tet whose circumradius
  /// exceeds the size at one of its vertices), not as an edge length; 1 hands it h(x) as is.
  double size_factor = 1;
  /// With mtr: the background mesh uses kdmesh's nodes thinned to about one per cube of edge
  /// background_spacing * h(x) (0: all of them). TetGen 1.5 walks its background mesh to find
  /// the size of each new point, often from a far tet, so its refinement time grows steeply
  /// with the background mesh (docs/tetgen_comparison.md); h(x) varies slowly (gradation), so a
  /// coarse background mesh loses little (size fidelity is measured on the exact h(x)).
  double background_spacing = 4;
  double timeout_seconds = 0;  ///< TetGen is killed after this (0 = no limit)
  std::string keep_dir;        ///< non-empty: write kdmesh.vtu and tetgen.vtu there
  /// Directory for the temporary copy of kdmesh's mesh (removed afterwards); "" = the
  /// system's temporary directory.
  std::string scratch_dir;
};

/// The complete TetGen switch string: the user's switches, then "z" and the sizing switch
/// ("m", or "a<V>" with V = h_max^3 / (6 sqrt 2)). Throws UsageError when the user's switches
/// lack p, or contain a switch that would break the comparison: r (refine a mesh), m or a
/// digits-after-a (the sizing belongs to --tetgen-sizing), i (insert points), w (weighted),
/// N / E (suppress the nodes / tets), o2 (quadratic), d (only detect intersections),
/// or a character TetGen does not know.
std::string tetgen_switch_string(const std::string& user, TetgenSizing sizing, double max_size);

/// A background mesh for TetGen's -m: tets over `points` (4 ids each, positively oriented)
/// and the target size at every point.
struct BackgroundMesh {
  PointSet points;
  std::vector<std::uint32_t> tets;
  std::vector<double> size;
};

/// `nodes` thinned to about one per cube of edge spacing * h(x): a node is kept unless an
/// earlier one fell in the same cell of size 2^l, where 2^l <= spacing * h(x) < 2^(l+1)
/// (cells of each level l tile space). spacing <= 0: all nodes. Deterministic.
PointSet thin_nodes(const PointSet& nodes, const SizingField& sizing, double spacing);

/// The Delaunay tetrahedralization (mesher/delaunay/delaunay.h) of thin_nodes(nodes, sizing, spacing)
/// together with every point of `surface` (so that it covers the whole solid: TetGen leaves
/// points outside its background mesh without a size), exact duplicates merged, with
/// size = sizing(x) at every point. Throws GeometryError if the points span no volume.
BackgroundMesh make_background_mesh(const PointSet& nodes, const SurfaceMesh& surface,
                                    const SizingField& sizing, double spacing = 0);

/// One point strictly inside each void of the solid (a shell with negative volume), for
/// TetGen's hole list: next to a facet of the void's shell, on its void side, at a distance
/// the surface query proves no other facet is closer than (so the point is in the void region
/// that facet bounds). Throws GeometryError if no facet of some void admits such a point.
PointSet void_hole_points(const PreparedSurface& surface, const SurfaceQuery& query);

/// TetGen's result, in kdmesh's conventions.
struct TetgenRun {
  TetMesh mesh;                 ///< TetGen's points and tets, every tet positively oriented
                                ///< (zero-volume tets, if any, kept as TetGen gave them)
  std::size_t flat_tets = 0;    ///< tets of zero volume (exact orient3d)
  double seconds = 0;           ///< wall time of tetrahedralize() alone
  /// TetGen's own stage times, in its order, from its "<stage> seconds: <t>" lines (CPU
  /// seconds by clock(); TetGen is single-threaded). Empty with the Q switch.
  std::vector<std::pair<std::string, double>> stages;
  /// Peak RSS during tetrahedralize() minus the RSS just before (after malloc_trim): about
  /// what TetGen's call allocated at its peak, its output arrays included.
  double added_peak_bytes = 0;
  std::string log;              ///< what TetGen printed
};

/// Meshes the surface with TetGen 1.5 (library) in a forked child process: TetGen's error exit
/// crashes the process that calls it (see mesher/reference/tetgen_delaunay.cpp), and a PLC TetGen
/// rejects (self-intersections, close facets, ...) must fail only the comparison.
/// `holes`: points in the voids (void_hole_points); `background`: required iff `switches`
/// contain m. Throws CheckError when TetGen reports an error (its code and the tail of its
/// log in the message), Error (ExitCode::failure) when it crashes, is killed or exceeds
/// `timeout_seconds` (> 0).
TetgenRun run_tetgen(const PreparedSurface& surface, const PointSet& holes,
                     const BackgroundMesh* background, const std::string& switches,
                     double timeout_seconds = 0);

/// The comparison's measures of one mesh, the same for both sides:
///   nodes (points used by a tet), tets, quality (mesher/tet_quality.h summarize_quality: tets,
///   inverted, min/max dihedral, mean/min radius ratio, max radius-edge, volume-length),
///   min_dihedral_below {"5", "10", "12"} (tets whose smallest dihedral is below, degrees),
///   volume {mesh, solid, relative_error}, size_fidelity (mesher/quality/size_fidelity.h against
///   `sizing`: edges, mean_ratio, fraction_in_range [0.7, 1.4], min_ratio, max_ratio).
nlohmann::json measure_mesh(const TetMesh& mesh, const SizingField& sizing, double solid_volume);

struct TetgenComparison {
  /// ok; the kdmesh job's code if it failed (TetGen then does not run); or TetGen's failure
  /// (check: TetGen reported an error; failure: it crashed or timed out).
  ExitCode code = ExitCode::ok;
  std::string error;  ///< one message when code != ok
  /// {job, input, method {...}, kdmesh {status, measures, seconds, peak_rss_bytes, summary},
  ///  tetgen {status, switches, counts, measures, seconds, added_peak_bytes, error?}}.
  nlohmann::json report;
  bool ok() const { return code == ExitCode::ok; }
};

/// Runs the job with run_mesh_job (its outputs replaced: kdmesh's mesh goes to a temporary
/// MEDIT file, read back to measure it per tet), then TetGen on the same prepared surface
/// with the same sizing, and measures both with measure_mesh. Never throws for the jobs'
/// own failures (they are in the result); throws UsageError for bad options.
TetgenComparison compare_with_tetgen(MeshJob job, const TetgenCompareOptions& options,
                                     const MeshJobCallbacks& callbacks = {});

/// Two side-by-side plain-text tables (quality, then time) of a comparison report, each
/// line ending in '\n'; a failed side shows its error instead of figures.
std::string format_comparison(const nlohmann::json& report);

}  // namespace kdmesh
