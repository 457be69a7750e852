// kdmesh — tests of SurfaceQuery (mesher/surface/surface_query.h): the side of a point and the
// facet-box certificate that carries a known side along a short segment.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <vector>
#include <utility>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "core/rng.h"
#include "core/triangle_distance.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {
namespace {

/// A closed, outward-oriented sphere of radius r: an octahedron subdivided `levels` times,
/// vertices pushed onto the sphere (curved, with many small facets in every direction).
SurfaceMesh sphere(double r, int levels) {
  std::vector<std::array<double, 3>> p = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<std::array<std::uint32_t, 3>> t = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::vector<std::array<std::uint32_t, 3>> next;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      std::array<double, 3> m;
      for (int k = 0; k < 3; ++k) m[k] = (p[a][k] + p[b][k]) / 2;
      p.push_back(m);
      return mid[key] = std::uint32_t(p.size() - 1);
    };
    for (const auto& f : t) {
      const std::uint32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({a, f[1], b});
      next.push_back({c, b, f[2]});
      next.push_back({a, b, c});
    }
    t = next;
  }
  SurfaceMesh s;
  for (auto& q : p) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    s.points.push_back(r * q[0] / n, r * q[1] / n, r * q[2] / n);
  }
  for (const auto& f : t) s.tris.insert(s.tris.end(), f.begin(), f.end());
  return s;
}

/// The cube [0, 1]^3, outward, two facets a side.
SurfaceMesh unit_cube() {
  SurfaceMesh unit;
  for (int i = 0; i < 8; ++i) unit.points.push_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const std::uint32_t v : {q[0], q[1], q[2], q[0], q[2], q[3]}) unit.tris.push_back(v);
  return unit;
}

// The side of a point is exact at every magnitude. Points on a grid in a cube of side 2^k
// include the centre and others whose vertical line meets the facets' diagonals, so the
// inside test must fall back from the vertical direction to others. Up to issue 19 that
// fallback (CGAL's Point_inside_vertical_ray_cast) cast rays p + u of a unit vector u, whose
// direction is rounded away at coordinates of 2^52 and beyond: the cube's centre came out
// "outside" from k = 52, and at k >= 54 every point on such a line did (see ray_parity.h).
TEST(SurfaceQuery, SideIsExactAtEveryMagnitude) {
  const SurfaceMesh unit = unit_cube();
  constexpr int n = 8;  // grid steps per side: i / n is exact, on and off the diagonals
  // Every binade from near the smallest normal doubles to near the largest (the grid's
  // coordinates stay normal and finite), and each side of 2^52 and 2^53 closely.
  std::vector<int> exps;
  for (int k = -1000; k <= 1000; k += 50) exps.push_back(k);
  for (int k = 48; k <= 58; ++k) exps.push_back(k);
  for (const int k : exps) {
    SurfaceMesh m = unit;
    for (double& x : m.points.xyz) x = std::ldexp(x, k);
    const SurfaceQuery q(m);
    int wrong = 0;
    for (int i = -1; i <= n + 1; ++i)
      for (int j = -1; j <= n + 1; ++j)
        for (int l = -1; l <= n + 1; ++l) {
          const double p[3] = {std::ldexp(double(i) / n, k), std::ldexp(double(j) / n, k), std::ldexp(double(l) / n, k)};
          const auto in = [](int c) { return c > 0 && c < n; };
          const auto out = [](int c) { return c < 0 || c > n; };
          const int expected = in(i) && in(j) && in(l) ? 1 : out(i) || out(j) || out(l) ? -1 : 0;
          wrong += q.side(p) != expected;
        }
    EXPECT_EQ(wrong, 0) << "cube of side 2^" << k;
  }
}

