// kdmesh — raw file input and output and token quoting for the io/ readers and writers
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <charconv>
#include <string>
#include <string_view>
#include <cstddef>
#include <system_error>

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
