// DistinctSorter: the same as std::sort + std::unique on every group, with one object reused.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "mesher/distinct_sorter.h"

namespace kdmesh {
namespace {

std::vector<std::uint32_t> sort_unique(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// Groups of 0-300 values (the table takes up to 128, larger ones are sorted whole), drawn from
// ranges of 1 to 2^32 values (from all repeats to none), some with the table's empty marker
// 0xFFFFFFFF and values that collide in the table, all through one sorter: its table must be
// empty again after every group.
TEST(DistinctSorter, EqualsSortThenUniqueOnManyGroups) {
  Rng rng(7);
  DistinctSorter distinct;
  const std::uint64_t ranges[] = {1, 2, 7, 40, 1000, 1u << 20, std::uint64_t(1) << 32};
  std::size_t hashed = 0, whole = 0, marked = 0;
  for (int g = 0; g < 20000; ++g) {
    const std::size_t m = std::size_t(rng.uniform(0, 301));
    const std::uint64_t range = ranges[g % 7];
    const std::uint32_t base = g % 3 == 0 ? 0xFFFFFFFFu - std::uint32_t(range - 1) : 0;
    std::vector<std::uint32_t> group(m);
    for (auto& x : group) {
      x = base + std::uint32_t(std::uint64_t(rng.uniform(0, double(range))) % range);
      if (g % 11 == 0) x <<= 24;  // the same low bits: many collide in the table
    }
    const std::vector<std::uint32_t> want = sort_unique(group);
    std::vector<std::uint32_t> got = group;
    const std::size_t k = distinct(got.data(), got.size());
    got.resize(k);
    ASSERT_EQ(got, want) << "group " << g << " of " << m;
    (m <= 128 ? hashed : whole) += 1;
    marked += std::count(group.begin(), group.end(), 0xFFFFFFFFu) > 0;
  }
  EXPECT_GT(hashed, 5000u);
  EXPECT_GT(whole, 5000u);
  EXPECT_GT(marked, 100u);
}

}  // namespace
}  // namespace kdmesh