// side() answers a point in a cell that lists facets from the cell's centre when the segment
// between them is clear, and from the long parity segment otherwise. A hollow cube with walls
// 1/64 thick (much thinner than a cell) puts wall, cavity and outside in the same cells, so
// many points have a centre on the other side of a wall; points on the walls, one ulp off them
// and anywhere else are compared with the exact answer, which coordinate comparisons give
// here. Two queries answer the points in opposite orders: the cells' cached sides must not
// matter. Taking the centre's side without the segment test fails this.
TEST(SurfaceQuery, SideInCellsWithFacetsIsExact) {
  SurfaceMesh s = unit_cube();
  const double a = 1.0 / 64, b = 1 - a;
  SurfaceMesh inner = unit_cube();
  for (double& x : inner.points.xyz) x = x == 0 ? a : b;
  for (std::size_t f = 0; f < inner.num_tris(); ++f) std::swap(inner.tris[3 * f + 1], inner.tris[3 * f + 2]);  // inward
  const std::uint32_t base = std::uint32_t(s.points.size());
  for (std::size_t v = 0; v < inner.points.size(); ++v) s.points.push_back(inner.points.p(std::uint32_t(v))[0],
                                                                          inner.points.p(std::uint32_t(v))[1],
                                                                          inner.points.p(std::uint32_t(v))[2]);
  for (const std::uint32_t v : inner.tris) s.tris.push_back(base + v);
  auto exact = [&](const double* p) {
    const auto all = [&](auto in) { return in(p[0]) && in(p[1]) && in(p[2]); };
    if (!all([](double x) { return x >= 0 && x <= 1; })) return -1;
    if (!all([](double x) { return x > 0 && x < 1; })) return 0;  // on the outer walls
    if (all([&](double x) { return x > a && x < b; })) return -1;  // in the cavity
    return all([&](double x) { return x >= a && x <= b; }) ? 0 : 1;  // on the inner walls, or in a wall
  };
  std::vector<std::array<double, 3>> points;
  Rng rng(17);
  const double marks[] = {0, a, b, 1};  // the walls' planes
  for (int i = 0; i < 60000; ++i) {
    std::array<double, 3> p;
    for (double& x : p) {
      const int kind = int(rng.uniform(0, 4));
      const double m = marks[int(rng.uniform(0, 4)) & 3];
      x = kind == 0 ? m : kind == 1 ? std::nextafter(m, rng.uniform(0, 1) < 0.5 ? -1.0 : 2.0)
        : kind == 2 ? m + rng.uniform(-a, a) : rng.uniform(-0.1, 1.1);
    }
    points.push_back(p);
  }
  const SurfaceQuery forward(s), backward(s);
  int counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int want = exact(points[i].data());
    ASSERT_EQ(forward.side(points[i].data()), want) << "point " << i;
    ++counts[want + 1];
  }
  for (std::size_t i = points.size(); i-- > 0;)
    ASSERT_EQ(backward.side(points[i].data()), exact(points[i].data())) << "point " << i;
  EXPECT_GT(counts[0], 5000);  // outside or in the cavity
  EXPECT_GT(counts[1], 5000);  // on a wall
  EXPECT_GT(counts[2], 5000);  // in a wall
}

/// Brute force: the least distance from x to any facet of s.
double brute_distance(const SurfaceMesh& s, const double* x) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < s.num_tris(); ++f)
    best = std::min(best, triangle_distance(x, s.points.p(s.tri(f)[0]), s.points.p(s.tri(f)[1]),
                                            s.points.p(s.tri(f)[2])));
  return best;
}

// The facet grid's queries hold at every magnitude too: a clear segment joins two points of
// one side, a segment between the two sides is never clear, and the distance is the brute
// force's. The grid's point-triangle arithmetic takes products of four coordinates, which
// overflowed for a cube of side 2^300 and up: no facet was registered in any cell, so
// segment_clear called segments across the surface clear (and, with the cells' sides kept
// since, side() answered for the whole cube from one point). Beyond its scale range the grid
// now leaves every query to the tree.
TEST(SurfaceQuery, GridQueriesHoldAtEveryMagnitude) {
  const SurfaceMesh unit = unit_cube();
  for (const int k : {-1000, -600, -300, -256, -200, -100, 0, 100, 200, 250, 256, 300, 600, 1000}) {
    SurfaceMesh m = unit;
    for (double& x : m.points.xyz) x = std::ldexp(x, k);
    const SurfaceQuery q(m);
    Rng rng(std::uint64_t(k + 2000));
    int crossing = 0, clear = 0;
    for (int i = 0; i < 400; ++i) {
      double a[3], b[3];
      for (int c = 0; c < 3; ++c) a[c] = std::ldexp(rng.uniform(-0.3, 1.3), k), b[c] = std::ldexp(rng.uniform(-0.3, 1.3), k);
      const int sa = q.side(a), sb = q.side(b);
      if (q.segment_clear(a, b)) {
        ASSERT_TRUE(sa != 0 && sa == sb) << "2^" << k << " segment " << i;
        ++clear;
      }
      if (sa * sb < 0) {
        ASSERT_FALSE(q.segment_clear(a, b)) << "2^" << k << " segment " << i;
        ++crossing;
      }
      if (k >= -250 && k <= 250) {  // (the brute force takes products of four coordinates too)
        const double want = brute_distance(m, a);
        ASSERT_NEAR(q.distance(a), want, 1e-12 * want) << "2^" << k << " point " << i;
      }
    }
    EXPECT_GT(clear, 40) << "2^" << k;
    EXPECT_GT(crossing, 40) << "2^" << k;
  }
}

