// kdmesh — one meshing job (surface file -> checked tet mesh + summary), the whole pipeline.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "mesher/mesh_solid.h"

namespace kdmesh {

/// One meshing job: the pipeline's parameters (mesher/mesh_solid.h; name and input, the
/// surface file's path usable as is, are among them) plus where it was defined, its batch time
/// limit and its output files (what `kdmesh mesh` options and one entry of a batch file map
/// to; see tools/app/job_config.h for the YAML schema).
/// One named body of a job's `bodies` list: its name (its region's) and its surface file.
struct BodyInput {
  std::string name, input;
};

struct MeshJob : MeshParams {
  std::string origin;          ///< where it was defined, e.g. "jobs.yaml:12" (may be empty)
  /// Several named solids meshed together, each read from its own file (mesh_solid on a list
  /// of NamedSurface); empty: the one surface `input`. MeshParams::input then lists them.
  std::vector<BodyInput> bodies;
  /// Wall-clock limit in seconds when run in a batch (tools/app/job_process.h); 0 = none.
  double timeout = 0;
  std::string vtu, summary, nodes;  ///< output paths (usable as is); empty = not written
  /// Solver formats (usable as is; empty = not written): Gmsh MSH, Abaqus/CalculiX INP, MEDIT,
  /// the boundary VTU (faces and feature edges with patch / curve ids and one 0/1 array per
  /// boundary group, io/boundary_vtu_writer.h), XDMF (with its HDF5 file beside it,
  /// io/xdmf_writer.h) and Exodus II (io/exodus_writer.h). Any of them turns on the boundary
  /// groups stage (MeshParams::fe_groups).
  std::string msh, inp, medit, boundary_vtu, xdmf, exodus;
  int msh_version = 41;        ///< 41 or 22
};

/// Every output path the job writes (the non-empty ones, the XDMF's HDF5 file included), e.g.
/// to clean up after a crash.
std::vector<std::string> output_paths(const MeshJob& job);

/// Whether the job writes a solver format (msh, inp, medit, boundary_vtu, xdmf, exodus): those need
/// the boundary groups stage.
bool has_solver_outputs(const MeshJob& job);

/// Callbacks of a running job (log, progress, cancel): those of the front door.
using MeshJobCallbacks = MeshCallbacks;

struct MeshJobResult {
  ExitCode code = ExitCode::ok;  ///< ok, or the class of the error that failed the job
  /// The job's summary (also written to job.summary when it succeeds):
  ///   job, input, status ("ok" | "failed"),
  ///   bodies [{name, input, region, solid_volume, mesh_volume, volume_error, tets}] (named
  ///           bodies only; the last three once the mesh is checked),
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
  ///   boundary_vtu, xdmf, xdmf_h5, exodus, summary} (the files written, by kind),
  ///   error {type, exit_code, message} (failed jobs only).
  /// Keys of stages a failed job never reached are absent.
  nlohmann::json summary;
  bool ok() const { return code == ExitCode::ok; }
};

/// Runs one job: read the surface -> mesh_solid (mesher/mesh_solid.h) -> [Delaunay checks of
/// the final nodes] -> outputs and the summary (report_json).
/// Never throws: every error (typed kdmesh::Error, bad_alloc, any std::exception) is caught and
/// returned in the result with its exit code, so that one job cannot affect another. A failed
/// mesh check (or Delaunay check) fails the job with ExitCode::check. A failed job writes no
/// output at all: every output is first written to a temporary file, and all are renamed into
/// place only once every one of them has been written.
MeshJobResult run_mesh_job(const MeshJob& job, const MeshJobCallbacks& callbacks = {});

/// What run_mesh_job runs, throwing instead (the typed kdmesh::Error of the failure), and
/// returning the mesh: `summary` is filled as the job goes (so a failure still has what was
/// measured; record_failure then marks it). With `surface` given, the job meshes it instead
/// of reading job.input (which then only names it in messages).
MeshResult run_job(const MeshJob& job, const MeshJobCallbacks& callbacks, nlohmann::json& summary,
                   const SurfaceMesh* surface = nullptr);

/// Marks `summary` failed by `error` (status, error {type, exit_code, message}, no outputs,
/// seconds.total); returns the error's exit code.
ExitCode record_failure(nlohmann::json& summary, std::exception_ptr error, double seconds);

/// The summary's figures of a report (counts, estimate, repairs, automatic_sizing, thickness,
/// improve, mesh_check, quality, size_fidelity, boundary, groups (with `fe`), quadratic,
/// seconds, notices, solid_volume, bbox), merged into `j`: the keys of stages the report never
/// reached are left out.
void add_report_json(const MeshReport& report, const FeMesh* fe, nlohmann::json& j);

/// The summary's "quality" block: tets, inverted, min/max dihedral, mean/min radius ratio, max
/// radius-edge, mean/min volume-length, and the two histograms {lo, hi, counts}.
nlohmann::json quality_json(const QualitySummary& q);

/// The summary's "size_fidelity" block: edges, mean_ratio, fraction_in_range, range,
/// short/long_fraction, min/max_ratio, away_edges, away_mean_ratio.
nlohmann::json size_fidelity_json(const SizeFidelity& f);

/// A short human-readable table of a job summary (counts, quality, size fidelity, check,
/// times, outputs or the error), one item per line, each line ending in '\n'.
std::string format_job_report(const nlohmann::json& summary);

/// The error class name used in summaries: "input", "surface", "geometry", "check", "output",
/// "usage", "internal" (exit codes of core/error.h).
std::string error_type_name(ExitCode code);

}  // namespace kdmesh
