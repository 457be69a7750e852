// The parallel insertion rounds of the Delaunay kernel (DelaunayOptions::threads): the same
// tets as the sequential kernel on every distribution and on a maximally degenerate lattice,
// valid by the exact check, deterministic for a thread count, and duplicates handled.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <string>

#include "core/error.h"
#include "mesher/delaunay/canonical_order.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/reference/delaunay_check.h"
#include "mesher/order/order.h"
#include "mesher/reference/tet_compare.h"
#include "tests/support/walk_histogram.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {
namespace {

// Below ~40k points the kernel ignores the thread count; these sizes are just above.
constexpr std::size_t kN = 45000;

DelaunayResult run(const PointSet& pts, unsigned threads, OrderKind order = OrderKind::kd_bfs) {
  DelaunayOptions o;
  o.threads = threads;
  return delaunay(pts, make_order(pts, {order, 1, 0.125}), o);
}

std::vector<std::uint32_t> canonical_tets(const PointSet& pts, const Triangulation& tri) {
  std::vector<std::uint32_t> t = finite_tets(tri);
  const auto canon = canonical_point_ids(pts);
  for (auto& v : t) v = canon[v];
  return t;
}

void expect_valid(const PointSet& pts, const DelaunayResult& r, const std::string& what) {
  const ValidityReport rep = check_delaunay(pts, r.tri);
  std::string msg;
  for (const auto& p : rep.problems) msg += "\n  " + p;
  EXPECT_TRUE(rep.ok()) << what << ": " << msg;
}

/// Runs `pts` sequentially and on `threads` threads; the parallel run must really have used
/// rounds, be valid, and give the sequential tet set.
void expect_same_as_sequential(const PointSet& pts, unsigned threads, const std::string& what,
                               OrderKind order = OrderKind::kd_bfs) {
  const DelaunayResult seq = run(pts, 1, order);
  const DelaunayResult par = run(pts, threads, order);
  EXPECT_EQ(seq.stats.parallel_rounds, 0u) << what;
  EXPECT_GE(par.stats.parallel_rounds, 1u) << what;
  EXPECT_EQ(par.stats.inserted, seq.stats.inserted) << what;
  EXPECT_EQ(par.stats.duplicates.size(), seq.stats.duplicates.size()) << what;
  expect_valid(pts, par, what);
  EXPECT_TRUE(compare_tets(pts, canonical_tets(pts, seq.tri), canonical_tets(pts, par.tri)).same_set())
      << what;
}

TEST(ParallelDelaunay, SameTetsAsSequentialOnEveryDistribution) {
  for (Distribution d : all_distributions())
    expect_same_as_sequential(generate_points(d, kN, 4), 2, std::string(distribution_name(d)));
}

// The default order, kd-bfs-hilbert (each kd level in Hilbert order), in rounds: its levels
// reach the slabs in a different order than kd-bfs's.
TEST(ParallelDelaunay, DefaultOrderInRoundsGivesTheSameTets) {
  for (Distribution d : {Distribution::axes, Distribution::planes})
    expect_same_as_sequential(generate_points(d, kN, 5), 2,
                              std::string(distribution_name(d)) + ", kd-bfs-hilbert",
                              OrderKind::kd_bfs_hilbert);
}

// Three slabs per round (more workers than this machine's cores is still correct).
TEST(ParallelDelaunay, ThreeWorkersGiveTheSameTets) {
  expect_same_as_sequential(generate_points(Distribution::cube, kN, 9), 3, "cube, 3 threads");
}

// A 36^3 integer lattice: cospherical and coplanar ties everywhere, and points exactly on the
// slab boundaries (the cuts are point coordinates). The symbolic perturbation decides every
// tie the same way whoever inserts the point.
TEST(ParallelDelaunay, LatticeTiesAreBrokenAsSequentially) {
  PointSet pts;
  for (int i = 0; i < 36; ++i)
    for (int j = 0; j < 36; ++j)
      for (int k = 0; k < 36; ++k) pts.push_back(i, j, k);
  expect_same_as_sequential(pts, 2, "lattice 36^3");
}

TEST(ParallelDelaunay, DeterministicForAThreadCount) {
  const PointSet pts = generate_points(Distribution::spiral, kN, 2);
  const DelaunayResult a = run(pts, 2), b = run(pts, 2);
  EXPECT_EQ(a.tri.data, b.tri.data);
  EXPECT_EQ(a.stats.orient_tests, b.stats.orient_tests);
  EXPECT_EQ(a.stats.conflicts, b.stats.conflicts);
  EXPECT_EQ(a.stats.deferrals, b.stats.deferrals);
  EXPECT_GT(a.stats.deferrals, 0u);  // the rounds did meet their slab boundaries
  // Each point but the first four is located at least once; a deferred point may be again
  // (a worker defers some points before walking, from a hint it does not own).
  test::expect_walk_histogram_consistent(a.stats, kN - 4, kN - 4 + a.stats.deferrals,
                                         "spiral, 2 threads");
}

TEST(ParallelDelaunay, DuplicatesAreSkippedInRounds) {
  PointSet pts = generate_points(Distribution::cube, kN, 6);
  for (std::uint32_t i = 0; i < 3000; ++i) {
    const std::uint32_t src = (i * 7919u) % std::uint32_t(kN);
    pts.push_back(pts.p(src)[0], pts.p(src)[1], pts.p(src)[2]);
  }
  const DelaunayResult r = run(pts, 2);
  EXPECT_EQ(r.stats.inserted, kN);
  ASSERT_EQ(r.stats.duplicates.size(), 3000u);
  for (std::size_t i = 0; i < r.stats.duplicates.size(); ++i) {
    const double *a = pts.p(r.stats.duplicates[i]), *b = pts.p(r.stats.duplicate_of[i]);
    EXPECT_TRUE(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
  }
  expect_same_as_sequential(pts, 2, "cube with 3000 repeats");
}

// Workers look a vertex's slab up in a table filled up to the round's last rank. A caller's
// hint may name a point later in the order, whose slab is not filled yet: the point that asks
// waits for a later round, and the tets are still the sequential ones.
TEST(ParallelDelaunay, HintsToPointsLaterInTheOrderAreHonoured) {
  const PointSet pts = generate_points(Distribution::cube, kN, 7);
  Ordering order = make_order(pts, {OrderKind::kd_bfs, 1, 0.125});
  const std::size_t n = order.size();
  for (std::size_t k = 4; k < n; k += 3) order.hint[k] = order.order[n - 1 - k / 2];
  DelaunayOptions o;
  const DelaunayResult seq = delaunay(pts, order, o);
  o.threads = 2;
  const DelaunayResult par = delaunay(pts, order, o);
  EXPECT_GE(par.stats.parallel_rounds, 1u);
  EXPECT_GT(par.stats.deferrals, 0u);
  EXPECT_EQ(par.stats.inserted, seq.stats.inserted);
  expect_valid(pts, par, "hints forward");
  EXPECT_TRUE(compare_tets(pts, canonical_tets(pts, seq.tri), canonical_tets(pts, par.tri)).same_set());
}

TEST(ParallelDelaunay, AbsurdThreadCountIsAUsageError) {
  EXPECT_THROW(run(generate_points(Distribution::cube, 1000, 1), 100000), UsageError);
}

}  // namespace
}  // namespace kdmesh

