// kdmesh — PageWarmer: MADV_POPULATE_WRITE in chunks on a thread of its own.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/page_warmer.h"

#include <algorithm>
#include <cstdint>
#include <system_error>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace kdmesh {

namespace {
/// Bytes per madvise call: small enough that stop() waits little (about 0.1 ms here).
constexpr std::uintptr_t kChunk = std::uintptr_t(256) << 10;
}  // namespace

PageWarmer::PageWarmer(std::vector<Range> ranges) : ranges_(std::move(ranges)) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  try {
    thread_ = std::thread([this] { run(); });
  } catch (const std::system_error&) {
    // No thread: the pages are touched by whoever writes them first, as without a warmer.
  }
#endif
}

void PageWarmer::stop() {
  stop_.store(true, std::memory_order_relaxed);
  if (thread_.joinable()) thread_.join();
}

void PageWarmer::run() {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  const long size = sysconf(_SC_PAGESIZE);
  if (size <= 0) return;
  const std::uintptr_t page = std::uintptr_t(size);
  for (const Range& r : ranges_) {
    // Whole pages inside the range only: a page it shares with other data is touched anyway.
    std::uintptr_t a = (reinterpret_cast<std::uintptr_t>(r.begin) + page - 1) & ~(page - 1);
    const std::uintptr_t e = reinterpret_cast<std::uintptr_t>(r.end) & ~(page - 1);
    while (a < e) {
      if (stop_.load(std::memory_order_relaxed)) return;
      const std::uintptr_t len = std::min(kChunk, e - a);
      // Fails with EINVAL before Linux 5.14: then nothing more is tried.
      if (madvise(reinterpret_cast<void*>(a), len, MADV_POPULATE_WRITE) != 0) return;
      a += len;
      bytes_.fetch_add(len, std::memory_order_relaxed);
    }
  }
#endif
}

}  // namespace kdmesh
