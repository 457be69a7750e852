// core/parallel_for.h: run_workers, parallel_for and parallel_blocks cover their index range
// exactly once on any worker count, and a body's exception reaches the caller. (Without threads to start: test_thread_limit.)
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "core/cpu_count.h"
#include "core/parallel_for.h"

namespace kdmesh {
namespace {

TEST(ParallelFor, RunWorkersCallsEveryJobOnce) {
  for (const unsigned workers : {0u, 1u, 2u, 5u}) {
    std::vector<std::atomic<int>> calls(std::max(1u, workers));
    run_workers(workers, [&](unsigned w) { ++calls[w]; });
    for (const auto& c : calls) EXPECT_EQ(c.load(), 1) << workers << " workers";
  }
}

TEST(ParallelFor, EachIndexOnceInOneChunkPerWorkerOrInFreeBlocks) {
  for (const std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(999), std::size_t(100003)}) {
    for (const unsigned workers : {0u, 1u, 2u, 3u}) {
      std::vector<std::atomic<int>> chunked(n), blocked(n);
      std::atomic<std::size_t> chunks{0};
      parallel_for(n, [&](std::size_t b, std::size_t e, unsigned) {
        ++chunks;
        for (std::size_t i = b; i < e; ++i) ++chunked[i];
      }, 100, workers);
      parallel_blocks(n, 7, [&](std::size_t b, std::size_t e, unsigned) {
        EXPECT_LE(e - b, 7u);
        for (std::size_t i = b; i < e; ++i) ++blocked[i];
      }, workers);
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(chunked[i].load(), 1) << "parallel_for, n " << n << ", index " << i;
        ASSERT_EQ(blocked[i].load(), 1) << "parallel_blocks, n " << n << ", index " << i;
      }
      EXPECT_LE(chunks.load(), std::max(1u, workers == 0 ? available_cpus() : workers));
    }
  }
}

TEST(ParallelFor, ExceptionReachesTheCaller) {
  for (const unsigned workers : {1u, 2u, 3u}) {
    std::vector<std::atomic<int>> seen(1000);
    EXPECT_THROW(parallel_blocks(seen.size(), 10, [&](std::size_t b, std::size_t e, unsigned) {
                   for (std::size_t i = b; i < e; ++i) ++seen[i];
                   if (b == 500) throw std::runtime_error("block 50");
                 }, workers),
                 std::runtime_error);
    for (const auto& s : seen) EXPECT_LE(s.load(), 1);  // no block twice
    EXPECT_EQ(seen[500].load(), 1);
    EXPECT_THROW(run_workers(workers, [&](unsigned w) {
                   if (w + 1 == workers) throw std::runtime_error("the last job");
                 }),
                 std::runtime_error);
  }
}

}  // namespace
}  // namespace kdmesh
