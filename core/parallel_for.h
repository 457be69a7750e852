// kdmesh — fork-join on a few std::threads: run_workers (one job per worker) and parallel_for
// (an index range in one chunk per worker).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace kdmesh {

/// Calls job(w) for every w in [0, workers): job(0) on the calling thread and each other on a
/// thread started here. Where a thread cannot be started (std::system_error, e.g. under a
/// batch system's limit on processes and threads), that job and the later ones run on the
/// calling thread after job(0), so jobs must not wait for one another. Every thread started is
/// joined before the first exception thrown by a job (lowest w) is rethrown.
template <class Job>
void run_workers(unsigned workers, const Job& job) {
  workers = std::max(1u, workers);
  std::vector<std::exception_ptr> errors(workers);
  auto guarded = [&](unsigned w) {
    try {
      job(w);
    } catch (...) {
      errors[w] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);  // no reallocation (which could throw) once threads run
  unsigned started = 1;
  for (; started < workers; ++started) {
    try {
      threads.emplace_back(guarded, started);
    } catch (const std::system_error&) {
      break;  // no more threads: the rest run here
    }
  }
  guarded(0);
  for (unsigned w = started; w < workers; ++w) guarded(w);
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

/// Calls body(begin, end, worker) on disjoint chunks covering [0, n), one chunk per worker,
/// on up to `max_workers` threads (0 = hardware concurrency) through run_workers. Ranges
/// shorter than `grain` per worker run on the calling thread. The first exception thrown by a
/// worker is rethrown.
template <class Body>
void parallel_for(std::size_t n, Body&& body, std::size_t grain = 4096, unsigned max_workers = 0) {
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  unsigned workers = max_workers ? std::min(max_workers, hw) : hw;
  workers = unsigned(std::min<std::size_t>(workers, std::max<std::size_t>(1, n / std::max<std::size_t>(grain, 1))));
  if (workers <= 1) {
    if (n) body(std::size_t(0), n, 0u);
    return;
  }
  const std::size_t chunk = (n + workers - 1) / workers;
  run_workers(workers, [&](unsigned w) {
    const std::size_t b = std::min(n, w * chunk), e = std::min(n, b + chunk);
    if (b < e) body(b, e, w);
  });
}

}  // namespace kdmesh
