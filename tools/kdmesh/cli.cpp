// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/kdmesh/cli.h"

#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>
#include <iostream>

namespace kdmesh::cli {

std::ostream& Output::human() const { return json ? std::cerr : std::cout; }

void Output::stage(const std::string& msg) const {
  if (!quiet) std::cerr << ("kdmesh: " + msg + "\n") << std::flush;  // one write (print_error)
}

void print_error(const std::string& message, const char* what) {
  std::cerr << ("kdmesh: " + std::string(what) + ": " + message + "\n") << std::flush;
}

std::function<void(double)> Output::progress(const std::string& what) const {
  if (quiet) return {};
  if (!isatty(STDERR_FILENO)) {  // logs: one whole line per 25% step
    auto last = std::make_shared<int>(-1);
    return [what, last](double f) {
      const int step = int(f * 4);
      if (step <= *last) return;
      *last = step;
      std::fprintf(stderr, "kdmesh: %s %d%%\n", what.c_str(), 25 * step);
    };
  }
  return [what](double f) {
    std::fprintf(stderr, "\rkdmesh: %s %5.1f%%%s", what.c_str(), 100.0 * f, f >= 1.0 ? "\n" : "");
    std::fflush(stderr);
  };
}

void Output::emit_json(const nlohmann::json& j) const {
  if (json) std::cout << j.dump(2) << std::endl;
}

CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& value) { return value.empty() ? std::string("the path is empty") : std::string(); }, "PATH");
}

void add_output_flags(CLI::App* cmd, Output& out) {
  cmd->add_flag("--json", out.json, "Print a machine-readable JSON summary on stdout");
  cmd->add_flag("-q,--quiet", out.quiet, "No progress messages on stderr");
}

}  // namespace kdmesh::cli