// distance() searches the facet box grid near the surface and the AABB tree farther away:
// both must give the least point-facet distance, near, far, outside the bounding box, on
// a sphere of small facets and on a slab of long thin ones (boxes spanning many cells).
TEST(SurfaceQuery, DistanceIsTheNearestFacetsNearAndFar) {
  SurfaceMesh slab;  // a 100 x 1 x 1 box, each long face two triangles 100 long
  for (int i = 0; i < 8; ++i) slab.points.push_back(i & 1 ? 100.0 : 0.0, i & 2 ? 1.0 : 0.0, i & 4 ? 1.0 : 0.0);
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) slab.tris.insert(slab.tris.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  // A gear-like prism: 400 long needle facets around (each ~500 times longer than wide, so
  // a point near one lies in many facet boxes, and a plane's computed normal is least
  // certain), closed by two coplanar fans (many facets at one plane distance).
  SurfaceMesh prism;
  constexpr int kSides = 200;
  for (int end = 0; end < 2; ++end) {
    for (int i = 0; i < kSides; ++i) {
      const double a = 6.283185307179586 * i / kSides, r = i % 2 ? 1.0 : 0.9;  // teeth
      prism.points.push_back(r * std::cos(a), r * std::sin(a), end * 15.0);
    }
    prism.points.push_back(0.0, 0.0, end * 15.0);  // the fan's centre
  }
  const std::uint32_t c0 = kSides, c1 = 2 * kSides + 1;
  for (std::uint32_t i = 0; i < kSides; ++i) {
    const std::uint32_t j = (i + 1) % kSides, a0 = i, b0 = j, a1 = kSides + 1 + i, b1 = kSides + 1 + j;
    prism.tris.insert(prism.tris.end(), {a0, b0, b1, a0, b1, a1, c0, b0, a0, c1, a1, b1});
  }
  for (const SurfaceMesh& s : {sphere(10, 4), slab, prism}) {
    const SurfaceQuery q(s);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t v = 0; v < s.points.size(); ++v)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], s.points.p(v)[k]), hi[k] = std::max(hi[k], s.points.p(v)[k]);
    Rng rng(11);
    for (int i = 0; i < 3000; ++i) {
      double x[3];
      const double pad = i % 3 == 0 ? 0.01 : i % 3 == 1 ? 0.3 : 3.0;  // near the box, around it, far out
      for (int k = 0; k < 3; ++k) {
        const double span = hi[k] - lo[k];
        x[k] = rng.uniform(lo[k] - pad * span, hi[k] + pad * span);
      }
      if (i % 5 == 0) {  // on or just off a facet: a random point of one
        const std::uint32_t* t = s.tri(std::size_t(rng.uniform(0, double(s.num_tris()))) % s.num_tris());
        const double u = rng.uniform(), w = rng.uniform() * (1 - u), off = i % 10 == 0 ? 0.0 : rng.uniform(-1e-3, 1e-3);
        for (int k = 0; k < 3; ++k)
          x[k] = s.points.p(t[0])[k] + u * (s.points.p(t[1])[k] - s.points.p(t[0])[k]) +
                 w * (s.points.p(t[2])[k] - s.points.p(t[0])[k]) + off;
      }
      const double want = brute_distance(s, x);
      ASSERT_NEAR(q.distance(x), want, 1e-12 * (1 + want)) << "point " << i << " of " << s.num_tris() << " facets";
    }
  }
}

// segment_clear searches the facets near the cells a segment spans, or the tree for a long
// one: a clear segment joins two points strictly on one side, and two points on different
// sides are never joined by a clear segment.
TEST(SurfaceQuery, ClearSegmentsJoinPointsOfOneSide) {
  const SurfaceMesh s = sphere(10, 3);
  const SurfaceQuery q(s);
  Rng rng(5);
  int clear = 0, crossing = 0, blocked_same_side = 0;
  for (int i = 0; i < 20000; ++i) {
    double a[3], b[3];
    const double len = i % 3 == 0 ? 0.05 : i % 3 == 1 ? 1.0 : 20.0;  // few cells, some, many (the tree)
    for (int k = 0; k < 3; ++k) a[k] = rng.uniform(-11, 11), b[k] = a[k] + rng.uniform(-len, len);
    const int sa = q.side(a), sb = q.side(b);
    if (q.segment_clear(a, b)) {
      ASSERT_NE(sa, 0) << "segment " << i;
      ASSERT_EQ(sa, sb) << "segment " << i;
      ++clear;
    } else if (sa != sb) {
      ++crossing;
    } else {
      ++blocked_same_side;  // in and out again, or near a facet
    }
  }
  EXPECT_GT(clear, 1000);
  EXPECT_GT(crossing, 1000);
  EXPECT_GT(blocked_same_side, 10);
}

