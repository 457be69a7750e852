// kdmesh — fork-join on a few std::threads: run_workers (one job per worker), parallel_for
// (an index range in one chunk per worker) and parallel_blocks (in blocks taken by free
// workers).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

#include "core/cpu_count.h"

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
/// on up to `max_workers` threads (0 = available_cpus()) through run_workers. Ranges
/// shorter than `grain` per worker run on the calling thread. The first exception thrown by a
/// worker is rethrown.
template <class Body>
void parallel_for(std::size_t n, Body&& body, std::size_t grain = 4096, unsigned max_workers = 0) {
  const unsigned hw = available_cpus();
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

/// Calls body(begin, end, worker) on blocks of `block` indices covering [0, n), each block
/// taken by whichever of up to `max_workers` threads (0 = available_cpus()) is free, for
/// loops whose items differ in cost (one chunk per worker, as parallel_for gives, leaves a core
/// idle while the other finishes the costly part). Which worker runs a block depends on the
/// timing, so bodies must give per-index results. The first exception thrown (lowest worker)
/// is rethrown once every worker has stopped; blocks after it may not have run.
template <class Body>
void parallel_blocks(std::size_t n, std::size_t block, Body&& body, unsigned max_workers = 0) {
  block = std::max<std::size_t>(1, block);
  const std::size_t blocks = (n + block - 1) / block;
  const unsigned hw = available_cpus();
  const unsigned workers = unsigned(std::min<std::size_t>(max_workers ? std::min(max_workers, hw) : hw, blocks));
  if (workers <= 1) {
    for (std::size_t k = 0; k < blocks; ++k) body(k * block, std::min(n, (k + 1) * block), 0u);
    return;
  }
  std::atomic<std::size_t> next{0};
  run_workers(workers, [&](unsigned w) {
    for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < blocks;)
      body(k * block, std::min(n, (k + 1) * block), w);
  });
}

}  // namespace kdmesh
