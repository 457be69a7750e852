// kdmesh CLI — the options of one meshing job, shared by `kdmesh mesh` and `kdmesh compare-tetgen`.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "tools/kdmesh/cli.h"
#include "tools/app/mesh_job.h"

namespace kdmesh::cli {

/// What the command line says about one job: the surface, its sizing, the pipeline switches
/// and (for `kdmesh mesh`) its outputs. Defaults are those of `kdmesh mesh --help`.
struct MeshCliOptions {
  std::string input;
  std::vector<std::string> bodies;  ///< --body NAME=PATH, instead of input
  double size = 0;
  double refine_edges = 0;  ///< 0: no sharp_edges zone
  double edge_size = 0;     ///< 0: size / 4
  double min_size = 0;      ///< 0: size / 1000
  double gradation = 0.3;
  double sharp_angle = 30;
  double scale = 1;
  std::string order = "kd-bfs-hilbert";
  std::uint64_t seed = 1;
  std::vector<std::string> checks;
  std::string max_memory;   ///< empty: the machine's memory
  std::string repair;       ///< comma-separated opt-in repairs
  std::string output, summary, nodes;
  std::string msh, inp, medit, boundary_vtu, xdmf, exodus;
  int element_order = 1;
  std::string msh_version = "4.1";
  bool patch_groups = false;
  bool no_improve = false;
  double curvature_angle = 15;     ///< degrees; 0 = no curvature term
  double chordal_deviation = -1;   ///< < 0: derived from the volume tolerance; 0 = off
  bool no_auto_creases = false;
  double thickness_layers = 2;     ///< 0 = no thickness term
  double hausdorff_tolerance = 0.1;
  double volume_tolerance = 0.005;
  int max_refinements = 8;
};

/// Which of the options a subcommand offers.
struct MeshCliSpec {
  /// `input` and `--size` are required (kdmesh mesh). When false they are optional and the
  /// subcommand checks them itself (e.g. compare-tetgen, where --config replaces them).
  bool input_required = true;
  /// --body NAME=PATH (repeatable): several named solids instead of `input` (kdmesh mesh).
  bool bodies = true;
  /// The output options (-o, --summary, --nodes, --msh, --inp, --medit, --boundary-vtu, --xdmf, --exodus,
  /// --element-order, --msh-version, --patch-groups).
  bool outputs = true;
};

/// Callbacks that print a job's stages through `out` (stage lines) and one progress line per
/// stage (rewritten in place on a terminal; silent otherwise). `out` must outlive them.
MeshJobCallbacks job_callbacks(const Output& out);

/// Registers the job's options on `cmd` (names, help texts, checks and defaults of
/// `kdmesh mesh`), storing into `o`, which must outlive the parse.
void add_mesh_job_options(CLI::App* cmd, MeshCliOptions& o, const MeshCliSpec& spec = {});

/// The MeshJob the options describe (name: the input's stem). Throws UsageError for
/// inconsistent values (--min-size above --size, --edge-size without --refine-edges, a bad
/// --max-memory or --repair).
MeshJob make_mesh_job(const MeshCliOptions& o);

}  // namespace kdmesh::cli
