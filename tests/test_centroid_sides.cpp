// kdmesh — tests of centroid_sides (mesher/quality/centroid_sides.h): the mesh check's inside
// test carried between neighbouring tets must give every centroid the side SurfaceQuery::side
// gives it, whatever the tets' place against the surface.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "mesher/quality/centroid_sides.h"
#include "mesher/surface/surface_query.h"
#include "tests/support/icosphere.h"

namespace kdmesh {
namespace {

/// The unit icosphere scaled to radius r.
SurfaceMesh sphere(double r, int levels) {
  SurfaceMesh s = test::icosphere(levels);
  for (double& x : s.points.xyz) x *= r;
  return s;
}

/// A grid of n^3 cubes over [-s, s]^3, each cut into 6 tets around its main diagonal (Kuhn),
/// with the pairs of tets that share a face.
struct Grid {
  PointSet points;
  std::vector<std::uint32_t> tets;
  std::vector<TetPair> neighbours;
};

Grid kuhn_grid(int n, double s) {
  Grid g;
  auto id = [n](int i, int j, int k) { return std::uint32_t((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) g.points.push_back(-s + 2 * s * i / n, -s + 2 * s * j / n, -s + 2 * s * k / n);
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : kPerm) {  // the path from corner 0 to corner 7 along axes p[0], p[1], p[2]
          int c[3] = {i, j, k};
          std::array<std::uint32_t, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s2 = 0; s2 < 3; ++s2) {
            ++c[p[s2]];
            t[s2 + 1] = id(c[0], c[1], c[2]);
          }
          g.tets.insert(g.tets.end(), t.begin(), t.end());
        }
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> seen;
  for (std::uint32_t t = 0; t < g.tets.size() / 4; ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<std::uint32_t, 3> key;
      for (int q = 0, w = 0; q < 4; ++q)
        if (q != f) key[w++] = g.tets[4 * t + q];
      std::sort(key.begin(), key.end());
      const auto [it, fresh] = seen.emplace(key, t);
      if (!fresh) g.neighbours.push_back({it->second, t});
    }
  return g;
}

TEST(CentroidSides, EveryTetGetsTheInsideTestsAnswer) {
  const SurfaceMesh s = sphere(10, 3);  // 1,280 facets; the grid spans it, and tets cross it
  const SurfaceQuery q(s);
  for (const double span : {12.0, 10.0, 7.0}) {  // around it, its corners inside, all inside
    const Grid g = kuhn_grid(12, span);
    const std::vector<std::int8_t> got = centroid_sides(g.points, g.tets, g.neighbours, q);
    ASSERT_EQ(got.size(), g.tets.size() / 4);
    int inside = 0, outside = 0;
    for (std::size_t t = 0; t < got.size(); ++t) {
      double c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = (g.points.p(g.tets[4 * t])[k] + g.points.p(g.tets[4 * t + 1])[k] + g.points.p(g.tets[4 * t + 2])[k] +
                g.points.p(g.tets[4 * t + 3])[k]) / 4;
      ASSERT_EQ(got[t], q.side(c)) << "tet " << t << " of the grid over +-" << span;
      (got[t] > 0 ? inside : outside)++;
    }
    EXPECT_GT(inside, 0);
    if (span > 10) {
      EXPECT_GT(outside, 0);  // both sides met
    }
  }
}

}  // namespace
}  // namespace kdmesh
