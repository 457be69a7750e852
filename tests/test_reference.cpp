// kdmesh — tests of the reference Delaunay adapters (TetGen, CGAL) and of tet comparison.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gmp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "core/ordering.h"
#include "core/point_set.h"
#include "core/rng.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"
#include "tests/support/tetgen.h"

namespace kdmesh {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers, independent of the code under test.

/// Exact sign of det[b-a, c-a, d-a] (kdmesh's orientation): a double evaluation with a
/// conservative error bound, falling back to exact rational arithmetic (GMP) when undecided.
int orient_sign(const double* a, const double* b, const double* c, const double* d) {
  const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  const double det = bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
  const double perm = std::fabs(bx) * (std::fabs(cy * dz) + std::fabs(cz * dy)) +
                      std::fabs(by) * (std::fabs(cx * dz) + std::fabs(cz * dx)) +
                      std::fabs(bz) * (std::fabs(cx * dy) + std::fabs(cy * dx));
  // The differences are rounded too; 1e-14 relative is far above the true bound (~1e-15).
  if (std::fabs(det) > 1e-14 * perm) return det > 0 ? 1 : -1;
  mpq_t q[12], t0, t1, acc;
  for (auto& x : q) mpq_init(x);
  mpq_inits(t0, t1, acc, nullptr);
  const double* pts[4] = {a, b, c, d};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) mpq_set_d(q[3 * i + k], pts[i][k]);
  // Rows r1..r3 = (b-a, c-a, d-a), stored back into q[3..11].
  for (int i = 1; i < 4; ++i)
    for (int k = 0; k < 3; ++k) mpq_sub(q[3 * i + k], q[3 * i + k], q[k]);
  auto m = [&](int r, int k) { return q[3 * r + k]; };
  mpq_set_ui(acc, 0, 1);
  const int cof[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  for (int k = 0; k < 3; ++k) {
    const int u = cof[k][0], v = cof[k][1];
    mpq_mul(t0, m(2, u), m(3, v));
    mpq_mul(t1, m(2, v), m(3, u));
    mpq_sub(t0, t0, t1);
    mpq_mul(t0, t0, m(1, k));
    if (k == 1) mpq_sub(acc, acc, t0);
    else mpq_add(acc, acc, t0);
  }
  const int s = mpq_sgn(acc);
  for (auto& x : q) mpq_clear(x);
  mpq_clears(t0, t1, acc, nullptr);
  return s;
}

PointSet random_points(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  PointSet ps;
  for (std::size_t i = 0; i < n; ++i) ps.push_back(rng.uniform(), rng.uniform(), rng.uniform());
  return ps;
}

/// Identity order, each point located from the previous one.
Ordering identity_order(std::size_t n) {
  Ordering o;
  o.name = "identity";
  for (std::uint32_t i = 0; i < n; ++i) {
    o.order.push_back(i);
    o.hint.push_back(i == 0 ? kNoHint : i - 1);
  }
  return o;
}

/// A seeded random permutation, each point located from a random earlier-inserted point.
Ordering random_order(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  Ordering o;
  o.name = "random";
  o.order.resize(n);
  std::iota(o.order.begin(), o.order.end(), 0u);
  for (std::size_t i = n; i > 1; --i) std::swap(o.order[i - 1], o.order[rng.below(i)]);
  for (std::size_t k = 0; k < n; ++k) {
    o.hint.push_back(k == 0 ? kNoHint : o.order[rng.below(k)]);
  }
  return o;
}

std::size_t count_non_positive(const PointSet& ps, const std::vector<std::uint32_t>& tets) {
  std::size_t bad = 0;
  for (std::size_t t = 0; t < tets.size(); t += 4) {
    if (orient_sign(ps.p(tets[t]), ps.p(tets[t + 1]), ps.p(tets[t + 2]), ps.p(tets[t + 3])) <= 0)
      ++bad;
  }
  return bad;
}

/// Checks the combinatorics of a tetrahedralization of a convex point set (a 3-ball whose
/// boundary is a triangulated 2-sphere): V - E + F - T = 1 (Euler characteristic of a ball);
/// every interior face is in 2 tets and every hull face in 1, so 4T = 2F - Fh; and the hull is a
/// triangulated sphere with h vertices, so Fh = 2h - 4 (from h - Eh + Fh = 2 and 3Fh = 2Eh).
void expect_ball_combinatorics(const std::vector<std::uint32_t>& tets) {
  using Edge = std::array<std::uint32_t, 2>;
  using Face = std::array<std::uint32_t, 3>;
  std::vector<std::uint32_t> verts(tets);
  std::vector<Edge> edges;
  std::vector<Face> faces;
  for (std::size_t t = 0; t < tets.size(); t += 4) {
    std::array<std::uint32_t, 4> v = {tets[t], tets[t + 1], tets[t + 2], tets[t + 3]};
    std::sort(v.begin(), v.end());
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.push_back({v[i], v[j]});
    for (int skip = 0; skip < 4; ++skip) {
      Face f{};
      for (int i = 0, k = 0; i < 4; ++i)
        if (i != skip) f[k++] = v[i];
      faces.push_back(f);
    }
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::sort(faces.begin(), faces.end());
  std::vector<Face> unique_faces, hull_faces;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    ASSERT_LE(j - i, 2u) << "a face shared by more than two tets";
    unique_faces.push_back(faces[i]);
    if (j - i == 1) hull_faces.push_back(faces[i]);
    i = j;
  }
  std::vector<std::uint32_t> hull_verts;
  for (const Face& f : hull_faces) hull_verts.insert(hull_verts.end(), f.begin(), f.end());
  std::sort(hull_verts.begin(), hull_verts.end());
  hull_verts.erase(std::unique(hull_verts.begin(), hull_verts.end()), hull_verts.end());

  const long long V = (long long)verts.size(), E = (long long)edges.size(),
                  F = (long long)unique_faces.size(), T = (long long)tets.size() / 4,
                  Fh = (long long)hull_faces.size(), h = (long long)hull_verts.size();
  EXPECT_EQ(V - E + F - T, 1);
  EXPECT_EQ(4 * T, 2 * F - Fh);
  EXPECT_EQ(Fh, 2 * h - 4);
}

void expect_same_set(const PointSet& ps, const std::vector<std::uint32_t>& a,
                     const std::vector<std::uint32_t>& b, const char* what) {
  const TetComparison c = compare_tets(ps, a, b);
  EXPECT_TRUE(c.same_set()) << what << ": " << c.tets_a << " vs " << c.tets_b << " tets, "
                            << c.only_in_a << " only in first, " << c.only_in_b
                            << " only in second";
}

double rel_diff(double a, double b) { return std::fabs(a - b) / std::max(std::fabs(b), 1e-300); }

// ---------------------------------------------------------------------------------------------
// canonical_point_ids, compare_tets, total_volume

TEST(CanonicalIds, HandExample) {
  PointSet ps;
  ps.push_back(0, 0, 0);     // 0
  ps.push_back(1, 0, 0);     // 1
  ps.push_back(0, 0, 0);     // 2 -> 0
  ps.push_back(1, 0, 1e-300);  // 3 (distinct from 1)
  ps.push_back(-0.0, 0, 0);  // 4 -> 0 (-0 == +0)
  ps.push_back(1, 0, 0);     // 5 -> 1
  ps.push_back(1, 0, 1e-300);  // 6 -> 3
  EXPECT_EQ(canonical_point_ids(ps), (std::vector<std::uint32_t>{0, 1, 0, 3, 0, 1, 3}));
  EXPECT_TRUE(canonical_point_ids(PointSet{}).empty());
}

TEST(CanonicalIds, MatchesOrderedMapOnManyDuplicates) {
  Rng rng(7);
  PointSet ps;
  for (int i = 0; i < 20000; ++i) {
    // Few distinct values per coordinate: many exact repeats.
    ps.push_back(double(rng.below(8)) / 8, double(rng.below(8)) / 8, double(rng.below(8)));
  }
  std::map<std::tuple<double, double, double>, std::uint32_t> first;
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 0; i < ps.size(); ++i) {
    const double* p = ps.p(i);
    expected.push_back(first.emplace(std::make_tuple(p[0], p[1], p[2]), i).first->second);
  }
  EXPECT_EQ(canonical_point_ids(ps), expected);
}

