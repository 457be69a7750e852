// kdmesh — raw file input and output and token quoting for the io/ readers and writers.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"

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

std::string read_whole_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  FdGuard guard{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw InputError(path, 0, std::string("cannot stat: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw InputError(path, 0, "cannot read: is a directory");

  // Regular files: one buffer of the right size (+1 so the final read sees EOF without growing).
  // Pipes and other special files report no size: grow geometrically.
  std::string data(S_ISREG(st.st_mode) ? std::size_t(st.st_size) + 1 : std::size_t(1) << 16, '\0');
  std::size_t used = 0;
  for (;;) {
    if (used == data.size()) data.resize(2 * data.size());
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

FileWriter::FileWriter(const std::string& file, std::string report_as)
    : fd_(::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666)),
      report_as_(std::move(report_as)) {
  if (fd_ < 0) throw OutputError(report_as_, std::string("cannot create: ") + std::strerror(errno));
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
