// kdmesh mesh — tetrahedral mesh of a closed surface (STL/PLY): the whole pipeline, checked.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <iostream>
#include <memory>
#include <string>

#include "core/error.h"
#include "tools/kdmesh/cli.h"
#include "tools/kdmesh/mesh_options.h"
#include "tools/app/mesh_job.h"

namespace kdmesh::cli {

namespace {

struct Options {
  MeshCliOptions mesh;
  Output out;
};

int run_mesh(const Options& o) {
  const Output& out = o.out;
  if (o.mesh.input.empty() && o.mesh.bodies.empty())
    throw UsageError("input: give a surface file (.stl, .ply, .obj or .off), or --body NAME=PATH for each body");
  const MeshJob job = make_mesh_job(o.mesh);
  const MeshJobCallbacks cb = job_callbacks(out);
  const MeshJobResult r = run_mesh_job(job, cb);
  out.human() << format_job_report(r.summary);
  out.emit_json(r.summary);
  if (!r.ok()) {
    print_error(r.summary["error"]["message"].get<std::string>());
    return int(r.code);
  }
  return 0;
}

}  // namespace

void add_mesh_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "mesh", "Tetrahedral mesh of a closed surface (.stl, .ply, .obj, .off), checked as an FE domain");
  add_mesh_job_options(cmd, o->mesh);
  add_output_flags(cmd, o->out);
  cmd->callback([o, &run] { run = [o] { return run_mesh(*o); }; });
}

}  // namespace kdmesh::cli
