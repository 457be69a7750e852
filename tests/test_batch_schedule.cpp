// kdmesh — how a batch's jobs are spread (tools/app/batch_schedule.h; issue 22): costs from
// the inputs and sizes, largest first, and shards that together hold each job once.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "tools/app/batch_schedule.h"

namespace kdmesh {
namespace {

TEST(BatchSchedule, LargestFirstKeepsJobOrderOnTies) {
  EXPECT_EQ(largest_first({1, 5, 3, 5, 0}), (std::vector<std::size_t>{1, 3, 2, 0, 4}));
  EXPECT_TRUE(largest_first({}).empty());
}

TEST(BatchSchedule, ParseShard) {
  const Shard s = parse_shard("2/5", "--shard");
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 5u);
  for (const char* bad : {"", "1", "5/5", "1/0", "-1/4", "a/4", "1/4x", "1//4", "/4"}) {
    try {
      parse_shard(bad, "--shard");
      ADD_FAILURE() << bad;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("--shard '" + std::string(bad) + "'"), std::string::npos) << e.what();
    }
  }
}

// Every job lands in exactly one shard, each shard's list is in job order, and the loads are
// balanced to within the largest job (greedy largest-first); the same costs give the same split.
TEST(BatchSchedule, ShardsHoldEachJobOnceAndBalance) {
  const std::vector<double> costs = {50, 1, 7, 7, 30, 0, 12, 3, 3, 90, 0, 5};
  for (std::size_t n : {1u, 2u, 3u, 5u, 12u, 20u}) {
    std::vector<int> seen(costs.size(), 0);
    double lo = 1e300, hi = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::vector<std::size_t> mine = shard_jobs(costs, {i, n});
      EXPECT_TRUE(std::is_sorted(mine.begin(), mine.end()));
      EXPECT_EQ(mine, shard_jobs(costs, {i, n}));
      double load = 0;
      for (std::size_t j : mine) ++seen[j], load += std::max(costs[j], 1.0);
      lo = std::min(lo, load), hi = std::max(hi, load);
    }
    for (int s : seen) EXPECT_EQ(s, 1) << n << " shards";
    if (n <= costs.size()) {
      EXPECT_LE(hi - lo, 90.0) << n << " shards";
    }
  }
}

// The cost grows as the size shrinks (cubically), and an unreadable input costs nothing.
TEST(BatchSchedule, CostsFollowSizeAndSkipUnreadableInputs) {
  MeshJob coarse, fine, missing;
  coarse.input = fine.input = std::string(KDMESH_SOURCE_DIR) + "/models/block/block.stl";
  coarse.sizing.max_size = 10;
  fine.sizing.max_size = 5;
  missing.input = std::string(KDMESH_SOURCE_DIR) + "/models/block/no-such-file.stl";
  missing.sizing.max_size = 1;
  const std::vector<double> c = estimate_job_costs({coarse, fine, missing});
  ASSERT_EQ(c.size(), 3u);
  EXPECT_GT(c[0], 0.0);
  EXPECT_GT(c[1], 4 * c[0]);  // (extent/h)^3 dominates: 8x, less the facets' share
  EXPECT_EQ(c[2], 0.0);
  MeshJob both = coarse;  // named bodies: the sum over their files
  both.bodies = {{"a", coarse.input}, {"b", coarse.input}};
  EXPECT_DOUBLE_EQ(estimate_job_costs({both})[0], 2 * c[0]);
}

}  // namespace
}  // namespace kdmesh
