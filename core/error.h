// kdmesh — typed errors. Library code throws these; executables map them to exit codes.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace kdmesh {

/// Process exit codes, one per class of error (documented in the README).
enum class ExitCode : int {
  ok = 0,
  failure = 1,      ///< unexpected internal error
  usage = 2,        ///< bad command line
  input = 3,        ///< unreadable or malformed input file
  geometry = 4,     ///< input that has no valid result (e.g. all points coplanar)
  check = 5,        ///< a --check verification found a mismatch
  output = 6,       ///< an output file could not be written
  resource = 7,     ///< the job would exceed a resource limit (e.g. --max-memory)
  cancelled = 130,  ///< the caller cancelled the job (128 + SIGINT, as a shell reports Ctrl-C)
};

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what, ExitCode code = ExitCode::failure)
      : std::runtime_error(what), code_(code) {}
  ExitCode code() const { return code_; }

 private:
  ExitCode code_;
};

/// A malformed or unreadable input file. `line` is 1-based, 0 when not applicable.
class InputError : public Error {
 public:
  InputError(const std::string& file, std::uint64_t line, const std::string& msg)
      : Error(where(file, line) + msg, ExitCode::input),
        file_(file),
        line_(line) {}
  const std::string& file() const { return file_; }
  std::uint64_t line() const { return line_; }

 private:
  /// "file:line: " (or "file: "), appended piece by piece: `":" + std::to_string(line)` made
  /// GCC 12 warn falsely (-Wrestrict, GCC bug 105329) wherever this was inlined.
  static std::string where(const std::string& file, std::uint64_t line) {
    std::string s = file;
    if (line) {
      s += ':';
      s += std::to_string(line);
    }
    s += ": ";
    return s;
  }
  std::string file_;
  std::uint64_t line_;
};

/// Input that is readable but admits no result (empty, all coplanar, ...).
class GeometryError : public Error {
 public:
  explicit GeometryError(const std::string& msg) : Error(msg, ExitCode::geometry) {}
};

/// The boundary of a solid could not be recovered by the mesher: a GeometryError that says
/// where (3 coordinates per place: bad boundary faces' centroids, non-manifold edges'
/// midpoints and vertices), so that a caller can refine the sizing there and try again.
class BoundaryRecoveryError : public GeometryError {
 public:
  BoundaryRecoveryError(const std::string& msg, std::vector<double> where)
      : GeometryError(msg), where_(std::move(where)) {}
  const std::vector<double>& where() const { return where_; }

 private:
  std::vector<double> where_;
};

/// A verification (validity check, TetGen/CGAL comparison) failed.
class CheckError : public Error {
 public:
  explicit CheckError(const std::string& msg) : Error(msg, ExitCode::check) {}
};

/// An output file could not be written.
class OutputError : public Error {
 public:
  OutputError(const std::string& file, const std::string& msg)
      : Error(file + ": " + msg, ExitCode::output), file_(file), reason_(msg) {}
  const std::string& file() const { return file_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, reason_;
};

/// A job refused before it starts because it would exceed a resource limit (memory).
class ResourceError : public Error {
 public:
  explicit ResourceError(const std::string& msg) : Error(msg, ExitCode::resource) {}
};

/// A bad option value passed to a library function or command.
class UsageError : public Error {
 public:
  explicit UsageError(const std::string& msg) : Error(msg, ExitCode::usage) {}
};

}  // namespace kdmesh
