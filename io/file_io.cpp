// kdmesh — raw file input and output and token quoting for the io/ readers and writers.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory_amount.h"

namespace kdmesh {

namespace {

/// Closes a file descriptor on scope exit.
struct FdGuard {
  int fd;
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

namespace {

const char* file_kind(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

}  // namespace

std::string read_whole_file(const std::string& path, std::uint64_t max_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer must not block (it is refused below).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  FdGuard guard{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw InputError(path, 0, std::string("cannot stat: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    throw InputError(path, 0, std::string("cannot read: it is ") + file_kind(st.st_mode) +
                                  ", not a regular file (inputs must be regular files)");
  if (max_bytes == 0) max_bytes = default_read_limit();
  if (std::uint64_t(st.st_size) > max_bytes)
    throw InputError(path, 0, "file too large: " + std::to_string(st.st_size) + " bytes, more than the " +
                                  std::to_string(max_bytes) + " bytes allowed (the memory limit)");
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);

  // One buffer of the right size (+1 so the final read sees EOF without growing). Files whose
  // size the kernel does not report (/proc) grow geometrically, up to max_bytes.
  std::string data(std::size_t(st.st_size) + 1, '\0');
  std::size_t used = 0;
  for (;;) {
    if (used == data.size()) {
      if (used > max_bytes)
        throw InputError(path, 0, "file too large: more than the " + std::to_string(max_bytes) +
                                      " bytes allowed (the memory limit)");
      data.resize(std::max<std::size_t>(2 * data.size(), std::size_t(1) << 16));
    }
    const ssize_t n = ::read(fd, data.data() + used, data.size() - used);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, 0, std::string("cannot read: ") + std::strerror(errno));
    }
    if (n == 0) break;
    used += std::size_t(n);
  }
  data.resize(used);
  return data;
}

std::uint64_t default_read_limit() {
  const double m = physical_memory_bytes();
  return m > 0 ? std::uint64_t(m / 2) : std::uint64_t(1) << 34;
}

FileWriter::FileWriter(const std::string& file, std::string report_as)
    : fd_(::open(file.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC)),
      report_as_(std::move(report_as)) {
  if (fd_ < 0) throw OutputError(report_as_, std::string("cannot open for writing: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    throw OutputError(report_as_, "cannot write: not a regular file");
  }
}

FileWriter::~FileWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void FileWriter::write(const char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd_, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw OutputError(report_as_, std::string("write failed: ") + std::strerror(errno));
    }
    p += w;
    n -= std::size_t(w);
  }
}

void FileWriter::close() {
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0)
    throw OutputError(report_as_, std::string("close failed: ") + std::strerror(errno));
}

void write_file_atomically(const std::string& path, std::string_view bytes) {
  AtomicFile file(path);
  FileWriter out(file.temp_path(), path);
  out.write(bytes.data(), bytes.size());
  out.close();
  file.commit();
}

std::string quote_token_printable(std::string_view tok) {
  constexpr std::size_t kMax = 40;
  std::string s(tok.substr(0, kMax));
  for (char& c : s)
    if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
  return "'" + s + (tok.size() > kMax ? "...'" : "'");
}

}  // namespace kdmesh
