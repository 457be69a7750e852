// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace kdmesh {

namespace {
std::atomic<unsigned> g_counter{0};

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
}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw OutputError("<empty>", "output path is empty");
  temp_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter++);
  slot_ = claim_slot(temp_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_.c_str());
  release_slot(slot_);
}

void AtomicFile::commit() {
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    int e = errno;
    std::remove(temp_.c_str());
    throw OutputError(path_, std::string("cannot rename temporary file into place: ") + std::strerror(e));
  }
  committed_ = true;
  release_slot(slot_);
  slot_ = -1;
}

void remove_temporaries_on_signal() {
  std::signal(SIGINT, remove_temporaries_and_die);
  std::signal(SIGTERM, remove_temporaries_and_die);
}

int remove_temporaries_of(const std::string& path, long pid) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const std::string prefix = target.filename().string() + ".tmp-" + std::to_string(pid) + "-";
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
