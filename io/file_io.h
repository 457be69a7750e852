// kdmesh — raw file input and output and token quoting for the io/ readers and writers
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <charconv>
#include <string>
#include <string_view>
#include <cstddef>
#include <cstdint>
#include <system_error>

namespace kdmesh {

/// The complete contents of the regular file `path`, in one read of the right size. Throws
/// InputError naming the file: with strerror if it cannot be opened, stat'ed or read; if it is
/// not a regular file (a directory, device such as /dev/zero, FIFO or socket, also through a
/// symbolic link: refused at once, never read, never waited on); or if it holds more than
/// `max_bytes` (0: default_read_limit()). An empty file gives "".
std::string read_whole_file(const std::string& path, std::uint64_t max_bytes = 0);

/// The default bound of read_whole_file: half the machine's physical memory (16 GiB if unknown).
std::uint64_t default_read_limit();

/// Writes raw bytes to the existing regular file `file` (an AtomicFile's temporary path, which
/// AtomicFile created exclusively), truncating it; symbolic links are not followed. Errors are
/// OutputErrors naming `report_as` (the path the user asked for) with the errno text:
/// "cannot open for writing", "write failed", "close failed". The destructor closes the file if close() was not reached.
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

/// Parses the whole of `tok` as a number of type T with std::from_chars (locale independent),
/// also accepting a leading '+', which from_chars alone rejects. False if `tok` is not such a
/// number or does not fit in T.
template <class T>
bool parse_whole_token(std::string_view tok, T& value) {
  if (tok.size() > 1 && tok[0] == '+' && tok[1] != '-' && tok[1] != '+') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
  return ec == std::errc() && ptr == tok.data() + tok.size();
}

/// A token quoted for an error message: 'tok', cut to 40 characters ('...' after the cut),
/// unprintable bytes shown as '?'.
std::string quote_token_printable(std::string_view tok);

}  // namespace kdmesh
