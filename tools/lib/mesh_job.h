// kdmesh — one meshing job (surface file -> checked tet mesh + summary), the whole pipeline.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "mesher/boundary_groups.h"
#include "mesher/mesh_check.h"
#include "mesher/order.h"
#include "mesher/quality.h"
#include "mesher/surface_repair.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// Everything one run of the pipeline needs (what `kdmesh mesh` options and one entry of a
/// batch file map to; see tools/lib/job_config.h for the YAML schema).
struct MeshJob {
  std::string name;            ///< job name (messages, summaries)
  std::string origin;          ///< where it was defined, e.g. "jobs.yaml:12" (may be empty)
  std::string input;           ///< STL or PLY surface, a path usable as is
  double scale = 1;            ///< coordinates are multiplied by it (> 0)
  double sharp_angle = 30;     ///< degrees; feature edges kept in the mesh; 0 = none
  SizingOptions sizing;        ///< max_size (> 0) is the job's `size`
  OrderOptions order;          ///< insertion order; order.seed == seed
  std::uint64_t seed = 1;      ///< node placement and order seed
  bool check_tetgen = false;   ///< compare the nodes' Delaunay with TetGen 1.5 and CGAL 5.5
  bool check_delaunay = false; ///< exact validity check of the nodes' Delaunay
  /// Memory limit in bytes: the job is refused (ResourceError, exit 7) before node placement
  /// when its estimated peak memory exceeds it. 0 = the machine's physical memory; < 0 = none.
  double max_memory = 0;
  /// Wall-clock limit in seconds when run in a batch (tools/lib/job_process.h); 0 = none.
  double timeout = 0;
  SurfaceRepairOptions repair; ///< opt-in safe surface repairs, reported as notices
  /// Automatic sizing terms, on by default; each is announced by a notice when it shrinks the
  /// size below what the job asks (never below sizing.min_size):
  ///  - curvature: h <= curvature_angle (degrees, as radians) x the local radius of curvature
  ///    of the smooth surface; 0 = off;
  ///  - chordal deviation: the boundary facets' mean depth below the curved surface stays within
  ///    a share of the volume tolerance (chordal_deviation < 0: derived from
  ///    check.volume_tolerance; 0 = off; > 0: that depth in model units);
  ///  - creases: surface edges bent by more than the angle at which a boundary face across
  ///    them would leave the distance tolerance become feature edges (kept by nodes), even
  ///    below sharp_angle.
  ///  - thickness: walls get at least thickness_layers tets across, and gaps (slots, holes,
  ///    close sheets) boundary nodes no farther apart than the gap; 0 = off.
  double curvature_angle = 15;
  double chordal_deviation = -1;
  bool auto_creases = true;
  double thickness_layers = 2;
  /// The mesh check's tolerances (mesher/mesh_check.h); the sizing aims inside them.
  MeshCheckOptions check;
  /// Local refinement: when the boundary cannot be recovered, or the check finds faces too far
  /// from the surface or the volume off, the size is halved around those places and the job
  /// meshed again, at most this many times (and never below sizing.min_size).
  int max_refinements = 8;
  bool improve = true;         ///< quality improvement after meshing (mesher/mesh_improve.h)
  std::string vtu, summary, nodes;  ///< output paths (usable as is); empty = not written
  /// Solver formats (usable as is; empty = not written): Gmsh MSH, Abaqus/CalculiX INP, MEDIT,
  /// and the boundary VTU (faces and feature edges with patch / curve ids and one 0/1 array per
  /// boundary group, io/boundary_vtu_writer.h). Any of them turns on the boundary groups stage.
  std::string msh, inp, medit, boundary_vtu;
  int msh_version = 41;        ///< 41 or 22
  int element_order = 1;       ///< 1 (C3D4 / tet4) or 2 (C3D10 / tet10) in the solver formats
  std::vector<GroupSpec> groups;  ///< named boundary groups (mesher/boundary_groups.h)
  GroupOptions group_options;     ///< automatic patch_<i> / curve_<i> groups
};

