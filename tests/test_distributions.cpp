// The seven point distributions: names, determinism, counts, distance to their models,
// seeds, and (roughly) the sampling densities.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "tools/lib/distributions.h"

namespace kdmesh {
namespace {

constexpr double kDelta = 1e-4;  // disturbance amplitude documented in distributions.cpp
constexpr double kEps = 1e-12;   // rounding slack
constexpr double kPi = 3.141592653589793;

TEST(Distributions, Names) {
  const std::vector<std::string> names = {"cube", "planes",   "paraboloid", "spiral",
                                          "disk", "cylinder", "axes"};
  const std::vector<Distribution> all = all_distributions();
  ASSERT_EQ(all.size(), names.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(distribution_name(all[i]), names[i]);
    EXPECT_EQ(parse_distribution(names[i]), all[i]);
  }
  EXPECT_THROW(parse_distribution("sphere"), UsageError);
  EXPECT_THROW(parse_distribution("Cube"), UsageError);
}

TEST(Distributions, CountsDeterminismAndSeeds) {
  for (const Distribution d : all_distributions()) {
    SCOPED_TRACE(std::string(distribution_name(d)));
    EXPECT_TRUE(generate_points(d, 0, 1).empty());
    const PointSet a = generate_points(d, 5000, 17);
    const PointSet b = generate_points(d, 5000, 17);
    const PointSet c = generate_points(d, 5000, 18);
    ASSERT_EQ(a.size(), 5000u);
    ASSERT_EQ(a.xyz.size(), 15000u);
    EXPECT_EQ(a.xyz, b.xyz);  // bit-identical (== on doubles; no NaN)
    EXPECT_NE(a.xyz, c.xyz);
    for (const double v : a.xyz) ASSERT_TRUE(std::isfinite(v));
    // A shorter run is a prefix of a longer one (points are drawn one after another).
    const PointSet p = generate_points(d, 100, 17);
    EXPECT_TRUE(std::equal(p.xyz.begin(), p.xyz.end(), a.xyz.begin()));
  }
}

double radius_xy(const double* p) { return std::hypot(p[0] - 0.5, p[1] - 0.5); }

/// Largest deviation from the model over the points, and checks on each point.
template <class Deviation>
double max_deviation(const PointSet& ps, Deviation dev) {
  double worst = 0;
  for (std::uint32_t i = 0; i < ps.size(); ++i) worst = std::max(worst, dev(ps.p(i)));
  return worst;
}

TEST(Distributions, PointsLieNearTheirModels) {
  const std::size_t n = 20000;
  const std::uint64_t seed = 3;
  {
    SCOPED_TRACE("cube");
    const PointSet ps = generate_points(Distribution::cube, n, seed);
    for (const double v : ps.xyz) ASSERT_TRUE(v >= 0.0 && v < 1.0);
  }
  {
    SCOPED_TRACE("planes");
    const PointSet ps = generate_points(Distribution::planes, n, seed);
    int on_plane[3] = {0, 0, 0};
    for (std::uint32_t i = 0; i < ps.size(); ++i) {
      const double* p = ps.p(i);
      int near = -1;
      for (int j = 0; j < 3; ++j) {
        ASSERT_TRUE(p[j] > -kEps && p[j] < 1.0);
        if (std::abs(p[j] - 0.5) <= kDelta + kEps) near = j;
      }
      ASSERT_GE(near, 0) << "point " << i << " is on no plane";
      ++on_plane[near];
    }
    for (const int c : on_plane) EXPECT_NEAR(double(c) / n, 1.0 / 3, 0.02);
  }
  {
    SCOPED_TRACE("paraboloid");
    const PointSet ps = generate_points(Distribution::paraboloid, n, seed);
    // Moving (q, f(q)) by t along the unit normal changes z - f(x, y) by
    // t sqrt(1 + 64 r^2) - 4 t^2 |n_xy|^2, so |z - f| <= sqrt(17) delta + 4 delta^2.
    const double dev = max_deviation(ps, [](const double* p) {
      const double r = radius_xy(p);
      EXPECT_LE(r, 0.5 + kDelta);
      return std::abs(p[2] - 4 * r * r);
    });
    EXPECT_LE(dev, std::sqrt(17.0) * kDelta + 4 * kDelta * kDelta + kEps);
    EXPECT_GT(dev, 0.5 * kDelta);  // disturbed, not exactly on the surface
    // Uniform in the disk: a quarter of the points within radius 0.25.
    int inner = 0;
    for (std::uint32_t i = 0; i < ps.size(); ++i) inner += radius_xy(ps.p(i)) < 0.25;
    EXPECT_NEAR(double(inner) / n, 0.25, 0.015);
  }
  {
    SCOPED_TRACE("spiral");
    const PointSet ps = generate_points(Distribution::spiral, n, seed);
    const double r0 = 0.05, c = 0.45 / (6 * kPi);
    // Compare with the spiral point at the same polar angle: moving by t along the normal
    // changes the radial gap by about t sqrt(r^2 + c^2) / r <= 1.11 t (r >= 0.05).
    const double dev = max_deviation(ps, [&](const double* p) {
      EXPECT_TRUE(p[2] >= 0.0 && p[2] < 1.0);
      const double rho = radius_xy(p);
      double phi = std::atan2(p[1] - 0.5, p[0] - 0.5);
      if (phi < 0) phi += 2 * kPi;
      double best = 1e9;
      for (int k = -1; k <= 3; ++k) {
        const double theta = phi + 2 * kPi * k;
        if (theta < -0.01 || theta > 6 * kPi + 0.01) continue;
        best = std::min(best, std::abs(rho - (r0 + c * theta)));
      }
      return best;
    });
    EXPECT_LE(dev, 1.12 * kDelta + kEps);
    EXPECT_GT(dev, 0.5 * kDelta);
  }
  {
    SCOPED_TRACE("disk");
    const PointSet ps = generate_points(Distribution::disk, n, seed);
    const double dev = max_deviation(ps, [](const double* p) {
      EXPECT_LE(radius_xy(p), 0.5 + kEps);
      return std::abs(p[2] - 0.5);
    });
    EXPECT_LE(dev, kDelta + kEps);
    EXPECT_GT(dev, 0.5 * kDelta);
  }
  {
    SCOPED_TRACE("cylinder");
    const PointSet ps = generate_points(Distribution::cylinder, n, seed);
    const double dev = max_deviation(ps, [](const double* p) {
      EXPECT_TRUE(p[2] >= 0.0 && p[2] < 1.0);
      return std::abs(radius_xy(p) - 0.5);
    });
    EXPECT_LE(dev, kDelta + kEps);
    EXPECT_GT(dev, 0.5 * kDelta);
  }
  {
    SCOPED_TRACE("axes");
    const PointSet ps = generate_points(Distribution::axes, n, seed);
    int on_axis[3] = {0, 0, 0};
    for (std::uint32_t i = 0; i < ps.size(); ++i) {
      const double* p = ps.p(i);
      // Two coordinates within delta of 0, the remaining one in [0, 1).
      int small = 0, along = 0;
      for (int j = 0; j < 3; ++j) {
        if (std::abs(p[j]) <= kDelta) {
          ++small;
        } else {
          along = j;
        }
      }
      ASSERT_GE(small, 2) << "point " << i;
      if (small == 2) {
        ASSERT_TRUE(p[along] >= 0.0 && p[along] < 1.0);
        ++on_axis[along];
      }
    }
    for (const int c : on_axis) EXPECT_NEAR(double(c) / n, 1.0 / 3, 0.02);
  }
}

TEST(Distributions, SpiralIsUniformByArea) {
  // Fraction of points on each turn = its share of the arc length (z is uniform).
  const double r0 = 0.05, c = 0.45 / (6 * kPi);
  auto arc = [&](double a, double b) {  // Simpson's rule for the integral of sqrt(r^2 + c^2)
    const int steps = 2000;
    const double h = (b - a) / steps;
    double s = 0;
    for (int i = 0; i <= steps; ++i) {
      const double r = r0 + c * (a + i * h);
      s += (i == 0 || i == steps ? 1 : (i % 2 ? 4 : 2)) * std::sqrt(r * r + c * c);
    }
    return s * h / 3;
  };
  const double total = arc(0, 6 * kPi);
  const std::size_t n = 200000;
  const PointSet ps = generate_points(Distribution::spiral, n, 9);
  int turn[3] = {0, 0, 0};
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const double theta = (radius_xy(ps.p(i)) - r0) / c;  // off by < 0.005 rad
    turn[std::clamp(int(theta / (2 * kPi)), 0, 2)]++;
  }
  for (int t = 0; t < 3; ++t) {
    EXPECT_NEAR(double(turn[t]) / n, arc(2 * kPi * t, 2 * kPi * (t + 1)) / total, 0.005)
        << "turn " << t;
  }
}

TEST(Distributions, CubeIsThreeUniformDrawsPerPoint) {
  // Derived from the model's definition: cube point i is (u, u, u) from Rng(seed), in order.
  Rng rng(42);
  const PointSet cube = generate_points(Distribution::cube, 2, 42);
  for (const double v : cube.xyz) EXPECT_EQ(v, rng.uniform());
}

}  // namespace
}  // namespace kdmesh
