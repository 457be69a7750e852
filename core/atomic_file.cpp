// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/atomic_file.h"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "core/error.h"

namespace kdmesh {

namespace {

namespace fs = std::filesystem;

// Live temporary files, for the signal handler: fixed slots (no allocation, no locks in the
// handler; unlink() is async-signal-safe). A slot is claimed with a compare-exchange and its
// path written before it is published as `ready`.
constexpr int kSlots = 64;
constexpr std::size_t kPathMax = 4096;
struct Slot {
  std::atomic<int> state{0};  // 0 free, 1 being written, 2 ready
  char path[kPathMax];
};
Slot g_slots[kSlots];

int claim_slot(const std::string& path) {
  if (path.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(2);
      return i;
    }
  }
  return -1;  // more than kSlots concurrent outputs: still atomic, just not signal-cleaned
}

void release_slot(int i) {
  if (i >= 0) g_slots[i].state.store(0);
}

extern "C" void remove_temporaries_and_die(int sig) {
  for (Slot& s : g_slots)
    if (s.state.load() == 2) ::unlink(s.path);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

/// The longest file name (bytes) of a temporary's suffix ".tmp-<pid>-<16 hex>", pid < 2^32.
constexpr std::size_t kSuffixMax = 5 + 10 + 1 + 16;
constexpr std::size_t kNameMax = 255;

/// `name` cut so that the temporary's suffix fits in a file name (not inside a UTF-8 sequence).
std::string cut_name(std::string name) {
  if (name.size() + kSuffixMax <= kNameMax) return name;
  std::size_t n = kNameMax - kSuffixMax;
  while (n > 0 && (static_cast<unsigned char>(name[n]) & 0xC0) == 0x80) --n;
  name.resize(n);
  return name;
}

std::uint64_t random64() {
  std::uint64_t x = 0;
  if (::getrandom(&x, sizeof x, 0) == ssize_t(sizeof x)) return x;
  std::random_device rd;
  return (std::uint64_t(rd()) << 32) ^ rd();
}

const char* kind_of(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISFIFO(m)) return "a FIFO";
  if (S_ISSOCK(m)) return "a socket";
  if (S_ISLNK(m)) return "a symbolic link";
  return "not a regular file";
}

/// The path beside `target` for a temporary file or backup of this process.
std::string sibling_temp(const std::string& target) {
  const fs::path p(target);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(random64()));
  const std::string name = temporary_prefix(target, long(::getpid())) + hex;
  return (p.has_parent_path() ? (p.parent_path() / name) : fs::path(name)).string();
}

/// Creates a new file exclusively at an unpredictable path beside `target`; returns the path.
std::string create_temp_beside(const std::string& target) {
  for (int attempt = 0;; ++attempt) {
    std::string temp = sibling_temp(target);
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return temp;
    }
    const int e = errno;
    if (e == EEXIST && attempt < 16) continue;
    throw OutputError(target, std::string("cannot create a temporary file beside it: ") + std::strerror(e));
  }
}

}  // namespace

void check_output_target(const std::string& path) {
  if (path.empty()) throw OutputError("''", "the output path is empty");
  const fs::path p(path);
  const std::string name = p.filename().string();
  if (name.empty() || name == "." || name == "..")
    throw OutputError(path, "names a directory, not a file");
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    const int e = errno;
    if (e == ENOENT) return;  // created; a missing directory is created or reported later
    throw OutputError(path, std::string("cannot check the output: ") + std::strerror(e));
  }
  if (!S_ISREG(st.st_mode))
    throw OutputError(path, std::string("exists and is ") + kind_of(st.st_mode) +
                                "; an output may only create or replace a regular file");
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  check_output_target(path_);
  temp_ = create_temp_beside(path_);
  slot_ = claim_slot(temp_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_.c_str());
  release_slot(slot_);
}

void AtomicFile::commit() {
  check_output_target(path_);  // again: it may have changed while the output was written
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    int e = errno;
    throw OutputError(path_, std::string("cannot rename the temporary file into place: ") + std::strerror(e));
  }
  committed_ = true;
  release_slot(slot_);
  slot_ = -1;
}

const std::string& AtomicFileSet::add(const std::string& path) {
  files_.push_back(std::make_unique<AtomicFile>(path));
  return files_.back()->temp_path();
}

void AtomicFileSet::commit() {
  // Nothing is renamed unless every target is still a place an output may go.
  for (const auto& f : files_) check_output_target(f->path_);
  // A hard link to each existing target, so that a failed rename can restore it.
  struct Backup {
    std::string path;  // empty: the target did not exist (or could not be linked)
    bool existed = false;
    int slot = -1;
  };
  std::vector<Backup> backups(files_.size());
  auto drop_backups = [&] {
    for (Backup& b : backups) {
      if (!b.path.empty()) ::unlink(b.path.c_str());
      release_slot(b.slot);
      b = {};
    }
  };
  for (std::size_t i = 0; i < files_.size() && files_.size() > 1; ++i) {
    struct stat st {};
    backups[i].existed = ::lstat(files_[i]->path_.c_str(), &st) == 0;
    if (!backups[i].existed) continue;
    const std::string b = sibling_temp(files_[i]->path_);
    if (::link(files_[i]->path_.c_str(), b.c_str()) == 0) {
      backups[i].path = b;
      backups[i].slot = claim_slot(b);
    } else {
      const int e = errno;
      drop_backups();
      throw OutputError(files_[i]->path_,
                        std::string("cannot keep the previous file while replacing it: ") + std::strerror(e) +
                            "; no output was replaced");
    }
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    AtomicFile& f = *files_[i];
    if (std::rename(f.temp_.c_str(), f.path_.c_str()) == 0) {
      f.committed_ = true;
      continue;
    }
    const int e = errno;
    for (std::size_t k = i; k-- > 0;) {  // undo: restore the previous files, remove new ones
      AtomicFile& done = *files_[k];
      if (backups[k].existed && !backups[k].path.empty()) {
        if (::rename(backups[k].path.c_str(), done.path_.c_str()) == 0) backups[k].path.clear();
      } else if (!backups[k].existed) {
        ::unlink(done.path_.c_str());
      }
    }
    drop_backups();
    throw OutputError(f.path_, std::string("cannot rename the temporary file into place: ") + std::strerror(e) +
                                   "; none of the run's outputs was replaced");
  }
  drop_backups();
  for (auto& f : files_) {
    release_slot(f->slot_);
    f->slot_ = -1;
  }
}

void remove_temporaries_on_signal() {
  std::signal(SIGINT, remove_temporaries_and_die);
  std::signal(SIGTERM, remove_temporaries_and_die);
  std::signal(SIGHUP, remove_temporaries_and_die);
}

std::string temporary_prefix(const std::string& path, long pid) {
  return cut_name(fs::path(path).filename().string()) + ".tmp-" + std::to_string(pid) + "-";
}

int remove_temporaries_of(const std::string& path, long pid) {
  const fs::path target(path);
  const std::string prefix = temporary_prefix(path, pid);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) == 0 && fs::remove(it->path(), ec)) ++removed;
  }
  return removed;
}

}  // namespace kdmesh
