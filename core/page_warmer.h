// kdmesh — first touch of memory pages on a core that would otherwise wait.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace kdmesh {

/// Makes the pages of address ranges resident on a thread of its own, front to back, until
/// stop(): a later first write to them then costs no page fault. The contents never change
/// (Linux's MADV_POPULATE_WRITE), so other threads may read and write the ranges meanwhile, and
/// the ranges may be allocated memory past a vector's size, within its capacity. On this project's
/// VM a first touch costs 1.6-2.1 us per 4 KiB page; a worker that would otherwise idle pays it
/// instead. Where the system cannot populate pages (not Linux, or Linux before 5.14), or no
/// thread starts, it does nothing.
class PageWarmer {
 public:
  struct Range {
    const void* begin;
    const void* end;
  };
  explicit PageWarmer(std::vector<Range> ranges);
  ~PageWarmer() { stop(); }
  PageWarmer(const PageWarmer&) = delete;
  PageWarmer& operator=(const PageWarmer&) = delete;

  /// Stops after the chunk in progress (at most 256 KiB) and waits for the thread.
  void stop();
  /// Bytes made resident so far (whole pages; those already resident count too).
  std::size_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

 private:
  void run();

  std::vector<Range> ranges_;
  std::atomic<bool> stop_{false};
  std::atomic<std::size_t> bytes_{0};
  std::thread thread_;
};

}  // namespace kdmesh