/// Every output path the job writes (the non-empty ones), e.g. to clean up after a crash.
std::vector<std::string> output_paths(const MeshJob& job);

/// Callbacks of a running job; each may be empty. They are called from the job's thread.
struct MeshJobCallbacks {
  /// A stage starts or a notice is emitted (one line, no trailing newline).
  std::function<void(const std::string& message)> log;
  /// Progress inside a long stage: stage name ("interior", "delaunay", ...) and fraction in [0, 1].
  std::function<void(const std::string& stage, double fraction)> progress;
};

struct MeshJobResult {
  ExitCode code = ExitCode::ok;  ///< ok, or the class of the error that failed the job
  /// The job's summary (also written to job.summary when it succeeds):
  ///   job, input, status ("ok" | "failed"),
  ///   counts {surface_points, surface_facets, shells, bodies, feature_edges, feature_corners,
  ///           placed_nodes, nodes, nodes_by_kind {corner, edge, surface, interior},
  ///           steiner_points, dropped_nodes, steiner_rounds, tets, boundary_faces},
  ///   estimate {nodes, surface_nodes, interior_nodes, peak_bytes, capped, limit_bytes},
  ///   repairs {...} (when asked), improve {edge_removals, face_removals, relaxed, smoothed,
  ///   boundary_changes} (when on), boundary, groups [{name, dim, entities (how many entities
  ///   it lists), elements (tets / boundary faces / feature-edge segments of those entities)}],
  ///   quadratic (order 2) (these three with solver outputs),
  ///   seconds {read, prepare, features, sizing, query, estimate, place, mesh, improve,
  ///            delaunay_check, mesh_check, quality, groups, write, total,
  ///            mesh_stages {order, delaunay (all rounds), first_delaunay, classify, recover}},
  ///   size_fidelity {edges, mean_ratio, fraction_in_range, range [0.7, 1.4]},
  ///   quality {tets, inverted, min_dihedral, max_dihedral (degrees), mean_radius_ratio,
  ///            min_radius_ratio, max_radius_edge, min_dihedral_hist, radius_ratio_hist},
  ///   mesh_check {... every MeshCheck figure ..., pass, failures},
  ///   delaunay_check (when asked), notices [...], outputs {vtu, nodes, msh, inp, medit,
  ///   boundary_vtu, summary} (the files written, by kind),
  ///   error {type, exit_code, message} (failed jobs only).
  /// Keys of stages a failed job never reached are absent.
  nlohmann::json summary;
  bool ok() const { return code == ExitCode::ok; }
};

/// Runs the pipeline for one job:
///   read -> prepare (scale) -> sharp features -> sizing field -> surface query -> node placement
///   -> volume mesh -> [Delaunay checks of the final nodes] -> mesh check -> quality and size
///   fidelity -> outputs.
/// Never throws: every error (typed kdmesh::Error, bad_alloc, any std::exception) is caught and
/// returned in the result with its exit code, so that one job cannot affect another. A failed
/// mesh check (or Delaunay check) fails the job with ExitCode::check. A failed job writes no
/// output at all: every output is first written to a temporary file, and all are renamed into
/// place only once every one of them has been written.
MeshJobResult run_mesh_job(const MeshJob& job, const MeshJobCallbacks& callbacks = {});

/// The summary's "quality" block: tets, inverted, min/max dihedral, mean/min radius ratio, max
/// radius-edge, mean/min volume-length, and the two histograms {lo, hi, counts}.
nlohmann::json quality_json(const QualitySummary& q);

/// A short human-readable table of a job summary (counts, quality, size fidelity, check,
/// times, outputs or the error), one item per line, each line ending in '\n'.
std::string format_job_report(const nlohmann::json& summary);

/// The error class name used in summaries: "input", "surface", "geometry", "check", "output",
/// "usage", "internal" (exit codes of core/error.h).
std::string error_type_name(ExitCode code);

}  // namespace kdmesh
