// kdmesh — batch files: YAML -> a list of MeshJob (the schema of `kdmesh batch`).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>
#include <vector>

#include "tools/app/mesh_job.h"

namespace kdmesh {

/// Batch file schema (pinned; README and models follow it):
///
///   defaults:      optional mapping; any job key; merged under every job (job keys win,
///                  a value replaces the default's whole value, lists and mappings included)
///   jobs:          required, non-empty list of mappings:
///     name         required, unique, [A-Za-z0-9_.-]+
///     input        required unless bodies is given; .stl, .ply, .obj or .off; relative to the YAML
///                  file's directory; must exist
///     bodies       instead of input: a non-empty list of {name, input}, several solids meshed
///                  together, region k = body k (name: [A-Za-z0-9_-]+, distinct; it names the
///                  region's volume group in the solver formats; input as above). Bodies may lie
///                  apart, one in another's void, or touch on faces (imprinted on each other:
///                  one conforming interface); overlapping ones, and ones that meet only along an
///                  edge or at a point, are refused, naming both and a point
///     scale        optional number > 0 (default 1)
///     size         required number > 0: h_max
///     min_size     optional number > 0, <= size (default size / 1000)
///     gradation    optional number > 0 (default 0.3)
///     sharp_angle  optional degrees in [0, 180) (default 30; 0 = no feature edges)
///     zones        optional list of mappings {type, size > 0, name?} plus, by type:
///                    sharp_edges: angle (degrees, default 30)
///                    polyline: points [[x,y,z], ...] (>= 2, consecutive ones distinct)
///                    segment: from [x,y,z], to [x,y,z]   (distinct)
///                    plane: origin [x,y,z], normal [x,y,z] (non-zero)
///                    point: at [x,y,z]
///                    box: min [x,y,z], max [x,y,z]       (min <= max)
///                    ball: center [x,y,z], radius > 0
///                  mapped to SizingZone with coords packed as sizing/sizing_field.h documents
///     curvature_angle   optional degrees in [0, 90] (default 15; 0 = off): size on curved
///                  surface parts <= this angle (as radians) x the radius of curvature
///     chordal_deviation optional 'auto' (default: from tolerance.volume), 0 (off) or a depth
///                  in model units: the boundary facets' mean depth below the curved surface
///     auto_creases optional bool (default true): surface edges bent by more than the angle at
///                  which a boundary face across them would leave tolerance.hausdorff become
///                  feature edges, even below sharp_angle
///     thickness_layers optional number in [0, 16] (default 2; 0 = off): walls get this many
///                  tets across, gaps boundary nodes no farther apart than their width
///     tolerance    optional mapping {hausdorff (default 0.1, times the local size), volume
///                  (default 0.005, relative)}: the mesh check's tolerances
///     max_refinements optional integer in [0, 64] (default 8): local refinements (size halved
///                  where the boundary is not recovered or not within tolerance) before failing;
///                  also the budget of the (at most 2) refinements around tets left below 12 deg
///     order        optional order name (mesher/order/order.h: kd-bfs-hilbert, kd-bfs, kd-bfs-alt,
///                  kd-local, hilbert, brio, random, input; default kd-bfs-hilbert)
///     seed         optional unsigned integer (default 1)
///     check        optional list of: tetgen, delaunay
///     max_memory   optional memory limit, e.g. 8G, 512M, none (default: the machine's memory);
///                  a job whose estimated peak memory exceeds it fails with exit 7 before placement
///     repair       optional list of opt-in surface repairs: degenerate, duplicates, orientation, all
///     groups       optional list of named boundary groups for the solver formats, each
///                    {name, dim (1 curves | 2 surface patches; default: from the zone, else 2),
///                     exactly one of zone: <sizing zone name> | point: [x,y,z] (the nearest
///                     patch / curve) | box: {min: [..], max: [..]} (everything inside)}
///     patch_groups optional bool: also a group per surface patch and feature curve (default false)
///     timeout      optional seconds > 0: the job is stopped and fails (exit 7) past it
///     improve      optional bool: quality improvement after meshing (default true)
///     element_order optional 1 or 2 (C3D10 / tet10 with mid-edge nodes on the surface)
///     msh_version  optional 4.1 (default) or 2.2
///     output       optional mapping {vtu, summary, nodes, msh, inp, mesh, boundary_vtu, xdmf,
///                  exodus}:
///                  paths relative to out_dir, inside it (BatchLoadOptions); no two outputs (of
///                  any jobs) may be one file, and no output may be any job's input. mesh is
///                  MEDIT; boundary_vtu the boundary faces and feature edges with their patch /
///                  curve ids and one 0/1 cell array per group (io/boundary_vtu_writer.h); xdmf
///                  XDMF for FEniCSx with cell and facet tags, its HDF5 data in the same path
///                  with extension .h5 (io/xdmf_writer.h), which counts as an output too; exodus
///                  Exodus II for MOOSE with element blocks, side sets and node sets
///                  (io/exodus_writer.h)
///
/// Every error is an InputError naming the file, the 1-based line and the key at fault:
/// unknown keys (with the closest valid key), wrong types, missing required keys, bad values,
/// duplicate keys or job names, missing inputs, two outputs writing one file, YAML syntax errors.
struct BatchConfig {
  std::string file;           ///< the YAML file as given
  std::vector<MeshJob> jobs;  ///< in file order; MeshJob::origin is "file:line" of the job
};

/// How a batch file is loaded.
struct BatchLoadOptions {
  /// Where outputs go: relative output paths are resolved against it; "" = the YAML file's
  /// directory.
  std::string out_dir;
  /// Accept outputs outside out_dir (absolute paths, '..', symbolic links leading out). Off: such
  /// an output is an InputError naming file:line and the key.
  bool allow_outside_out_dir = false;
  /// The memory limit (bytes; as MeshJob::max_memory: 0 = the machine's memory, < 0 = none). It
  /// bounds the batch file's size (kConfigBytesPerByte bytes of memory per byte of YAML) and each
  /// job's zone count (kBytesPerZone each), before the YAML is parsed.
  double max_memory = 0;
};

/// Memory yaml-cpp takes per byte of a batch file (measured: a 48 MB file of 1M zones took
/// 4.9 GB, ~100 bytes per byte), and the memory one sizing zone costs at most (its YAML nodes
/// and its share of the sizing field's search structures).
constexpr double kConfigBytesPerByte = 128, kBytesPerZone = 4096;

/// Loads and validates a batch file. Relative output paths are resolved against the output
/// directory (options.out_dir; default the YAML file's directory) and must stay inside it;
/// inputs are resolved against the YAML file's directory. The batch's paths are checked as one
/// run: no output is any job's input, and no two outputs are one file (by device and inode).
/// The file must be a regular file of one YAML document.
BatchConfig load_batch_config(const std::string& path, const BatchLoadOptions& options);
/// The same, with `out_dir` as options.out_dir and the other options' defaults.
BatchConfig load_batch_config(const std::string& path, const std::string& out_dir = "");

/// One job's options as a mapping of the job keys above (the same schema and checks; JSON is
/// YAML), for callers that hold the surface in memory (the Python module's keyword
/// arguments): `name` defaults to "mesh", `input` may be absent, relative paths are resolved
/// against the current directory and outputs may lie anywhere. InputError naming `label`.
MeshJob parse_job(const std::string& text, const std::string& label);

/// Levenshtein distance, and the candidate closest to `word` (for "did you mean" hints; ""
/// when none is reasonably close).
std::size_t edit_distance(const std::string& a, const std::string& b);
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace kdmesh
