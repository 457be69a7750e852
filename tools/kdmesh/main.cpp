// kdmesh — command-line entry point. Every subcommand has --help; errors print one line and
// exit with the code of their class (core/error.h, README "Exit codes").
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <iostream>
#include <new>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tools/kdmesh/cli.h"

int main(int argc, char** argv) {
  // Every subcommand: SIGINT, SIGTERM and SIGHUP remove the temporaries of unfinished outputs.
  kdmesh::remove_temporaries_on_signal();
  CLI::App app{"kdmesh — tetrahedral mesh generator (kd-tree BFS insertion, exact Delaunay)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "kdmesh 0.1.0");
  kdmesh::cli::Runner run;
  kdmesh::cli::add_points_command(app, run);
  kdmesh::cli::add_delaunay_command(app, run);
  kdmesh::cli::add_mesh_command(app, run);
  kdmesh::cli::add_batch_command(app, run);
  kdmesh::cli::add_compare_tetgen_command(app, run);
  kdmesh::cli::add_bench_command(app, run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : int(kdmesh::ExitCode::usage);
  }
  try {
    return run();
  } catch (const kdmesh::Error& e) {
    kdmesh::cli::print_error(e.what());
    return int(e.code());
  } catch (const std::bad_alloc&) {
    kdmesh::cli::print_error("out of memory");
    return int(kdmesh::ExitCode::failure);
  } catch (const std::exception& e) {
    kdmesh::cli::print_error(e.what(), "internal error");
    return int(kdmesh::ExitCode::failure);
  }
}
