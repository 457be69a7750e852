// kdmesh — atomic outputs: write to a temporary file beside the target, then rename.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

namespace kdmesh {

/// Usage:
///   AtomicFile out(path);           // picks "<path>.tmp-<pid>-<n>" in the same directory
///   write_everything(out.temp_path());
///   out.commit();                   // rename(temp, path); throws OutputError on failure
/// If commit() is never reached (exception, early return) the destructor removes the
/// temporary file, so a failure never leaves a half-written or stale output behind.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_; }
  void commit();

 private:
  std::string path_;
  std::string temp_;
  bool committed_ = false;
  int slot_ = -1;  ///< registration for remove_temporaries_on_signal()
};

/// Installs SIGINT and SIGTERM handlers that remove every temporary file of a live
/// AtomicFile, then die of the signal as usual (exit status 128 + signal). So an interrupted
/// run leaves neither a partial output nor a stray temporary file. Executables call it once.
void remove_temporaries_on_signal();

/// Removes the temporary files an AtomicFile for `path` created in process `pid`
/// ("<path>.tmp-<pid>-<n>"), e.g. after that process crashed. Returns how many were removed.
/// Never throws (an unreadable directory removes nothing).
int remove_temporaries_of(const std::string& path, long pid);

}  // namespace kdmesh
