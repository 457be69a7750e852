// kdmesh compare-tetgen — the same surface meshed by kdmesh and by TetGen 1.5 (-pq) at a
// matching size; quality and time side by side.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"
#include "mesher/reference/reference_delaunay.h"
#include "tools/kdmesh/cli.h"
#include "tools/kdmesh/mesh_options.h"
#include "tools/app/job_config.h"
#include "tools/app/mesh_job.h"
#include "tools/compare/tetgen_compare.h"

namespace kdmesh::cli {

namespace {

struct Options {
  MeshCliOptions mesh;
  std::string config, job;
  std::string switches = "pq";
  std::string sizing = "mtr";
  double size_factor = 1;
  double background_spacing = 4;
  double timeout = 0;
  std::string keep;
  Output out;
  bool job_options_given = false;  ///< a mesh option was given on the command line
};

/// The job of a batch file: the one named, or the only one.
MeshJob config_job(const std::string& file, const std::string& name) {
  BatchConfig config = load_batch_config(file);  // InputError: exit 3
  std::vector<std::string> names;
  for (const MeshJob& j : config.jobs) names.push_back(j.name);
  std::string all;
  for (const std::string& n : names) all += (all.empty() ? "" : ", ") + n;
  if (name.empty()) {
    if (config.jobs.size() != 1)
      throw UsageError(file + " has " + std::to_string(config.jobs.size()) + " jobs: choose one with --job (" + all + ")");
    return std::move(config.jobs.front());
  }
  for (MeshJob& j : config.jobs)
    if (j.name == name) return std::move(j);
  const std::string near = closest_match(name, names);
  throw UsageError("--job " + name + ": no such job in " + file +
                   (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; jobs: " + all);
}

int run_compare(const Options& o) {
  if (!tetgen_available()) throw UsageError(without_tetgen_message("compare-tetgen"));
  const Output& out = o.out;
  MeshJob job;
  if (!o.config.empty()) {
    if (o.job_options_given)
      throw UsageError("--config takes the surface and every job option from the YAML file; give either a "
                       "surface with its options or --config, not both");
    job = config_job(o.config, o.job);
  } else {
    if (!o.job.empty()) throw UsageError("--job needs --config");
    if (o.mesh.input.empty()) throw UsageError("compare-tetgen needs a surface file with --size, or --config FILE");
    if (!(o.mesh.size > 0)) throw UsageError("--size is required with a surface file");
    job = make_mesh_job(o.mesh);
  }
  TetgenCompareOptions co;
  co.switches = o.switches;
  co.sizing = parse_tetgen_sizing(o.sizing);
  co.size_factor = o.size_factor;
  if (co.size_factor != 1 && co.sizing != TetgenSizing::mtr)
    throw UsageError("--tetgen-size-factor applies to --tetgen-sizing mtr only");
  co.background_spacing = o.background_spacing;
  if (o.background_spacing != 4 && co.sizing != TetgenSizing::mtr)
    throw UsageError("--tetgen-background-spacing applies to --tetgen-sizing mtr only");
  co.timeout_seconds = o.timeout;
  co.keep_dir = o.keep;

  const MeshJobCallbacks cb = job_callbacks(out);
  const TetgenComparison c = compare_with_tetgen(job, co, cb);
  out.human() << format_comparison(c.report);
  out.emit_json(c.report);
  if (!c.ok()) {
    print_error(c.error);
    return int(c.code);
  }
  return 0;
}

}  // namespace

void add_compare_tetgen_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "compare-tetgen",
      "Mesh a surface with kdmesh and with TetGen 1.5 (-pq) at the same size; print both quality and "
      "time tables side by side");
  MeshCliSpec spec;
  spec.input_required = false;
  spec.bodies = false;  // TetGen meshes one surface
  spec.outputs = false;
  add_mesh_job_options(cmd, o->mesh, spec);
  std::vector<CLI::Option*> job_options = cmd->get_options();  // input, --size, ... (and --help)
  cmd->add_option("--config", o->config,
                  "A batch file (YAML, see `kdmesh batch`): its job replaces the surface and the job options");
  cmd->add_option("--job", o->job, "The job of --config to compare (needed when it has several)");
  cmd->add_option("--tetgen-switches", o->switches,
                  "TetGen switches: p plus quality, e.g. pq, pq1.414/12, pq1.2O7; z and the sizing "
                  "switch are added")
      ->capture_default_str();
  cmd->add_option("--tetgen-sizing", o->sizing,
                  "How TetGen gets the size: mtr (-m with a background mesh: the Delaunay of kdmesh's "
                  "nodes carrying h(x)), volume (-a: the regular tet of edge --size, no zones), none")
      ->check(CLI::IsMember({"mtr", "volume", "none"}))
      ->capture_default_str();
  cmd->add_option("--tetgen-size-factor", o->size_factor,
                  "With mtr: TetGen's node sizes are this times h(x) (TetGen reads a size as the "
                  "largest circumradius of the tets at a node, not as an edge length)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--tetgen-background-spacing", o->background_spacing,
                  "With mtr: the background mesh keeps about one kdmesh node per cube of this times "
                  "h(x) (0: every node; TetGen 1.5's size lookup slows down steeply with its size)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--tetgen-timeout", o->timeout, "Stop TetGen after this many seconds (0: no limit)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--keep", o->keep, "Also write both meshes there: kdmesh.vtu and tetgen.vtu")
      ->check(non_empty_path());
  add_output_flags(cmd, o->out);
  const CLI::Option* help = cmd->get_help_ptr();
  cmd->callback([o, help, job_options, &run] {
    for (const CLI::Option* opt : job_options)
      if (opt != help && opt->count() > 0) o->job_options_given = true;
    run = [o] { return run_compare(*o); };
  });
}

}  // namespace kdmesh::cli
