// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/error.h"

namespace kdmesh {

namespace {
std::atomic<unsigned> g_counter{0};
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw OutputError("<empty>", "output path is empty");
  temp_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter++);
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_.c_str());
}

void AtomicFile::commit() {
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    int e = errno;
    std::remove(temp_.c_str());
    throw OutputError(path_, std::string("cannot rename temporary file into place: ") + std::strerror(e));
  }
  committed_ = true;
}

}  // namespace kdmesh
