// The seven point distributions: names, determinism, counts, distance to their models,
// seeds, and (roughly) the sampling densities.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "tools/bench/lib/distributions.h"

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

// ---- The practical models: constrained-cube and refined-constrained-cube ----
namespace kdmesh {
namespace {

// constrained-cube's field, as documented in distributions.cpp: h(d) = min(10, 1 + 30 d),
// d = distance to the nearest of the edges {y=z=0}, {x=z=0}, {x=y=0}.
double cc_distance(const double* p) {
  const double d0 = std::hypot(p[1], p[2]);
  const double d1 = std::hypot(p[0], p[2]);
  const double d2 = std::hypot(p[0], p[1]);
  return std::min(d0, std::min(d1, d2));
}
double cc_spacing(double d) { return std::min(10.0, 1.0 + 30.0 * d); }

TEST(PracticalDistributions, Names) {
  const std::vector<Distribution> prac = practical_distributions();
  ASSERT_EQ(prac.size(), 2u);
  EXPECT_EQ(prac[0], Distribution::constrained_cube);
  EXPECT_EQ(prac[1], Distribution::refined_constrained_cube);
  EXPECT_EQ(distribution_name(prac[0]), "constrained-cube");
  EXPECT_EQ(distribution_name(prac[1]), "refined-constrained-cube");
  EXPECT_EQ(parse_distribution("constrained-cube"), Distribution::constrained_cube);
  EXPECT_EQ(parse_distribution("refined-constrained-cube"),
            Distribution::refined_constrained_cube);
  // The paper's seven stay alone in all_distributions().
  for (const Distribution d : all_distributions()) {
    EXPECT_NE(d, Distribution::constrained_cube);
    EXPECT_NE(d, Distribution::refined_constrained_cube);
  }
  EXPECT_EQ(all_distributions().size(), 7u);
}

TEST(PracticalDistributions, CountsDeterminismAndInsideTheCube) {
  for (const Distribution d : practical_distributions()) {
    SCOPED_TRACE(std::string(distribution_name(d)));
    EXPECT_TRUE(generate_points(d, 0, 1).empty());
    for (const std::size_t n : {1u, 2u, 4u, 5u, 6u, 9u, 10u, 11u}) {
      EXPECT_EQ(generate_points(d, n, 3).size(), n);
    }
    const PointSet a = generate_points(d, 5003, 17);
    const PointSet b = generate_points(d, 5003, 17);
    const PointSet c = generate_points(d, 5003, 18);
    ASSERT_EQ(a.size(), 5003u);
    ASSERT_EQ(a.xyz.size(), 3u * 5003u);
    EXPECT_EQ(a.xyz, b.xyz);  // bit-identical
    EXPECT_NE(a.xyz, c.xyz);
    for (const double v : a.xyz) ASSERT_TRUE(v >= 0.0 && v < 1.0) << v;
  }
  // constrained-cube draws point after point: a shorter run is a prefix of a longer one.
  const PointSet a = generate_points(Distribution::constrained_cube, 5000, 17);
  const PointSet p = generate_points(Distribution::constrained_cube, 100, 17);
  EXPECT_TRUE(std::equal(p.xyz.begin(), p.xyz.end(), a.xyz.begin()));
}

TEST(PracticalDistributions, ConstrainedCubeIsGraded) {
  const std::size_t n = 200000;
  const PointSet ps = generate_points(Distribution::constrained_cube, n, 5);
  // Within r = 0.05 of the edges h <= 1 + 30 r = 2.5, while in the far corner box
  // [0.5,1]^3 (d >= sqrt(0.5) > 0.3) h = 10: the density ratio is at least (10/2.5)^3 = 64
  // pointwise, hence on average. Volume within r of the three edges inside the cube, by
  // inclusion-exclusion (three quarter cylinders, pairwise overlaps 2r^3/3, the triple one
  // the tricylinder's octant (2 - sqrt 2) r^3): 3 pi r^2 / 4 - sqrt(2) r^3.
  const double r = 0.05;
  const double v_near = 3 * kPi * r * r / 4 - std::sqrt(2.0) * r * r * r;
  const double v_far = 0.125;
  std::size_t near = 0, far = 0;
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const double* p = ps.p(i);
    if (cc_distance(p) < r) ++near;
    if (p[0] >= 0.5 && p[1] >= 0.5 && p[2] >= 0.5) ++far;
  }
  ASSERT_GT(far, 100u);
  const double ratio = (double(near) / v_near) / (double(far) / v_far);
  std::printf("constrained-cube: %zu of %zu points within 0.05 of the edges, %zu in [0.5,1]^3; "
              "density ratio %.1f (bound 64)\n",
              near, n, far, ratio);
  EXPECT_GE(ratio, 64.0);
  EXPECT_LE(ratio, 1000.0);  // (H/h0)^3: the largest possible
  // The three edges are treated alike.
  int nearest[3] = {0, 0, 0};
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const double* p = ps.p(i);
    const double d[3] = {std::hypot(p[1], p[2]), std::hypot(p[0], p[2]), std::hypot(p[0], p[1])};
    nearest[int(std::min_element(d, d + 3) - d)]++;
  }
  for (const int c : nearest) EXPECT_NEAR(double(c) / n, 1.0 / 3, 0.01);
}

