// Test support: run the kdmesh executable and capture its exit code, stdout and stderr.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace kdmesh::test {

struct CliResult {
  int code;  ///< exit status, -1 if killed by a signal
  std::string out, err;
};

/// A scratch directory for this test process: KDMESH_TEST_TMP/<area>-<pid>. ctest runs every
/// test case as its own process, in parallel, so names are unique per process.
inline std::filesystem::path process_tmpdir(const std::string& area) {
  static const std::filesystem::path d = [&] {
    std::filesystem::path p = std::filesystem::path(KDMESH_TEST_TMP) / (area + "-" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return p;
  }();
  return d;
}

/// True if `s` contains `part`.
inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// A fresh (emptied) directory `name` under `base`.
inline std::filesystem::path fresh_dir(const std::filesystem::path& base, const std::string& name) {
  const std::filesystem::path d = base / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Runs `kdmesh <args>` (the build's executable), capturing its output through files in `dir`.
/// `env` is prepended to the shell command, e.g. "NAME='value'".
inline CliResult run_kdmesh(const std::string& args, const std::filesystem::path& dir,
                            const std::string& env = "") {
  static int counter = 0;
  const std::string tag = std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const std::filesystem::path out = dir / ("stdout-" + tag), err = dir / ("stderr-" + tag);
  const std::string cmd = (env.empty() ? "" : env + " ") + std::string(KDMESH_EXE) + " " + args +
                          " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace kdmesh::test