TEST(TetCompare, DetectsOneDifferingTetAndReportsIt) {
  const PointSet ps = random_points(6, 3);
  const std::vector<std::uint32_t> a = {0, 1, 2, 3, 1, 2, 3, 4, 2, 3, 4, 5};
  // Same tets with vertices permuted and listed in another order ...
  const std::vector<std::uint32_t> a2 = {4, 3, 1, 2, 0, 1, 3, 2, 5, 4, 3, 2};
  const TetComparison same = compare_tets(ps, a, a2);
  EXPECT_TRUE(same.same_set());
  EXPECT_EQ(same.tets_a, 3u);
  EXPECT_DOUBLE_EQ(same.volume_a, same.volume_b);
  // ... and with one tet replaced.
  const std::vector<std::uint32_t> b = {4, 3, 1, 2, 0, 1, 3, 2, 5, 4, 3, 0};
  const TetComparison diff = compare_tets(ps, a, b);
  EXPECT_FALSE(diff.same_set());
  EXPECT_TRUE(diff.same_count());
  EXPECT_EQ(diff.only_in_a, 1u);
  EXPECT_EQ(diff.only_in_b, 1u);
  EXPECT_EQ(diff.example_only_a, (std::vector<std::uint32_t>{2, 3, 4, 5}));
  EXPECT_EQ(diff.example_only_b, (std::vector<std::uint32_t>{0, 3, 4, 5}));
  // A missing tet.
  const TetComparison fewer = compare_tets(ps, a, {0, 1, 2, 3});
  EXPECT_FALSE(fewer.same_count());
  EXPECT_EQ(fewer.only_in_a, 2u);
  EXPECT_EQ(fewer.only_in_b, 0u);
  EXPECT_THROW(compare_tets(ps, a, {0, 1, 2}), UsageError);
  EXPECT_THROW(compare_tets(ps, a, {0, 1, 2, 6}), UsageError);
}

