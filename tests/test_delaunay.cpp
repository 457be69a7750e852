// The Delaunay kernel: exact validity on every distribution and on degenerate inputs,
// agreement with TetGen and CGAL, order independence, determinism, and errors.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/rng.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/reference/delaunay_check.h"
#include "mesher/order/order.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"
#include "tests/support/walk_histogram.h"
#include "tools/bench/lib/distributions.h"
#include "tests/support/tetgen.h"

namespace kdmesh {
namespace {

DelaunayResult run(const PointSet& pts, OrderKind kind = OrderKind::kd_bfs) {
  return delaunay(pts, make_order(pts, {kind, 1, 0.125}));
}

void expect_valid(const PointSet& pts, const DelaunayResult& r, const std::string& what) {
  const ValidityReport rep = check_delaunay(pts, r.tri);
  std::string msg;
  for (const auto& p : rep.problems) msg += "\n  " + p;
  EXPECT_TRUE(rep.ok()) << what << ": " << msg << "\n  volume " << rep.volume << " hull "
                        << rep.hull_volume;
}

/// Finite tets in canonical ids (duplicates mapped to their first copy).
std::vector<std::uint32_t> canonical_tets(const PointSet& pts, const Triangulation& tri) {
  std::vector<std::uint32_t> t = finite_tets(tri);
  const auto canon = canonical_point_ids(pts);
  for (auto& v : t) v = canon[v];
  return t;
}

PointSet lattice(int k, double scale = 1.0, double offset = 0.0) {
  PointSet p;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < k; ++l) p.push_back(offset + scale * i, offset + scale * j, offset + scale * l);
  return p;
}

TEST(Delaunay, ValidOnAllDistributionsAndOrders) {
  for (Distribution d : all_distributions()) {
    const PointSet pts = generate_points(d, 3000, 11);
    std::vector<std::uint32_t> reference;
    for (const std::string& name : order_kind_names()) {
      const DelaunayResult r = run(pts, parse_order_kind(name));
      const std::string what = std::string(distribution_name(d)) + "/" + name;
      expect_valid(pts, r, what);
      EXPECT_EQ(r.stats.inserted, pts.size()) << what;
      EXPECT_GT(r.stats.orient_tests, 0u);
      EXPECT_GE(r.stats.conflicts, r.stats.inserted - 4);  // every insertion deletes >= 1 tet
      // General position: the Delaunay tetrahedralization is unique, so every order agrees.
      const auto tets = canonical_tets(pts, r.tri);
      if (reference.empty()) reference = tets;
      EXPECT_TRUE(compare_tets(pts, reference, tets).same_set()) << what;
    }
  }
}

TEST(Delaunay, MatchesTetGenAndCgalInGeneralPosition) {
  KDMESH_REQUIRE_TETGEN();
  for (Distribution d : {Distribution::cube, Distribution::axes, Distribution::disk}) {
    const PointSet pts = generate_points(d, 5000, 3);
    const auto ours = canonical_tets(pts, run(pts).tri);
    const ReferenceResult tg = tetgen_delaunay(pts);
    const ReferenceResult cg = cgal_delaunay(pts, nullptr);
    EXPECT_TRUE(compare_tets(pts, ours, tg.tets).same_set()) << distribution_name(d);
    EXPECT_TRUE(compare_tets(pts, ours, cg.tets).same_set()) << distribution_name(d);
  }
}

// A 10x10x10 lattice is maximally degenerate (cospherical and coplanar everywhere). The
// perturbation is lexicographic, as in CGAL, so the result is the same for every insertion
// order and is CGAL's tet set; TetGen breaks ties its own way, so only invariants are compared.
TEST(Delaunay, IntegerLatticeIsValidOrderIndependentAndMatchesCgal) {
  KDMESH_REQUIRE_TETGEN();
  const PointSet pts = lattice(10);
  const auto kd = run(pts, OrderKind::kd_bfs);
  expect_valid(pts, kd, "lattice kd-bfs");
  EXPECT_GT(kd.stats.exact_fallbacks, 0u);
  const auto tets = canonical_tets(pts, kd.tri);
  EXPECT_NEAR(total_volume(pts, tets), 729.0, 1e-9);
  for (OrderKind k : {OrderKind::random, OrderKind::hilbert, OrderKind::input, OrderKind::kd_bfs_alt}) {
    const auto r = run(pts, k);
    expect_valid(pts, r, "lattice " + std::string(order_kind_name(k)));
    EXPECT_TRUE(compare_tets(pts, tets, canonical_tets(pts, r.tri)).same_set()) << order_kind_name(k);
  }
  const ReferenceResult cg = cgal_delaunay(pts, nullptr);
  EXPECT_TRUE(compare_tets(pts, tets, cg.tets).same_set());
  const ReferenceResult tg = tetgen_delaunay(pts);
  EXPECT_NEAR(total_volume(pts, tg.tets), 729.0, 1e-9);
}

// Regression: a full lattice is centrally symmetric, and reversing the perturbation's priority
// (lexicographically smallest point first) gives the mirror image of its triangulation, which
// the test above cannot tell from CGAL's. A random subset of a lattice has no such symmetry:
// its ties are broken as CGAL breaks them only with CGAL's priority. (The tie-break's priority
// order came to be chosen point by point, not by a sort.)
TEST(Delaunay, RegressionRandomLatticeSubsetMatchesCgalTieBreaks) {
  const PointSet full = lattice(9);
  Rng rng(7);
  PointSet pts;
  for (std::size_t i = 0; i < full.size(); ++i)
    if (rng.below(5) < 3) pts.push_back(full.p(i)[0], full.p(i)[1], full.p(i)[2]);
  const auto kd = run(pts, OrderKind::kd_bfs);
  expect_valid(pts, kd, "lattice subset");
  EXPECT_GT(kd.stats.exact_fallbacks, 0u);
  const auto tets = canonical_tets(pts, kd.tri);
  EXPECT_TRUE(compare_tets(pts, tets, canonical_tets(pts, run(pts, OrderKind::random).tri)).same_set());
  EXPECT_TRUE(compare_tets(pts, tets, cgal_delaunay(pts, nullptr).tets).same_set());
}

// The fill pairs new faces through an edge table that is reused across insertions (entries of
// older insertions are told apart by a generation tag, cleared every 31 insertions). Here one
// insertion's cavity is far larger than all before it (the centre of a sphere of points:
// every tet inside goes), so the table grows mid-run; then 200 small insertions follow, over
// several generation wraps. A stale entry taken for a live one would link faces wrongly.
TEST(Delaunay, EdgeTableSurvivesAGiantCavityAndGenerationWraps) {
  PointSet pts;
  Rng rng(11);
  for (int i = 0; i < 600; ++i) {  // on the unit sphere (rounded: not exactly cospherical)
    double x, y, z, r2;
    do {
      x = 2 * rng.uniform() - 1;
      y = 2 * rng.uniform() - 1;
      z = 2 * rng.uniform() - 1;
      r2 = x * x + y * y + z * z;
    } while (r2 < 0.01 || r2 > 1);
    const double r = std::sqrt(r2);
    pts.push_back(x / r, y / r, z / r);
  }
  pts.push_back(0, 0, 0);  // rank 600: its cavity is every tet
  for (int i = 0; i < 200; ++i)
    pts.push_back(0.5 * rng.uniform() - 0.25, 0.5 * rng.uniform() - 0.25, 0.5 * rng.uniform() - 0.25);
  const auto r = delaunay(pts, make_order(pts, {OrderKind::input, 1, 0.125}));
  EXPECT_EQ(r.stats.inserted, pts.size());
  EXPECT_GT(r.stats.conflicts, 1000u);  // the centre's cavity alone
  expect_valid(pts, r, "sphere, centre, then small cavities");
  const ReferenceResult cg = cgal_delaunay(pts, nullptr);
  EXPECT_TRUE(compare_tets(pts, canonical_tets(pts, r.tri), cg.tets).same_set());
}

// Inserting points into an existing triangulation (Steiner points) must give the Delaunay
// tetrahedralization of all points: in general position it is unique, so it equals the one
// built in one go. Also on the lattice (degenerate) the tie-breaking is order-independent.
TEST(Delaunay, InsertIntoExistingTriangulationEqualsOneGo) {
  for (const PointSet& pts : {generate_points(Distribution::cube, 4000, 5), lattice(7)}) {
    const std::size_t n = pts.size(), half = n / 2;
    PointSet first;
    first.xyz.assign(pts.xyz.begin(), pts.xyz.begin() + 3 * half);
    DelaunayResult r = run(first);
    std::vector<std::uint32_t> ids, hints;
    for (std::size_t i = half; i < n; ++i) {
      ids.push_back(std::uint32_t(i));
      hints.push_back(i % 3 == 0 ? kNoHint : std::uint32_t(i % half));  // both kinds of start
    }
    delaunay_insert(r.tri, pts, ids, hints, r.stats);
    EXPECT_EQ(r.stats.inserted, n);
    expect_valid(pts, r, "insert into existing");
    EXPECT_TRUE(compare_tets(pts, canonical_tets(pts, run(pts).tri), canonical_tets(pts, r.tri))
                    .same_set());
  }
}

TEST(Delaunay, InsertRejectsBadArguments) {
  const PointSet pts = generate_points(Distribution::cube, 100, 1);
  DelaunayResult r = run(pts);
  EXPECT_THROW(delaunay_insert(r.tri, pts, {100}, {kNoHint}, r.stats), UsageError);
  EXPECT_THROW(delaunay_insert(r.tri, pts, {1, 2}, {kNoHint}, r.stats), UsageError);
  PointSet fewer;
  fewer.xyz.assign(pts.xyz.begin(), pts.xyz.begin() + 30);
  const std::size_t tets = r.tri.num_tets();
  EXPECT_THROW(delaunay_insert(r.tri, fewer, {}, {}, r.stats), UsageError);
  EXPECT_EQ(r.tri.num_tets(), tets);  // left unchanged
}

TEST(Delaunay, DuplicatesAreReportedAndSkipped) {
  PointSet pts = generate_points(Distribution::cube, 500, 5);
  const std::size_t n = pts.size();
  for (std::uint32_t i : {7u, 100u, 250u, 7u}) pts.push_back(pts.p(i)[0], pts.p(i)[1], pts.p(i)[2]);
  const auto r = run(pts);
  expect_valid(pts, r, "duplicates");
  EXPECT_EQ(r.stats.inserted, n);
  ASSERT_EQ(r.stats.duplicates.size(), 4u);
  // Each reported pair really has identical coordinates.
  for (std::size_t i = 0; i < r.stats.duplicates.size(); ++i) {
    const double *a = pts.p(r.stats.duplicates[i]), *b = pts.p(r.stats.duplicate_of[i]);
    EXPECT_TRUE(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
    EXPECT_NE(r.stats.duplicates[i], r.stats.duplicate_of[i]);
  }
  // Same tets as without the repeats.
  PointSet base;
  base.xyz.assign(pts.xyz.begin(), pts.xyz.begin() + 3 * n);
  EXPECT_TRUE(compare_tets(pts, canonical_tets(pts, r.tri), canonical_tets(base, run(base).tri)).same_set());
}

// Points 1e-15 apart are distinct points, not duplicates: they must all become vertices, and
// the result must still be the unique Delaunay tetrahedralization that TetGen and CGAL find.
TEST(Delaunay, NearDuplicatesAreDistinctVertices) {
  KDMESH_REQUIRE_TETGEN();
  PointSet pts = generate_points(Distribution::cube, 500, 8);
  for (std::uint32_t i = 0; i < 50; ++i) pts.push_back(pts.p(i)[0] + 1e-15, pts.p(i)[1], pts.p(i)[2]);
  const auto r = run(pts);
  expect_valid(pts, r, "near-duplicates");
  EXPECT_EQ(r.stats.inserted, pts.size());
  EXPECT_TRUE(r.stats.duplicates.empty());
  const auto tets = canonical_tets(pts, r.tri);
  EXPECT_TRUE(compare_tets(pts, tets, tetgen_delaunay(pts).tets).same_set());
  EXPECT_TRUE(compare_tets(pts, tets, cgal_delaunay(pts, nullptr).tets).same_set());
}

TEST(Delaunay, TinyInputs) {
  PointSet four;
  for (const auto& q : {std::array<double, 3>{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}})
    four.push_back(q[0], q[1], q[2]);
  const auto r4 = run(four);
  expect_valid(four, r4, "4 points");
  EXPECT_EQ(finite_tets(r4.tri).size(), 4u);  // one tet
  EXPECT_EQ(r4.tri.num_tets(), 5u);           // plus 4 infinite ones
  PointSet five = four;
  five.push_back(0.2, 0.2, 0.2);  // inside: splits the tet in 4
  const auto r5 = run(five);
  expect_valid(five, r5, "5 points inside");
  EXPECT_EQ(finite_tets(r5.tri).size(), 16u);
  PointSet five_out = four;
  five_out.push_back(1, 1, 1);  // outside, cospherical with the other 4
  expect_valid(five_out, run(five_out), "5 points outside");
}

TEST(Delaunay, DegenerateStarts) {
  // The first points in insertion order are collinear, then coplanar (input order).
  PointSet pts;
  for (int i = 0; i < 20; ++i) pts.push_back(i, 0, 0);          // collinear
  for (int i = 0; i < 20; ++i) pts.push_back(i % 5, i / 5 + 1, 0);  // coplanar (z = 0)
  Rng rng(3);
  for (int i = 0; i < 100; ++i) pts.push_back(rng.uniform(0, 20), rng.uniform(0, 5), rng.uniform(0.5, 3));
  for (OrderKind k : {OrderKind::input, OrderKind::kd_bfs}) {
    const auto r = run(pts, k);
    expect_valid(pts, r, std::string("degenerate start ") + std::string(order_kind_name(k)));
    EXPECT_EQ(r.stats.inserted, pts.size());
  }
}

TEST(Delaunay, ExtremeScales) {
  for (double scale : {1e-200, 1e-6, 1e6, 1e200}) {
    PointSet pts = generate_points(Distribution::cube, 2000, 9);
    for (auto& x : pts.xyz) x = x * scale + 3 * scale;
    expect_valid(pts, run(pts), "scale " + std::to_string(scale));
    const PointSet lat = lattice(5, scale, scale);
    expect_valid(lat, run(lat), "lattice scale " + std::to_string(scale));
  }
}

// Regression: TetGen crashed (SIGSEGV in its cleanup) on points scaled by 1e-200, and the
// volume check overflowed to inf at 1e+200. Scaling by a power of two changes no tet.
TEST(Delaunay, RegressionTetgenAndVolumeAtScale1e200) {
  KDMESH_REQUIRE_TETGEN();
  const PointSet base = generate_points(Distribution::cube, 2000, 3);
  const auto reference = canonical_tets(base, run(base).tri);
  for (int e : {-664, 664}) {  // 2^+-664 ~ 1e+-200
    const PointSet pts = scaled_copy(base, e);
    const auto r = run(pts);
    expect_valid(pts, r, "scale 2^" + std::to_string(e));
    EXPECT_TRUE(compare_tets(base, reference, canonical_tets(pts, r.tri)).same_set());
    EXPECT_TRUE(compare_tets(base, reference, tetgen_delaunay(pts).tets).same_set());
    EXPECT_TRUE(compare_tets(base, reference, cgal_delaunay(pts, nullptr).tets).same_set());
  }
}

// The walk tries a tet's faces in the order of a direction heuristic (locate() in
// mesher/delaunay/delaunay.cpp). On kd-bfs cube points it needs about 8 orientation tests per point,
// where the walk with a random first face needed 11.7 (docs/bench/README.md, measured before
// the change at 100k-1M points, also what CGAL's walk needs with the same hints): the bound
// between the two catches a return to unordered faces.
TEST(Delaunay, OrderedWalkNeedsFewOrientationTests) {
  const PointSet pts = generate_points(Distribution::cube, 20000, 1);
  const DelaunayResult r = run(pts);
  const double per_point = double(r.stats.orient_tests) / double(pts.size());
  EXPECT_LT(per_point, 9.5);
  EXPECT_GT(per_point, 4.0);
}

// DelaunayStats::walks bins each point's walk by its orientation tests. Every point but the
// first four (they form the first tet) is located once, duplicates included. Hints far from
// the points move the walks to the upper bins: here every point starts from the kd root, a
// point near the centre, so most walks cross a good part of the cube.
TEST(Delaunay, WalkHistogramAddsUpAndShowsFarHints) {
  PointSet pts = generate_points(Distribution::cube, 5000, 3);
  for (std::uint32_t i = 0; i < 50; ++i) pts.push_back(pts.p(97 * i)[0], pts.p(97 * i)[1], pts.p(97 * i)[2]);
  const DelaunayResult near = run(pts);
  ASSERT_EQ(near.stats.duplicates.size(), 50u);
  const std::uint64_t located = pts.size() - 4;
  test::expect_walk_histogram_consistent(near.stats, located, located, "kd-bfs hints");

  Ordering far = make_order(pts, {OrderKind::kd_bfs, 1, 0.125});
  for (std::size_t k = 1; k < far.hint.size(); ++k) far.hint[k] = far.order[0];
  const DelaunayResult r = delaunay(pts, far);
  test::expect_walk_histogram_consistent(r.stats, located, located, "root hints");
  EXPECT_EQ(r.tri.data.size(), near.tri.data.size());  // the same number of tets
  std::uint64_t near_long = 0, far_long = 0;  // walks of 32 tests or more
  for (std::size_t b = 6; b < kWalkBins; ++b) {
    near_long += near.stats.walks[b];
    far_long += r.stats.walks[b];
  }
  EXPECT_GT(far_long, 10 * near_long + pts.size() / 10) << far_long << " " << near_long;
}

TEST(Delaunay, Deterministic) {
  const PointSet pts = generate_points(Distribution::spiral, 4000, 2);
  const auto a = run(pts), b = run(pts);
  EXPECT_EQ(a.tri.data, b.tri.data);
  EXPECT_EQ(a.stats.orient_tests, b.stats.orient_tests);
  EXPECT_EQ(a.stats.conflicts, b.stats.conflicts);
}

TEST(Delaunay, ErrorsForInputsWithoutTetrahedralization) {
  EXPECT_THROW(run(PointSet{}), GeometryError);
  PointSet flat;
  Rng rng(1);
  for (int i = 0; i < 100; ++i) flat.push_back(rng.uniform(), rng.uniform(), 2.0);
  try {
    run(flat);
    FAIL() << "coplanar input accepted";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("coplanar"), std::string::npos) << e.what();
  }
  PointSet line;
  for (int i = 0; i < 10; ++i) line.push_back(i, 2 * i, 3 * i);
  EXPECT_THROW(run(line), GeometryError);
  PointSet same;
  for (int i = 0; i < 3; ++i) same.push_back(1, 1, 1);
  EXPECT_THROW(run(same), GeometryError);
  PointSet three;
  three.push_back(0, 0, 0);
  three.push_back(1, 0, 0);
  three.push_back(0, 1, 0);
  EXPECT_THROW(run(three), GeometryError);
}

TEST(Delaunay, RejectsBadOrderings) {
  const PointSet pts = generate_points(Distribution::cube, 10, 1);
  Ordering o = make_order(pts, {OrderKind::input, 1, 0.125});
  o.order[3] = o.order[4];  // not a permutation
  EXPECT_THROW(delaunay(pts, o), UsageError);
  Ordering short_o = make_order(pts, {OrderKind::input, 1, 0.125});
  short_o.order.pop_back();
  EXPECT_THROW(delaunay(pts, short_o), UsageError);
}

// The validity check itself must catch broken triangulations.
TEST(DelaunayCheck, DetectsCorruption) {
  const PointSet pts = generate_points(Distribution::cube, 300, 4);
  const auto r = run(pts);
  {  // swap two vertices of a finite tet: orientation flips
    Triangulation t = r.tri;
    for (std::size_t i = 0; i < t.num_tets(); ++i)
      if (!t.is_infinite(i)) {
        std::swap(t.v(i, 0), t.v(i, 1));
        break;
      }
    EXPECT_FALSE(check_delaunay(pts, t).ok());
  }
  {  // break an adjacency
    Triangulation t = r.tri;
    std::swap(t.adj(0, 0), t.adj(0, 1));
    EXPECT_GT(check_delaunay(pts, t).asymmetric_adjacencies, 0u);
  }
  {  // move a point: the triangulation is no longer Delaunay (or no longer valid)
    PointSet moved = pts;
    moved.xyz[3 * 17] += 0.05;
    EXPECT_FALSE(check_delaunay(moved, r.tri).ok());
  }
}

}  // namespace
}  // namespace kdmesh
