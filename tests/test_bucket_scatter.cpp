// bucket_scatter (mesher/bucket_scatter.h): a stable counting sort counted and scattered by
// parts on several threads must give exactly std::stable_sort's order by bucket.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "mesher/bucket_scatter.h"

namespace kdmesh {
namespace {

TEST(BucketScatter, GivesTheStableSortByBucketAndTheBucketStarts) {
  // 0 items, fewer than one part (64k), several parts; buckets few, many, some empty.
  for (const auto& [n, buckets] : std::vector<std::pair<std::size_t, std::size_t>>{
           {0, 5}, {1000, 7}, {300000, 3}, {300000, 100000}, {200001, 1}}) {
    Rng rng(n + buckets);
    std::vector<std::uint32_t> bucket(n);
    for (auto& b : bucket) b = std::uint32_t(rng.below(buckets));
    std::vector<std::uint32_t> out(n, 0xffffffffu);
    const std::vector<std::size_t> start = bucket_scatter(
        n, buckets, [&](std::size_t i) { return bucket[i]; },
        [&](std::size_t i, std::size_t at) { out[at] = std::uint32_t(i); });
    std::vector<std::uint32_t> expected(n);
    std::iota(expected.begin(), expected.end(), 0u);
    std::stable_sort(expected.begin(), expected.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return bucket[a] < bucket[b]; });
    EXPECT_EQ(out, expected) << n << " items, " << buckets << " buckets";
    ASSERT_EQ(start.size(), buckets + 1);
    EXPECT_EQ(start.front(), 0u);
    EXPECT_EQ(start.back(), n);
    std::vector<std::size_t> count(buckets, 0);
    for (const std::uint32_t b : bucket) ++count[b];
    for (std::size_t b = 0; b < buckets; ++b) ASSERT_EQ(start[b + 1] - start[b], count[b]) << "bucket " << b;
  }
}

}  // namespace
}  // namespace kdmesh
