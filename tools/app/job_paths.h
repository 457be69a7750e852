// kdmesh — the files a meshing job reads and writes, checked before any work is done.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "core/path_clash.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {

/// One file a job writes: its batch-file output key ("vtu", "summary", "nodes", "msh", "inp",
/// "mesh" (MEDIT), "boundary_vtu", "xdmf", "xdmf_h5" for the XDMF file's HDF5 data, "exodus"), a
/// label for messages ("vtu output", ...) and the path.
struct JobOutput {
  const char* key;
  const char* label;
  std::string path;
};

/// The job's outputs in a fixed order, the empty ones left out; an xdmf output brings its HDF5
/// file (io/xdmf_writer.h: xdmf_hdf5_path) right after it.
std::vector<JobOutput> job_outputs(const MeshJob& job);

/// The job's input and every output it writes, labelled "input", "vtu output", ... .
std::vector<PathUse> job_path_uses(const MeshJob& job);

/// Checks a job's paths before any work: each output may be created as, or replace, a regular
/// file (check_output_target; OutputError, exit 6), and no output is the job's input or another
/// of its outputs, compared by device and inode (UsageError, exit 2).
void check_job_paths(const MeshJob& job);

/// The same for a run with one input and outputs given by option (label: the option name);
/// empty outputs are not written and skipped.
void check_run_paths(const std::string& input, const std::vector<std::pair<std::string, std::string>>& outputs);

}  // namespace kdmesh
