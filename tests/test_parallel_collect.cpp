// parallel_collect (core/parallel_collect.h): the indices that pass, found by chunks on several
// threads, must be exactly those of one loop, in its order.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "core/parallel_collect.h"
#include "core/rng.h"

namespace kdmesh {
namespace {

TEST(ParallelCollect, GivesOneLoopsIndicesInOrderOnAnyThreads) {
  for (const std::size_t n : {std::size_t(0), std::size_t(10), std::size_t(1000), std::size_t(300001)}) {
    Rng rng(n + 1);
    std::vector<std::uint8_t> pass(n);
    for (auto& p : pass) p = rng.below(3) == 0;
    std::vector<std::uint32_t> expected;
    for (std::size_t i = 0; i < n; ++i)
      if (pass[i]) expected.push_back(std::uint32_t(i));
    for (const unsigned workers : {1u, 2u, 3u, 0u}) {
      std::atomic<std::size_t> calls{0};
      std::vector<std::uint8_t> seen(n, 0);
      const std::vector<std::uint32_t> got = parallel_collect(n, [&](std::size_t i) {
        ++calls;
        seen[i] = 1;  // take(i) may write index i's data
        return pass[i] != 0;
      }, 1000, workers);
      EXPECT_EQ(got, expected) << n << " items, " << workers << " workers";
      EXPECT_EQ(calls.load(), n);
      EXPECT_EQ(std::vector<std::uint8_t>(n, 1), seen);
    }
  }
}

}  // namespace
}  // namespace kdmesh
