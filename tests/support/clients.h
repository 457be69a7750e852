// Test support: run the real FE clients (gmsh, meshio through /usr/bin/python3, CalculiX ccx)
// and small text-file helpers for reading what they write.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace kdmesh::test {

struct ToolRun {
  int code;         ///< exit status, -1 if killed by a signal
  std::string out;  ///< stdout and stderr together
};

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_text_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

inline std::vector<std::string> text_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

/// Runs `cmd` through the shell with stdout and stderr captured to `log_base`.log.
inline ToolRun run_tool(const std::string& cmd, const std::string& log_base) {
  const std::string log = log_base + ".log";
  const int status = std::system((cmd + " >" + log + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_text(log)};
}

inline bool have_command(const std::string& cmd) {
  return std::system(("command -v " + cmd + " >/dev/null 2>&1").c_str()) == 0;
}

inline bool have_meshio() {
  return std::system("/usr/bin/python3 -c 'import meshio' >/dev/null 2>&1") == 0;
}

/// True when a missing client must fail the test instead of skipping it: the environment
/// variable KDMESH_REQUIRE_CLIENTS is set to 1 (tools/setup.sh test and sanitize set it, since
/// they install every client first).
inline bool clients_required() {
  const char* v = std::getenv("KDMESH_REQUIRE_CLIENTS");
  return v != nullptr && std::string(v) == "1";
}

}  // namespace kdmesh::test

/// Skips the test when `available` is false, or fails it when clients are required.
#define KDMESH_NEED_CLIENT(available, what)                                                   \
  do {                                                                                        \
    if (!(available)) {                                                                       \
      if (::kdmesh::test::clients_required()) FAIL() << what << " is required but missing";   \
      GTEST_SKIP() << what << " is not installed";                                            \
    }                                                                                         \
  } while (0)
