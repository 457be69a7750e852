// kdmesh CLI — shared plumbing for subcommands (executable-internal header).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <iosfwd>
#include <string>

namespace kdmesh::cli {

/// Where a subcommand's output goes. Human-readable text goes to stdout, or to stderr when
/// --json is given (stdout then carries exactly one JSON document). Progress goes to stderr.
struct Output {
  bool json = false;
  bool quiet = false;
  std::ostream& human() const;
  /// "stage: message" on stderr unless --quiet.
  void stage(const std::string& msg) const;
  /// A callback for long loops: rewrites one stderr line with the percentage when stderr is a
  /// terminal; silent otherwise (logs stay readable).
  std::function<void(double)> progress(const std::string& what) const;
  void emit_json(const nlohmann::json& j) const;
};

/// A check for path options: an empty value ("") is an error, not "no output".
CLI::Validator non_empty_path();

/// Adds --json and --quiet to a subcommand.
void add_output_flags(CLI::App* cmd, Output& out);

/// "kdmesh: <what>: <message>" on stderr in one write: under mpirun, whose own messages go
/// to the same stream, a line written piece by piece could be cut apart.
void print_error(const std::string& message, const char* what = "error");

using Runner = std::function<int()>;

/// Each subcommand registers itself and sets `run` to its action when it is selected.
void add_points_command(CLI::App& app, Runner& run);
void add_delaunay_command(CLI::App& app, Runner& run);
void add_bench_command(CLI::App& app, Runner& run);
void add_mesh_command(CLI::App& app, Runner& run);
void add_batch_command(CLI::App& app, Runner& run);
void add_compare_tetgen_command(CLI::App& app, Runner& run);

}  // namespace kdmesh::cli