TEST(TetCompare, TotalVolumeOfUnitTet) {
  PointSet ps;
  ps.push_back(0, 0, 0);
  ps.push_back(1, 0, 0);
  ps.push_back(0, 1, 0);
  ps.push_back(0, 0, 1);
  EXPECT_DOUBLE_EQ(total_volume(ps, {0, 1, 2, 3}), 1.0 / 6);
  EXPECT_DOUBLE_EQ(total_volume(ps, {1, 0, 2, 3}), 1.0 / 6);  // |det|: orientation ignored
  EXPECT_DOUBLE_EQ(total_volume(ps, {}), 0.0);
  EXPECT_GT(orient_sign(ps.p(0), ps.p(1), ps.p(2), ps.p(3)), 0);  // the test helper itself
  EXPECT_LT(orient_sign(ps.p(1), ps.p(0), ps.p(2), ps.p(3)), 0);
}

// ---------------------------------------------------------------------------------------------
// Reference tetrahedralizations

TEST(Reference, OrientationConvention) {
  KDMESH_REQUIRE_TETGEN();
  // (0, e1, e2, e3) is positive in kdmesh's convention; both adapters must return it so.
  PointSet ps;
  ps.push_back(0, 0, 0);
  ps.push_back(1, 0, 0);
  ps.push_back(0, 1, 0);
  ps.push_back(0, 0, 1);
  for (const ReferenceResult& r : {tetgen_delaunay(ps), cgal_delaunay(ps, nullptr)}) {
    ASSERT_EQ(r.tets.size(), 4u);
    EXPECT_EQ(count_non_positive(ps, r.tets), 0u);
    EXPECT_EQ(r.num_vertices, 4u);
    EXPECT_GE(r.seconds, 0.0);
  }
  EXPECT_DOUBLE_EQ(convex_hull_volume(ps), 1.0 / 6);
}

class GeneralPosition : public ::testing::TestWithParam<std::size_t> {};

TEST_P(GeneralPosition, TetgenAndCgalAgree) {
  KDMESH_REQUIRE_TETGEN();
  const std::size_t n = GetParam();
  const PointSet ps = random_points(n, 1000 + n);
  const ReferenceResult tg = tetgen_delaunay(ps);
  const ReferenceResult range = cgal_delaunay(ps, nullptr);
  const Ordering ident = identity_order(n);
  const ReferenceResult one = cgal_delaunay(ps, &ident);
  const Ordering shuffled = random_order(n, 42);
  const ReferenceResult rnd = cgal_delaunay(ps, &shuffled);
  CgalOptions stock;
  stock.plain = true;
  const ReferenceResult plain = cgal_delaunay(ps, nullptr, stock);

  ASSERT_FALSE(tg.tets.empty());
  expect_same_set(ps, tg.tets, range.tets, "tetgen vs cgal range");
  expect_same_set(ps, tg.tets, one.tets, "tetgen vs cgal identity order");
  expect_same_set(ps, tg.tets, rnd.tets, "tetgen vs cgal random order");
  expect_same_set(ps, tg.tets, plain.tets, "tetgen vs stock cgal (no vertex info)");

  const double hull = convex_hull_volume(ps);
  ASSERT_GT(hull, 0.0);
  for (const ReferenceResult* r : {&tg, &range, &one, &rnd, &plain}) {
    EXPECT_EQ(r->num_vertices, n);
    EXPECT_EQ(count_non_positive(ps, r->tets), 0u);
    EXPECT_LT(rel_diff(total_volume(ps, r->tets), hull), 1e-12);
  }
  expect_ball_combinatorics(tg.tets);
}

