// kdmesh — PointValues (mesher/point_values.h): f at points, each computed once per distinct
// point until clear().
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "core/rng.h"
#include "mesher/point_values.h"

namespace kdmesh {
namespace {

double f(const double* p) { return std::sin(p[0]) + 3 * p[1] * p[1] - std::cos(7 * p[2]); }

TEST(PointValues, EachDistinctPointIsComputedOnceAndGivesItsOwnValue) {
  Rng rng(9);
  // A pool of points, some differing from others in one coordinate by one ulp.
  std::vector<std::array<double, 3>> pool;
  for (int i = 0; i < 10000; ++i) {
    std::array<double, 3> p{rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5)};
    pool.push_back(p);
    if (i % 10 == 0) {
      p[i % 3] = std::nextafter(p[i % 3], 10.0);
      pool.push_back(p);
    }
  }
  PointValues values;
  for (int round = 0; round < 2; ++round) {  // the second after clear(): all computed again
    std::uint64_t computed = 0, calls = 0;
    std::set<std::array<double, 3>> asked;
    for (int k = 0; k < 60000; ++k) {
      const std::array<double, 3>& p = pool[rng.below(pool.size())];
      const double v = values.at(p.data(), [&](const double* x) { ++calls; return f(x); }, computed);
      ASSERT_EQ(v, f(p.data()));
      asked.insert(p);
    }
    EXPECT_EQ(computed, asked.size());
    EXPECT_EQ(calls, asked.size());
    EXPECT_EQ(values.size(), asked.size());
    EXPECT_LT(asked.size(), 60000u);  // points were asked again
    values.clear();
    EXPECT_EQ(values.size(), 0u);
  }
  // -0.0 and 0.0 are one point.
  std::uint64_t computed = 0;
  const double a[3] = {0.0, 1.0, -0.0}, b[3] = {-0.0, 1.0, 0.0};
  values.at(a, f, computed);
  values.at(b, f, computed);
  EXPECT_EQ(computed, 1u);
}

}  // namespace
}  // namespace kdmesh
