// kdmesh — a minimal fork-join loop over an index range on a few std::threads.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace kdmesh {

/// Calls body(begin, end, worker) on disjoint chunks covering [0, n), one chunk per worker,
/// on up to `max_workers` threads (0 = hardware concurrency). Ranges shorter than `grain`
/// per worker run on the calling thread. The first exception thrown by a worker is rethrown.
template <class Body>
void parallel_for(std::size_t n, Body&& body, std::size_t grain = 4096, unsigned max_workers = 0) {
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  unsigned workers = max_workers ? std::min(max_workers, hw) : hw;
  workers = unsigned(std::min<std::size_t>(workers, std::max<std::size_t>(1, n / std::max<std::size_t>(grain, 1))));
  if (workers <= 1) {
    if (n) body(std::size_t(0), n, 0u);
    return;
  }
  std::vector<std::thread> threads;
  std::vector<std::exception_ptr> errors(workers);
  const std::size_t chunk = (n + workers - 1) / workers;
  for (unsigned w = 1; w < workers; ++w) {
    threads.emplace_back([&, w] {
      try {
        const std::size_t b = std::min(n, w * chunk), e = std::min(n, b + chunk);
        if (b < e) body(b, e, w);
      } catch (...) {
        errors[w] = std::current_exception();
      }
    });
  }
  try {
    body(std::size_t(0), std::min(n, chunk), 0u);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (auto& t : threads) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace kdmesh