namespace kdmesh {
namespace {

/// The canonical order's cases: random points, the axes, an integer lattice (ties everywhere)
/// and random points with 3,000 exact repeats.
std::vector<std::pair<std::string, PointSet>> canonical_cases() {
  std::vector<std::pair<std::string, PointSet>> cases;
  cases.emplace_back("cube", generate_points(Distribution::cube, kN, 11));
  cases.emplace_back("axes", generate_points(Distribution::axes, kN, 12));
  PointSet lattice;
  for (int i = 0; i < 36; ++i)
    for (int j = 0; j < 36; ++j)
      for (int k = 0; k < 36; ++k) lattice.push_back(i, j, k);
  cases.emplace_back("lattice 36^3", lattice);
  PointSet repeats = generate_points(Distribution::cube, kN, 13);
  for (std::uint32_t i = 0; i < 3000; ++i) {
    const std::uint32_t src = (i * 7919u) % std::uint32_t(kN);
    repeats.push_back(repeats.p(src)[0], repeats.p(src)[1], repeats.p(src)[2]);
  }
  cases.emplace_back("cube with 3000 repeats", repeats);
  return cases;
}

// The pipeline meshes from canonical records (mesher/delaunay/canonical_order.h), so that its
// tie-breaks by tet id, and so the mesh, do not depend on the thread count. On 1, 2 and 3
// threads, for random points, the axes, an integer lattice (ties everywhere) and points with
// exact repeats (which copy a run keeps depends on who inserts it): the same records, the
// same duplicate lists, still a valid Delaunay triangulation with the same tets; and the
// same again from a triangulation built inserting another order.
TEST(CanonicalOrder, RecordsAreTheSameOnAnyThreadCountAndStillValid) {
  for (const auto& [what, pts] : canonical_cases()) {
    const Ordering order = make_order(pts, {OrderKind::kd_bfs_hilbert, 1, 0.125});
    DelaunayResult first;
    for (const unsigned threads : {1u, 2u, 3u}) {
      DelaunayOptions o;
      o.threads = threads;
      DelaunayResult r = delaunay(pts, order, o);
      const std::vector<std::uint32_t> before = canonical_tets(pts, r.tri);
      canonicalize_triangulation(r.tri, order, r.stats, threads);
      const std::string run = what + ", " + std::to_string(threads) + " threads";
      EXPECT_TRUE(compare_tets(pts, before, canonical_tets(pts, r.tri)).same_set()) << run;
      if (threads == 1) {  // the other runs must give these very records: checked once
        expect_valid(pts, r, run);
        first = std::move(r);
        continue;
      }
      EXPECT_GE(r.stats.parallel_rounds, 1u) << run;
      EXPECT_TRUE(r.tri.data == first.tri.data) << run;
      EXPECT_EQ(r.stats.duplicates, first.stats.duplicates) << run;
      EXPECT_EQ(r.stats.duplicate_of, first.stats.duplicate_of) << run;
    }
    // The form depends on the tets and the order given only: built inserting another order
    // (BRIO, randomized: it keeps other copies of the repeats), then put in the form of this one.
    DelaunayResult other = delaunay(pts, make_order(pts, {OrderKind::brio, 3, 0.125}));
    canonicalize_triangulation(other.tri, order, other.stats);
    EXPECT_TRUE(other.tri.data == first.tri.data) << what << ", built in brio order";
    EXPECT_EQ(other.stats.duplicates, first.stats.duplicates) << what << ", built in brio order";
    EXPECT_EQ(other.stats.duplicate_of, first.stats.duplicate_of) << what << ", built in brio order";
  }
}

// The canonical form as canonical_order.h states it, checked record by record rather than
// against an earlier run: each tet's least-ranked vertex first and the least of the other
// three second, by an even permutation (the finite tets stay positive); the tets in order of
// their last inserted vertex's rank, then of the other three's, largest first; face
// references that name each other across the same three vertices; no tet naming a repeat the
// stats list. On canonical_cases(), built on two threads.
TEST(CanonicalOrder, RecordsFollowTheDocumentedForm) {
  for (const auto& [what, pts] : canonical_cases()) {
    const Ordering order = make_order(pts, {OrderKind::kd_bfs_hilbert, 1, 0.125});
    DelaunayOptions o;
    o.threads = 2;
    DelaunayResult r = delaunay(pts, order, o);
    const std::vector<std::uint32_t> before = canonical_tets(pts, r.tri);
    canonicalize_triangulation(r.tri, order, r.stats, 2);
    EXPECT_TRUE(compare_tets(pts, before, canonical_tets(pts, r.tri)).same_set()) << what;
    std::vector<std::uint32_t> rank(pts.size());
    for (std::size_t k = 0; k < order.size(); ++k) rank[order.order[k]] = std::uint32_t(k);
    const std::uint32_t infinite_rank = std::uint32_t(pts.size());  // (a binding: not captured)
    auto rank_of = [&](std::uint32_t v) { return v == kInfiniteVertex ? infinite_rank : rank[v]; };
    std::vector<std::uint8_t> repeat(pts.size(), 0);
    for (const std::uint32_t d : r.stats.duplicates) repeat[d] = 1;
    std::array<std::uint32_t, 4> previous{};
    const std::size_t nt = r.tri.num_tets();
    ASSERT_GT(nt, 0u);
    for (std::size_t t = 0; t < nt; ++t) {
      std::array<std::uint32_t, 4> rk;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t v = r.tri.v(t, i);
        ASSERT_TRUE(v == kInfiniteVertex || !repeat[v]) << what << ": tet " << t << " names a repeat";
        rk[std::size_t(i)] = rank_of(v);
      }
      ASSERT_LT(rk[0], std::min({rk[1], rk[2], rk[3]})) << what << ": tet " << t;
      ASSERT_LT(rk[1], std::min(rk[2], rk[3])) << what << ": tet " << t;
      if (r.tri.v(t, 0) != kInfiniteVertex && r.tri.v(t, 1) != kInfiniteVertex &&
          r.tri.v(t, 2) != kInfiniteVertex && r.tri.v(t, 3) != kInfiniteVertex) {
        ASSERT_GT(pred::orient3d(pts.p(r.tri.v(t, 0)), pts.p(r.tri.v(t, 1)), pts.p(r.tri.v(t, 2)),
                                 pts.p(r.tri.v(t, 3))), 0) << what << ": tet " << t;
      }
      std::array<std::uint32_t, 4> key = rk;
      std::sort(key.begin(), key.end(), std::greater<>());
      if (t > 0) {  // the last inserted vertex's rank up, then the other three's down
        const std::array<std::uint32_t, 3> rest{key[1], key[2], key[3]};
        const std::array<std::uint32_t, 3> rest_before{previous[1], previous[2], previous[3]};
        const bool follows = key[0] > previous[0] || (key[0] == previous[0] && rest < rest_before);
        ASSERT_TRUE(follows) << what << ": tets " << t - 1 << ", " << t;
      }
      previous = key;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t a = r.tri.adj(t, i), u = a >> 2;
        const int j = int(a & 3);
        ASSERT_LT(u, nt) << what;
        ASSERT_EQ(r.tri.adj(u, j), 4 * std::uint32_t(t) + std::uint32_t(i)) << what << ": tet " << t;
        std::array<std::uint32_t, 3> mine{}, theirs{};
        for (int k = 0, m = 0, w = 0; k < 4; ++k) {
          if (k != i) mine[std::size_t(m++)] = r.tri.v(t, k);
          if (k != j) theirs[std::size_t(w++)] = r.tri.v(u, k);
        }
        std::sort(mine.begin(), mine.end());
        std::sort(theirs.begin(), theirs.end());
        ASSERT_EQ(mine, theirs) << what << ": tet " << t << " face " << i;
      }
    }
  }
}

}  // namespace
}  // namespace kdmesh