TEST(PracticalDistributions, ConstrainedCubeFollowsItsField) {
  // Compare with a brute-force reference sampler of the same density h(d)^-3: uniform
  // proposals accepted with probability (h0/h)^3. Fractions of points in distance bands.
  const double edges[] = {0.0, 0.01, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 10.0};
  constexpr int kBands = 8;
  auto bands = [&](const PointSet& ps) {
    std::vector<double> f(kBands, 0.0);
    for (std::uint32_t i = 0; i < ps.size(); ++i) {
      const double d = cc_distance(ps.p(i));
      for (int b = 0; b < kBands; ++b) {
        if (d >= edges[b] && d < edges[b + 1]) f[b] += 1.0 / double(ps.size());
      }
    }
    return f;
  };
  PointSet ref;
  Rng rng(1234);
  while (ref.size() < 60000) {
    const double x = rng.uniform(), y = rng.uniform(), z = rng.uniform();
    const double p[3] = {x, y, z};
    const double h = cc_spacing(cc_distance(p));
    if (rng.uniform() * h * h * h < 1.0) ref.push_back(x, y, z);
  }
  const std::vector<double> want = bands(ref);
  const std::vector<double> got = bands(generate_points(Distribution::constrained_cube, 200000, 7));
  for (int b = 0; b < kBands; ++b) {
    // Binomial standard deviation of the reference fraction is at most 0.002.
    EXPECT_NEAR(got[b], want[b], 0.01) << "band [" << edges[b] << ", " << edges[b + 1] << ")";
  }
}

TEST(PracticalDistributions, RefinedConstrainedCube) {
  const std::size_t n = 100000;
  const PointSet ps = generate_points(Distribution::refined_constrained_cube, n, 11);
  ASSERT_EQ(ps.size(), n);
  // The first n - n/5 points are the constrained cube of that size and seed.
  const PointSet base = generate_points(Distribution::constrained_cube, n - n / 5, 11);
  EXPECT_TRUE(std::equal(base.xyz.begin(), base.xyz.end(), ps.xyz.begin()));
  // No exact duplicates.
  std::vector<std::array<double, 3>> pts(n);
  for (std::uint32_t i = 0; i < n; ++i) pts[i] = {ps.p(i)[0], ps.p(i)[1], ps.p(i)[2]};
  std::sort(pts.begin(), pts.end());
  EXPECT_EQ(std::adjacent_find(pts.begin(), pts.end()), pts.end());
  // The added points are midpoints of nearby pairs: they follow the graded density too.
  std::size_t near_base = 0, near_mid = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    (i < base.size() ? near_base : near_mid) += cc_distance(ps.p(i)) < 0.05;
  }
  const double f_base = double(near_base) / double(base.size());
  const double f_mid = double(near_mid) / double(n - base.size());
  EXPECT_NEAR(f_mid, f_base, 0.05 * f_base + 0.01);
}

}  // namespace
}  // namespace kdmesh