TEST(SurfaceQuery, SegmentsTouchingTheSurfaceAtOnePointAreNotClear) {
  // A facet corner at (10, 0, 0): a segment ending exactly there meets the (closed) facets;
  // one ending just outside does not.
  const SurfaceMesh s = sphere(10, 0);
  const SurfaceQuery q(s);
  const double a[3] = {12, 0, 0}, corner[3] = {10, 0, 0}, near[3] = {10.000001, 0, 0};
  EXPECT_FALSE(q.segment_clear(a, corner));
  EXPECT_TRUE(q.segment_clear(a, near));
  EXPECT_FALSE(q.segment_clear(corner, corner));  // a point on the surface
}

// segment_clear passes over a facet when both ends lie on one side of its plane, farther than
// the rounding slack of the computed distance, and otherwise asks the exact test. The cube's
// facets lie in coordinate planes, so points exactly on them are representable: a segment
// ending on a facet, or at any distance down to one ulp of the plane, is judged like the exact
// test; so is a segment in the plane of a facet, beside the cube or across its edge.
TEST(SurfaceQuery, SegmentsEndingOnAFacetOrBesideItsPlaneAreJudgedExactly) {
  SurfaceMesh s;
  for (int i = 0; i < 8; ++i) s.points.push_back(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0);
  s.tris = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  const SurfaceQuery q(s);
  Rng rng(11);
  for (int i = 0; i < 4000; ++i) {
    const int axis = i % 3;
    double on[3], off[3];
    for (int k = 0; k < 3; ++k) on[k] = rng.uniform(-0.85, 0.85);  // off stays within the other faces
    on[axis] = 1;  // on the facet
    const double gap = std::ldexp(1.0, -int(rng.uniform(1, 53)));  // 2^-1 .. 2^-52
    for (int k = 0; k < 3; ++k) off[k] = on[k] + rng.uniform(-0.1, 0.1);
    off[axis] = i % 2 ? 1 + gap : 1 - gap;  // outside or inside, down to one ulp of 1
    ASSERT_FALSE(q.segment_clear(off, on)) << "segment " << i;
    double near[3] = {on[0], on[1], on[2]};
    near[axis] = off[axis];
    ASSERT_TRUE(q.segment_clear(off, near)) << "segment " << i;  // parallel to the facet, off it
    ASSERT_EQ(q.side(near), i % 2 ? -1 : 1);
  }
  const double beside_a[3] = {1.5, 0, 1}, beside_b[3] = {2, 0.5, 1}, across[3] = {0.5, 0, 1};
  EXPECT_TRUE(q.segment_clear(beside_a, beside_b));  // in the plane z = 1, off the cube
  EXPECT_FALSE(q.segment_clear(beside_a, across));   // in that plane, over the facet's edge
}