INSTANTIATE_TEST_SUITE_P(Sizes, GeneralPosition, ::testing::Values(5, 100, 2000));

TEST(Reference, CubeCornersAndCentreAreCospherical) {
  KDMESH_REQUIRE_TETGEN();
  // The centre and the 4 corners of any face are cospherical: each face's diagonal is an
  // arbitrary choice, so only the count (2 tets per face) and the volume are determined.
  PointSet ps;
  for (int i = 0; i < 8; ++i) ps.push_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  ps.push_back(0.5, 0.5, 0.5);
  const ReferenceResult tg = tetgen_delaunay(ps);
  const ReferenceResult cg = cgal_delaunay(ps, nullptr);
  const Ordering ident = identity_order(ps.size());
  const ReferenceResult one = cgal_delaunay(ps, &ident);
  EXPECT_DOUBLE_EQ(convex_hull_volume(ps), 1.0);
  for (const ReferenceResult* r : {&tg, &cg, &one}) {
    EXPECT_EQ(r->tets.size(), 4u * 12);
    EXPECT_EQ(r->num_vertices, 9u);
    EXPECT_EQ(count_non_positive(ps, r->tets), 0u);
    EXPECT_DOUBLE_EQ(total_volume(ps, r->tets), 1.0);
    expect_ball_combinatorics(r->tets);
  }
}

TEST(Reference, LatticeVolumes) {
  KDMESH_REQUIRE_TETGEN();
  // A 4x4x4 lattice: massively cospherical, the tet counts may legitimately differ.
  PointSet ps;
  for (int i = 0; i < 64; ++i) ps.push_back(i % 4, (i / 4) % 4, i / 16);
  const ReferenceResult tg = tetgen_delaunay(ps);
  const ReferenceResult cg = cgal_delaunay(ps, nullptr);
  EXPECT_DOUBLE_EQ(convex_hull_volume(ps), 27.0);
  for (const ReferenceResult* r : {&tg, &cg}) {
    EXPECT_EQ(r->num_vertices, 64u);
    EXPECT_EQ(count_non_positive(ps, r->tets), 0u);
    EXPECT_DOUBLE_EQ(total_volume(ps, r->tets), 27.0);
    expect_ball_combinatorics(r->tets);
  }
}

TEST(Reference, ExactDuplicatesAreMerged) {
  KDMESH_REQUIRE_TETGEN();
  const std::size_t m = 300;
  const PointSet base = random_points(m, 77);
  // Every base point once, some twice or three times, in a shuffled order, so that copies
  // appear both before and after each other.
  Rng rng(78);
  std::vector<std::uint32_t> source;  // base id of each point of `dup`
  for (std::uint32_t i = 0; i < m; ++i) {
    source.push_back(i);
    if (i % 3 == 0) source.push_back(i);
    if (i % 7 == 0) source.push_back(i);
  }
  for (std::size_t i = source.size(); i > 1; --i) std::swap(source[i - 1], source[rng.below(i)]);
  PointSet dup;
  for (const std::uint32_t s : source) dup.push_back(base.p(s)[0], base.p(s)[1], base.p(s)[2]);
  ASSERT_GT(dup.size(), m);

  // Expected: the base tets, with each base id replaced by the first id of its copies in `dup`.
  std::vector<std::uint32_t> first_copy(m, kNoHint);
  for (std::uint32_t i = 0; i < dup.size(); ++i)
    if (first_copy[source[i]] == kNoHint) first_copy[source[i]] = i;
  std::vector<std::uint32_t> expected = tetgen_delaunay(base).tets;
  for (std::uint32_t& v : expected) v = first_copy[v];

  const std::vector<std::uint32_t> canon = canonical_point_ids(dup);
  for (std::uint32_t i = 0; i < dup.size(); ++i) EXPECT_EQ(canon[i], first_copy[source[i]]);

  const ReferenceResult tg = tetgen_delaunay(dup);
  const ReferenceResult range = cgal_delaunay(dup, nullptr);
  const Ordering ident = identity_order(dup.size());
  const ReferenceResult one = cgal_delaunay(dup, &ident);
  const Ordering shuffled = random_order(dup.size(), 5);
  const ReferenceResult rnd = cgal_delaunay(dup, &shuffled);
  CgalOptions stock;
  stock.plain = true;
  const ReferenceResult plain = cgal_delaunay(dup, nullptr, stock);  // ids found by point lookup
  for (const ReferenceResult* r : {&tg, &range, &one, &rnd, &plain}) {
    EXPECT_EQ(r->num_vertices, m);
    expect_same_set(dup, r->tets, expected, "with duplicates vs without");
    EXPECT_EQ(count_non_positive(dup, r->tets), 0u);
    for (const std::uint32_t v : r->tets) EXPECT_EQ(canon[v], v) << "non-canonical id";
  }
}

