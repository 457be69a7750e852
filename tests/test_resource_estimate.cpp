// kdmesh — tests of the node and memory estimate (mesher/resource_estimate.h): its integrals
// against closed forms and a brute-force integration, its cap, and the memory-amount parser.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "mesher/resource_estimate.h"

namespace kdmesh {
namespace {

/// The prepared box [0, a] x [0, b] x [0, c] (12 outward facets).
PreparedSurface box(double a, double b, double c) {
  SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.push_back(a * (i & 1), b * ((i >> 1) & 1), c * ((i >> 2) & 1));
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const int t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.tris.push_back(std::uint32_t(t));
  return prepare_surface(std::move(m), "box");
}

SizingField uniform(const PreparedSurface& s, double h) {
  SizingOptions o;
  o.max_size = h;
  return build_sizing_field(s.mesh, o);
}

TEST(ResourceEstimate, UniformSizeMatchesTheClosedForms) {
  const PreparedSurface s = box(10, 20, 30);
  const SurfaceQuery q(s.mesh);
  const double h = 0.7;
  const ResourceEstimate e = estimate_resources({s, q, uniform(s, h)});
  // A constant density integrates exactly however the facets are split.
  const double area = 2 * (10 * 20 + 20 * 30 + 10 * 30);
  EXPECT_NEAR(e.surface_nodes, area / (kSurfaceDensity * h * h), 1e-6 * e.surface_nodes);
  // Volume: exact up to the octree cells the surface crosses, each counted by its centre.
  const double volume = 10 * 20 * 30;
  EXPECT_NEAR(e.interior_nodes, volume / (kVolumeDensity * h * h * h), 0.03 * e.interior_nodes);
  EXPECT_DOUBLE_EQ(e.nodes, e.surface_nodes + e.interior_nodes);
  EXPECT_FALSE(e.capped);
  EXPECT_DOUBLE_EQ(e.peak_bytes, kBaseBytes + kBytesPerNode * e.nodes + kBytesPerFacet * 12);
  // Adaptive: fewer queries than nodes, even on this small box where the surface layer of
  // octree cells dominates.
  EXPECT_LT(double(e.samples), e.nodes);
}

TEST(ResourceEstimate, GradedSizeMatchesABruteForceIntegral) {
  const PreparedSurface s = box(40, 40, 40);
  const SurfaceQuery q(s.mesh);
  SizingOptions o;
  o.max_size = 4;
  o.gradation = 0.3;
  SizingZone z;
  z.kind = SizingZone::Kind::segment;
  z.size = 0.3;
  z.coords = {5, 5, 20, 35, 30, 20};  // inside the box
  o.zones.push_back(z);
  const SizingField h = build_sizing_field(s.mesh, o);
  const ResourceEstimate e = estimate_resources({s, q, h});
  // Midpoint rule on a uniform 200^3 grid (cell 0.2, below the smallest size 0.3).
  const int n = 200;
  const double d = 40.0 / n;
  double interior = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double p[3] = {(i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d};
        const double hp = h(p);
        interior += d * d * d / (kVolumeDensity * hp * hp * hp);
      }
  EXPECT_NEAR(e.interior_nodes, interior, 0.05 * interior);
  EXPECT_FALSE(e.capped);
}

TEST(ResourceEstimate, AbsurdSizeStopsAtTheCapQuickly) {
  const PreparedSurface s = box(100, 100, 100);
  const SurfaceQuery q(s.mesh);
  const ResourceEstimate e = estimate_resources({s, q, uniform(s, 1e-3)}, 1e7);  // ~1.6e15 nodes
  EXPECT_TRUE(e.capped);
  EXPECT_EQ(e.nodes, 1e7);  // a capped estimate reports the cap: "more than 1e7 nodes"
  EXPECT_LT(e.samples, 2000000u);  // stopped once past the cap, not after 1e15 / 100 queries
}

TEST(ResourceEstimate, MemoryAmounts) {
  EXPECT_DOUBLE_EQ(parse_memory_amount("8G", "x"), 8e9);
  EXPECT_DOUBLE_EQ(parse_memory_amount("8gb", "x"), 8e9);
  EXPECT_DOUBLE_EQ(parse_memory_amount("512M", "x"), 512e6);
  EXPECT_DOUBLE_EQ(parse_memory_amount("2.5GB", "x"), 2.5e9);
  EXPECT_DOUBLE_EQ(parse_memory_amount("1000", "x"), 1000);
  EXPECT_DOUBLE_EQ(parse_memory_amount("3k", "x"), 3000);
  EXPECT_DOUBLE_EQ(parse_memory_amount("1T", "x"), 1e12);
  EXPECT_EQ(parse_memory_amount("none", "x"), -1);
  for (const char* bad : {"", "G", "-1G", "0", "8X", "8 G", "nan", "inf", "8GiB"})
    EXPECT_THROW(parse_memory_amount(bad, "--max-memory"), UsageError) << bad;
  try {
    parse_memory_amount("8X", "--max-memory");
  } catch (const UsageError& err) {
    EXPECT_NE(std::string(err.what()).find("--max-memory: '8X'"), std::string::npos) << err.what();
  }
  EXPECT_EQ(format_bytes(999), "999 bytes");
  EXPECT_EQ(format_bytes(1.5e9), "1.5 GB");
  EXPECT_EQ(format_bytes(2.34e6), "2.34 MB");
  EXPECT_GT(physical_memory_bytes(), 1e8);
}

}  // namespace
}  // namespace kdmesh
