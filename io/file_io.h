// kdmesh — raw file input and output and token quoting for the io/ readers and writers
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>
#include <string_view>
#include <cstddef>

namespace kdmesh {

/// The complete contents of `path` (regular files in one read of the right size, pipes and
/// special files grown geometrically). Throws InputError naming the file and strerror if it
/// cannot be opened, stat'ed or read, or is a directory. An empty file gives "".
std::string read_whole_file(const std::string& path);

/// Writes raw bytes to a new file at `file` (usually an AtomicFile's temporary path); errors
/// are OutputErrors naming `report_as` (the path the user asked for): "cannot create",
/// "write failed", "close failed". The destructor closes the file if close() was not reached.
class FileWriter {
 public:
  FileWriter(const std::string& file, std::string report_as);
  ~FileWriter();
  FileWriter(const FileWriter&) = delete;
  FileWriter& operator=(const FileWriter&) = delete;
  void write(const char* p, std::size_t n);
  void close();

 private:
  int fd_;
  std::string report_as_;
};

/// Writes `bytes` as the whole file `path`, atomically (core/atomic_file.h: a temporary file
/// beside it, renamed into place). OutputErrors as FileWriter's.
void write_file_atomically(const std::string& path, std::string_view bytes);

/// A token quoted for an error message: 'tok', cut to 40 characters ('...' after the cut),
/// unprintable bytes shown as '?'.
std::string quote_token_printable(std::string_view tok);

}  // namespace kdmesh