// closest() answers from the facet grid where one facet is nearest by a margin, and from
// CGAL's AABB tree elsewhere. Either way the answer must be the tree's, bit for bit: the point,
// the facet and the distance. The cube's points on its edges and corners (and the sphere's on
// its facets' edges) are ties, where the tree's choice depends on its traversal.
TEST(SurfaceQuery, ClosestIsTheAabbTreesAnswerBitForBit) {
  using K = CGAL::Epick;
  using Triangles = std::vector<K::Triangle_3>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>>>;
  SurfaceMesh cube;
  for (int i = 0; i < 8; ++i) cube.points.push_back(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0);
  cube.tris = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
               2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  for (const SurfaceMesh& s : {sphere(10, 3), cube}) {
    Triangles tris;
    for (std::size_t f = 0; f < s.num_tris(); ++f) {
      const double *a = s.points.p(s.tri(f)[0]), *b = s.points.p(s.tri(f)[1]), *c = s.points.p(s.tri(f)[2]);
      tris.emplace_back(K::Point_3(a[0], a[1], a[2]), K::Point_3(b[0], b[1], b[2]), K::Point_3(c[0], c[1], c[2]));
    }
    // Built as SurfaceQuery builds its own: at ties the answer depends on it (the tree made by
    // the range constructor picks another of the tied facets).
    Tree tree;
    tree.insert(tris.cbegin(), tris.cend());
    tree.build();
    tree.accelerate_distance_queries();
    const SurfaceQuery q(s);
    double extent = 0;
    for (double x : s.points.xyz) extent = std::max(extent, std::fabs(x));
    Rng rng(7);
    int ties = 0;
    for (int i = 0; i < 6000; ++i) {
      double p[3];
      if (i % 3 == 0) {  // on an edge of a facet, or off it along the facet's normal-ish
        const std::uint32_t* t = s.tri(std::size_t(rng.uniform(0, double(s.num_tris()) - 1e-9)));
        const double w = i % 2 ? 0.5 : rng.uniform();
        const double *a = s.points.p(t[0]), *b = s.points.p(t[1]);
        const double lift = i % 9 == 0 ? 0.0 : rng.uniform(-0.3, 0.3);
        for (int k = 0; k < 3; ++k) p[k] = (1 + lift) * (a[k] + w * (b[k] - a[k]));
        ++ties;
      } else {
        const double r = (i % 3 == 1 ? 0.5 : 1.3) * extent;
        for (double& x : p) x = rng.uniform(-r, r);
      }
      double out[3];
      std::uint32_t facet = 0;
      const double d = q.closest(p, out, &facet);
      const K::Point_3 qp(p[0], p[1], p[2]);
      const auto [c, id] = tree.closest_point_and_primitive(qp);
      ASSERT_EQ(out[0], c.x()) << "point " << i;
      ASSERT_EQ(out[1], c.y()) << "point " << i;
      ASSERT_EQ(out[2], c.z()) << "point " << i;
      ASSERT_EQ(facet, std::uint32_t(id - tris.cbegin())) << "point " << i;
      ASSERT_EQ(d, std::sqrt(CGAL::squared_distance(qp, c))) << "point " << i;
    }
    EXPECT_GT(ties, 1000);
  }
}

/// A random vertex of s (returned), and into p a point at most `spread` from it per axis.
const double* near_a_vertex(const SurfaceMesh& s, Rng& rng, double spread, double* p) {
  const double* v = s.points.p(std::uint32_t(rng.uniform(0, double(s.points.size()) - 1e-9)));
  for (int k = 0; k < 3; ++k) p[k] = v[k] + rng.uniform(-spread, spread);
  return v;
}

// within(p, r, hint) is distance(p, hint) <= r, and within(p, r) is distance(p) <= r, decided
// from the facet grid where the margins allow: the same answers for radii around the distance
// (at it exactly, 1 ulp either side, a little off, 0 and beyond the sphere), for hints on the
// surface (the callers' face corners) and off it (where |p - hint| decides), near the surface
// and far from it. (The resource estimate asks within(p, r) of its cells' centres.)
TEST(SurfaceQuery, WithinIsTheDistanceComparedWithTheRadius) {
  const SurfaceMesh s = sphere(10, 3);
  const SurfaceQuery q(s);
  Rng rng(13);
  int yes = 0, no = 0;
  auto check = [&](int i, double d, double r, bool got) {
    const bool want = d <= r;
    ASSERT_EQ(got, want) << "point " << i << " r " << r << " d " << d;
    (want ? yes : no) += 1;
  };
  for (int i = 0; i < 20000; ++i) {
    double p[3], hint[3];
    const double* v = near_a_vertex(s, rng, i % 4 == 0 ? 12.0 : 0.4, p);
    const double lift = i % 5 == 0 ? 1.0 + rng.uniform(-0.05, 0.05) : 1.0;  // some hints off the surface
    for (int k = 0; k < 3; ++k) hint[k] = lift * v[k];
    for (const bool hinted : {true, false}) {
      const double d = hinted ? q.distance(p, hint) : q.distance(p);
      for (const double r : {d, std::nextafter(d, 0.0), std::nextafter(d, INFINITY), d * 0.9, d * 1.1,
                             0.5 * d + 0.1, 0.0, 25.0})
        check(i, d, r, hinted ? q.within(p, r, hint) : q.within(p, r));
      if (HasFatalFailure()) return;
    }
  }
  EXPECT_GT(yes, 40000);
  EXPECT_GT(no, 40000);
}

}  // namespace
}  // namespace kdmesh
