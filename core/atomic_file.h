// kdmesh — atomic outputs: write to an exclusively created temporary file beside the target,
// then rename; several outputs of one run committed all or nothing.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace kdmesh {

/// Throws OutputError naming `path` unless an output may be created there: the path is not
/// empty, does not end in '/', '.' or '..', and is either absent or a regular file (per lstat:
/// a device node, FIFO, socket, directory or symbolic link is never replaced).
void check_output_target(const std::string& path);

/// Usage:
///   AtomicFile out(path);           // checks the target, creates the temporary exclusively
///   write_everything(out.temp_path());
///   out.commit();                   // rename(temp, path); throws OutputError on failure
/// The constructor checks the target (check_output_target) and creates the temporary file with
/// O_CREAT | O_EXCL | O_NOFOLLOW under an unpredictable name in the target's directory:
/// "<file name, cut to fit>.tmp-<pid>-<16 random hex digits>". So a planted file or symbolic
/// link is never opened, and a long output name still leaves room for the suffix.
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
  friend class AtomicFileSet;
  std::string path_;
  std::string temp_;
  bool committed_ = false;
  int slot_ = -1;  ///< registration for remove_temporaries_on_signal()
};

/// The outputs of one run, committed all or nothing:
///   AtomicFileSet files;
///   write_a(files.add(path_a));   // each add() is an AtomicFile (checks, exclusive temporary)
///   write_b(files.add(path_b));
///   files.commit();
/// commit() checks every target again, keeps a hard link to each existing target, then renames
/// the temporaries into place; if any rename fails, the ones already renamed are undone (the
/// previous files restored, new ones removed) and OutputError names the path that failed.
class AtomicFileSet {
 public:
  AtomicFileSet() = default;
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;
  /// Adds an output; returns its temporary path (valid until commit or destruction).
  const std::string& add(const std::string& path);
  void commit();
  std::size_t size() const { return files_.size(); }

 private:
  std::vector<std::unique_ptr<AtomicFile>> files_;
};

/// Installs SIGINT, SIGTERM and SIGHUP handlers that remove every temporary file of a live
/// AtomicFile, then die of the signal as usual (exit status 128 + signal). So an interrupted
/// run leaves neither a partial output nor a stray temporary file. Executables call it once.
void remove_temporaries_on_signal();

/// The prefix of the temporary files an AtomicFile for `path` creates in process `pid`
/// (file name only, without the directory).
std::string temporary_prefix(const std::string& path, long pid);

/// Removes the temporary files an AtomicFile for `path` created in process `pid`
/// (temporary_prefix), e.g. after that process crashed. Returns how many were removed.
/// Never throws (an unreadable directory removes nothing).
int remove_temporaries_of(const std::string& path, long pid);

}  // namespace kdmesh
