// kdmesh — tests of the recovery's point grid (mesher/volume/point_grid.h): every answer equals a
// brute-force scan of the same points.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "core/point_set.h"
#include "core/rng.h"
#include "mesher/volume/point_grid.h"

namespace kdmesh {
namespace {

bool brute_within(const std::vector<const double*>& pts, const double* p, double r) {
  for (const double* q : pts)
    if ((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]) < r * r)
      return true;
  return false;
}

struct Case {
  PointSet points;
  std::vector<std::uint8_t> skip;
  std::vector<double> added;  // 3 per point
};

/// n points: half uniform in [0, 10]^3, half in tight clusters (many per cell), every third
/// one skipped; 200 points to add.
Case make_case(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  Case c;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 2 == 0) {
      c.points.push_back(rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(0, 10));
    } else {
      const double cx = double(rng.below(5)) * 2, cy = double(rng.below(5)) * 2, cz = 3;
      c.points.push_back(cx + rng.uniform(0, 0.01), cy + rng.uniform(0, 0.01), cz + rng.uniform(0, 0.01));
    }
    c.skip.push_back(i % 3 == 0 ? 1 : 0);
  }
  for (int i = 0; i < 3 * 200; ++i) c.added.push_back(rng.uniform(-1, 11));
  return c;
}

void expect_same_as_brute_force(const Case& c, double cell, std::uint64_t seed) {
  const double origin[3] = {-0.5, -0.5, -0.5};
  PointGrid grid(cell, origin, c.points, c.skip);
  std::vector<const double*> kept;
  for (std::size_t i = 0; i < c.points.size(); ++i)
    if (!c.skip[i]) kept.push_back(c.points.p(std::uint32_t(i)));
  Rng rng(seed);
  int hits = 0, misses = 0;
  auto check = [&](std::size_t added) {
    for (int q = 0; q < 300; ++q) {
      const double p[3] = {rng.uniform(-2, 12), rng.uniform(-2, 12), rng.uniform(-2, 12)};
      // Radii from a hundredth of a cell to 20 cells (the last ones test every point).
      const double r = cell * std::pow(10.0, rng.uniform(-2, std::log10(20.0)));
      const bool want = brute_within(kept, p, r);
      ASSERT_EQ(grid.any_within(p, r), want) << "cell " << cell << " r " << r << " after " << added << " added";
      (want ? hits : misses) += 1;
    }
  };
  check(0);
  for (std::size_t a = 0; a < c.added.size(); a += 3) {
    grid.add(&c.added[a]);
    kept.push_back(&c.added[a]);
    if (a % 60 == 0) check(a / 3 + 1);
  }
  // Both answers occur (a grid that always says yes or no fails here).
  EXPECT_GT(hits, 100);
  EXPECT_GT(misses, 100);
}

TEST(PointGrid, AnswersEqualABruteForceScan) {
  const Case c = make_case(3000, 1);
  for (double cell : {0.05, 0.3, 2.0}) expect_same_as_brute_force(c, cell, 7);
}

// More than 64k points: the buckets are counted and filled on several threads.
TEST(PointGrid, AnswersEqualABruteForceScanWhenBuiltOnSeveralThreads) {
  const Case c = make_case(150000, 2);
  expect_same_as_brute_force(c, 0.1, 9);
}

TEST(PointGrid, SkippedPointsAndPointsAtDistanceRDoNotCount) {
  PointSet points;
  points.push_back(0, 0, 0);
  points.push_back(1, 0, 0);
  const double origin[3] = {0, 0, 0};
  PointGrid grid(0.25, origin, points, {1, 0});
  const double at_origin[3] = {0, 0, 0};
  EXPECT_FALSE(grid.any_within(at_origin, 0.5));  // (0,0,0) is skipped
  EXPECT_FALSE(grid.any_within(at_origin, 1.0));  // (1,0,0) is at distance exactly 1
  EXPECT_TRUE(grid.any_within(at_origin, std::nextafter(1.0, 2.0)));
  grid.add(at_origin);
  EXPECT_TRUE(grid.any_within(at_origin, 1e-9));
}

TEST(PointGrid, SkipFlagsOfAnotherLengthAreRefused) {
  PointSet points;
  points.push_back(0, 0, 0);
  points.push_back(1, 0, 0);
  const double origin[3] = {0, 0, 0};
  EXPECT_THROW(PointGrid(0.25, origin, points, {1}), UsageError);
}

TEST(PointGrid, EmptyGrid) {
  const PointSet none;
  const double origin[3] = {0, 0, 0};
  PointGrid grid(1.0, origin, none, {});
  const double p[3] = {0.5, 0.5, 0.5};
  EXPECT_FALSE(grid.any_within(p, 100));
  grid.add(p);
  EXPECT_TRUE(grid.any_within(p, 0.1));
}

}  // namespace
}  // namespace kdmesh