TEST(Reference, NearDuplicatesStayDistinct) {
  KDMESH_REQUIRE_TETGEN();
  // Points one ulp apart are distinct points; both kernels must keep all of them.
  PointSet ps = random_points(200, 11);
  for (std::uint32_t i = 0; i < 20; ++i) {
    const double* p = ps.p(i);
    ps.push_back(p[0], p[1], std::nextafter(p[2], 2.0));
  }
  const ReferenceResult tg = tetgen_delaunay(ps);
  const ReferenceResult cg = cgal_delaunay(ps, nullptr);
  EXPECT_EQ(tg.num_vertices, ps.size());
  EXPECT_EQ(cg.num_vertices, ps.size());
  EXPECT_EQ(count_non_positive(ps, tg.tets), 0u);
  EXPECT_EQ(count_non_positive(ps, cg.tets), 0u);
  EXPECT_LT(rel_diff(total_volume(ps, tg.tets), convex_hull_volume(ps)), 1e-12);
  EXPECT_DOUBLE_EQ(total_volume(ps, tg.tets), total_volume(ps, cg.tets));
}

TEST(Reference, DegenerateInputsThrowGeometryError) {
  KDMESH_REQUIRE_TETGEN();
  PointSet planar;  // coplanar, not axis-aligned (TetGen would crash on it)
  Rng rng(9);
  for (int i = 0; i < 50; ++i) {
    const double u = double(rng.below(100)), v = double(rng.below(100));
    planar.push_back(u, v, u + v);
  }
  EXPECT_THROW(tetgen_delaunay(planar), GeometryError);
  EXPECT_THROW(cgal_delaunay(planar, nullptr), GeometryError);
  EXPECT_EQ(convex_hull_volume(planar), 0.0);

  PointSet axis_plane;  // z = 0 everywhere (TetGen would abort on an assert)
  for (int i = 0; i < 10; ++i) axis_plane.push_back(i % 3, i / 3, 0);
  EXPECT_THROW(tetgen_delaunay(axis_plane), GeometryError);
  EXPECT_EQ(convex_hull_volume(axis_plane), 0.0);

  PointSet three;
  three.push_back(0, 0, 0);
  three.push_back(1, 0, 0);
  three.push_back(0, 1, 0);
  EXPECT_THROW(tetgen_delaunay(three), GeometryError);
  EXPECT_THROW(cgal_delaunay(three, nullptr), GeometryError);
  EXPECT_EQ(convex_hull_volume(three), 0.0);
  EXPECT_THROW(cgal_delaunay(PointSet{}, nullptr), GeometryError);

  // Non-coplanar but far flatter than TetGen's tolerance: refused by the TetGen adapter
  // (instead of crashing), handled exactly by CGAL.
  PointSet slab = random_points(30, 12);
  for (std::size_t i = 2; i < slab.xyz.size(); i += 3) slab.xyz[i] *= 1e-12;
  EXPECT_THROW(tetgen_delaunay(slab), GeometryError);
  const ReferenceResult cg = cgal_delaunay(slab, nullptr);
  EXPECT_EQ(count_non_positive(slab, cg.tets), 0u);
  EXPECT_GT(convex_hull_volume(slab), 0.0);

  PointSet bad = random_points(10, 13);
  bad.xyz[4] = std::nan("");
  EXPECT_THROW(tetgen_delaunay(bad), GeometryError);
  EXPECT_THROW(cgal_delaunay(bad, nullptr), GeometryError);
}

TEST(Reference, InvalidOrderingIsAUsageError) {
  const PointSet ps = random_points(10, 14);
  Ordering o = identity_order(10);
  o.order[3] = 2;  // not a permutation
  EXPECT_THROW(cgal_delaunay(ps, &o), UsageError);
  o = identity_order(10);
  o.hint[3] = 5;  // not inserted yet
  EXPECT_THROW(cgal_delaunay(ps, &o), UsageError);
  o = identity_order(9);  // wrong size
  EXPECT_THROW(cgal_delaunay(ps, &o), UsageError);
}

}  // namespace
}  // namespace kdmesh
