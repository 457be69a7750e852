// kdmesh — tests of the mesh quality-improvement pass (mesher/improve/mesh_improve.h) and of its
// parts: the flat tet structure (improve_tets), the flips (improve_flips), the objective
// (improve_quality) and smoothing (improve_smooth), on hand-built configurations and on small
// meshes made by the pipeline's own stages.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <string>

#include "core/error.h"
#include "core/rng.h"
#include "io/surface_io.h"
#include "mesher/improve/flip_parts.h"
#include "mesher/improve/flip_pass.h"
#include "mesher/improve/improve_boundary.h"
#include "mesher/improve/improve_flips.h"
#include "mesher/improve/improve_insert.h"
#include "mesher/improve/improve_quality.h"
#include "mesher/improve/improve_smooth.h"
#include "mesher/improve/improve_split_boundary.h"
#include "mesher/improve/improve_tets.h"
#include "mesher/improve/sine_cache.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/improve/mesh_improve.h"
#include "mesher/placement/node_placement.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/tet_quality.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_bodies.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"

namespace kdmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Hand-built configurations.

NodeSet interior_nodes(const std::vector<std::array<double, 3>>& pts) {
  NodeSet n;
  for (const auto& p : pts) n.push_back(p.data(), NodeKind::interior, kNoFacet, 1.0f);
  return n;
}

double signed_volume(const NodeSet& n, const std::uint32_t* v) {
  const double *a = n.points.p(v[0]), *b = n.points.p(v[1]), *c = n.points.p(v[2]), *d = n.points.p(v[3]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double x[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double y[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return (u[0] * (x[1] * y[2] - x[2] * y[1]) + u[1] * (x[2] * y[0] - x[0] * y[2]) +
          u[2] * (x[0] * y[1] - x[1] * y[0])) / 6;
}

/// Tets as sorted vertex sets (orientation checked separately).
std::set<std::array<std::uint32_t, 4>> tet_sets(const std::vector<std::uint32_t>& tets) {
  std::set<std::array<std::uint32_t, 4>> s;
  for (std::size_t k = 0; k + 3 < tets.size(); k += 4) {
    std::array<std::uint32_t, 4> a = {tets[k], tets[k + 1], tets[k + 2], tets[k + 3]};
    std::sort(a.begin(), a.end());
    s.insert(a);
  }
  return s;
}

/// A positively oriented copy of (a, b, c, d) (swaps c, d if needed).
std::vector<std::uint32_t> positive(const NodeSet& n, std::uint32_t a, std::uint32_t b,
                                    std::uint32_t c, std::uint32_t d) {
  std::uint32_t v[4] = {a, b, c, d};
  if (pred::orient3d(n.points.p(a), n.points.p(b), n.points.p(c), n.points.p(d)) < 0) std::swap(v[2], v[3]);
  return {v[0], v[1], v[2], v[3]};
}

/// Every live tet exactly positive; every interior face linked both ways with the same vertex set.
void expect_consistent(const ImproveTets& m) {
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    if (!m.alive(t)) continue;
    const std::uint32_t* v = m.v(t);
    EXPECT_GT(pred::orient3d(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])), 0) << "tet " << t;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t r = m.adj(t, i);
      if (r == kImproveNone) continue;
      ASSERT_TRUE(m.alive(r >> 2));
      EXPECT_EQ(m.adj(r >> 2, int(r & 3)), 4 * t + std::uint32_t(i));
      std::set<std::uint32_t> f1, f2;
      for (int j = 0; j < 4; ++j) {
        if (j != i) f1.insert(v[j]);
        if (j != int(r & 3)) f2.insert(m.v(r >> 2)[j]);
      }
      EXPECT_EQ(f1, f2);
    }
  }
}

std::vector<std::uint32_t> live_tets(const ImproveTets& m) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (m.alive(t)) out.insert(out.end(), m.v(t), m.v(t) + 4);
  return out;
}

TEST(ImproveQuality, SineOfTheRegularTetAndOfASliver) {
  // Regular tet: every dihedral angle is acos(1/3) = 70.53 deg, sin = sqrt(8)/3.
  const double a[3] = {1, 1, 1}, b[3] = {1, -1, -1}, c[3] = {-1, 1, -1}, d[3] = {-1, -1, 1};
  const double sgn = pred::orient3d(a, b, c, d) > 0 ? 1 : -1;
  const double* p[4] = {a, b, c, d};
  if (sgn < 0) std::swap(p[2], p[3]);
  EXPECT_NEAR(tet_sine(p), std::sqrt(8.0) / 3, 1e-14);
  EXPECT_NEAR(tet_radius_ratio(p[0], p[1], p[2], p[3]), 1.0, 1e-14);
  // Inverted: -1.
  EXPECT_EQ(tet_sine(p[0], p[1], p[3], p[2]), -1);
  // The corner tet (0, e1, e2, e3): three 90 deg angles at the origin's edges, and the three
  // angles at the slanted face are acos(1/sqrt 3) = 54.7 deg: min sine = sqrt(2/3).
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  EXPECT_NEAR(tet_sine(o, x, y, z), std::sqrt(2.0 / 3), 1e-14);
  // Agreement with tet_quality on a sliver: min(sin min_dih, sin max_dih).
  const double s1[3] = {0, 0, 0}, s2[3] = {1, 0, 0}, s3[3] = {0.5, 1, 0.01}, s4[3] = {0.5, 0.2, 1};
  const TetQuality q = tet_quality(s1, s2, s3, s4);
  const double expect = std::min(std::sin(q.min_dihedral * kPi / 180),
                                 (q.max_dihedral > 90 ? kObtuseWeight : 1.0) * std::sin(q.max_dihedral * kPi / 180));
  // The smallest weighted sine is at one of the extreme angles (sin is concave on [0, 180]).
  EXPECT_NEAR(tet_sine(s1, s2, s3, s4), expect, 1e-9);
}

// The objective weights obtuse angles so that it reaches sin 12 deg exactly where both targets
// hold (min dihedral >= 12, max <= 165): t13_data.stl and retinal.ply kept 166-168 deg angles
// the equal-weight sine ranked above a 12.5 deg angle. Checked against tet_quality's angles on
// random tets, away from the two thresholds' rounding.
TEST(ImproveQuality, ObjectiveReachesSin12ExactlyWhereBothTargetsHold) {
  EXPECT_NEAR(kObtuseWeight * std::sin(165 * kPi / 180), std::sin(12 * kPi / 180), 1e-15);
  Rng rng(7);
  const double s12 = std::sin(12 * kPi / 180);
  int meet = 0, miss_min = 0, miss_max = 0;
  for (int i = 0; i < 20000; ++i) {
    double p[4][3];
    for (auto& q : p)
      for (double& x : q) x = rng.uniform(-1, 1);
    if (pred::orient3d(p[0], p[1], p[2], p[3]) < 0) std::swap(p[2], p[3]);
    const TetQuality q = tet_quality(p[0], p[1], p[2], p[3]);
    const double s = tet_sine(p[0], p[1], p[2], p[3]);
    if (std::abs(q.min_dihedral - 12) < 1e-6 || std::abs(q.max_dihedral - 165) < 1e-6) continue;
    const bool targets = q.min_dihedral >= 12 && q.max_dihedral <= 165;
    EXPECT_EQ(s >= s12, targets) << i << ": " << q.min_dihedral << " .. " << q.max_dihedral;
    meet += targets;
    miss_min += q.min_dihedral < 12 && q.max_dihedral <= 165;
    miss_max += q.min_dihedral >= 12 && q.max_dihedral > 165;
  }
  // Random tets cover all three cases.
  EXPECT_GT(meet, 100);
  EXPECT_GT(miss_min, 100);
  EXPECT_GT(miss_max, 10);  // 23 of 20,000 when written
}

TEST(ImproveQuality, SineAndRatioTogetherAreBitIdenticalToEachAlone) {
  Rng rng(3);
  int positive = 0;
  for (int i = 0; i < 2000; ++i) {
    double p[4][3];
    for (auto& q : p)
      for (double& x : q) x = rng.uniform(-1, 1) * (i % 3 ? 1 : 1e-3);  // also tiny tets
    const SineRatio both = tet_sine_ratio(p[0], p[1], p[2], p[3]);
    const double sine = tet_sine(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(both.sine, sine) << i;  // exact equality: the same operations
    if (sine > 0) {
      ASSERT_EQ(both.ratio, tet_radius_ratio(p[0], p[1], p[2], p[3])) << i;
      ++positive;
    } else {
      EXPECT_LE(tet_radius_ratio(p[0], p[1], p[2], p[3]), 0);
      EXPECT_EQ(both.ratio, 0);
    }
  }
  EXPECT_GT(positive, 500);  // about half are positively oriented
}

// 2-3 flip: the face (a, b, c) in the plane z = 0 between apexes p (z = 1) and q (z = -1)
// whose segment pq crosses the face's interior. Face removal gives the three tets
// {p, q, a, b}, {p, q, b, c}, {p, q, c, a} with the same total volume.
TEST(ImproveFlips, FaceRemovalIsTheTwoThreeFlip) {
  NodeSet n = interior_nodes({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 1}, {1, 1, -1}});
  const std::uint32_t a = 0, b = 1, c = 2, p = 3, q = 4;
  std::vector<std::uint32_t> tets = positive(n, a, b, c, p);
  const auto t2 = positive(n, a, b, c, q);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  expect_consistent(m);
  const int i = index_in(m.v(0), p);  // the face of tet 0 opposite p is (a, b, c)
  FlipCandidate cand;
  ASSERT_TRUE(face_removal(m, 0, i, cand));
  EXPECT_EQ(cand.old.size(), 2u);
  ASSERT_EQ(cand.fresh.size(), 12u);
  EXPECT_EQ(tet_sets(cand.fresh), (std::set<std::array<std::uint32_t, 4>>{
                                      {a, b, p, q}, {b, c, p, q}, {a, c, p, q}}));
  double before = 0, after = 0;
  for (std::size_t k = 0; k < tets.size(); k += 4) before += signed_volume(n, &tets[k]);
  for (std::size_t k = 0; k < cand.fresh.size(); k += 4) {
    EXPECT_GT(signed_volume(n, &cand.fresh[k]), 0);
    after += signed_volume(n, &cand.fresh[k]);
  }
  EXPECT_NEAR(after, before, 1e-14);
  ASSERT_TRUE(m.replace(cand.old, cand.fresh));
  EXPECT_EQ(m.live(), 3u);
  expect_consistent(m);
  // Every new tet shares two faces with the others (around pq) and has two boundary faces.
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    if (!m.alive(t)) continue;
    int inner = 0;
    for (int k = 0; k < 4; ++k) inner += m.adj(t, k) != kImproveNone;
    EXPECT_EQ(inner, 2);
  }
}

// The flip stage takes dead slots for its new tets a pool at a time (take_slots). The slot
// arrays were sized exactly, so the first pool doubled and copied all of them: on the paper
// gear box (24.5M slots, 102k added in all) ~1 GB copied into fresh pages, both copies
// resident at once, and the sine cache's values then did the same. Both now keep room for a
// 32nd more slots: pools within it leave the arrays where they are, and the records stay.
TEST(ImproveTets, RegressionTakingSlotsForTheFlipPoolsDoesNotMoveTheSlotArrays) {
  // 4,096 separate tets, each with its own four nodes (the test needs slots, not a mesh): room
  // for 4,096 / 32 = 128 more slots.
  std::vector<std::array<double, 3>> pts;
  std::vector<std::uint32_t> tets;
  std::vector<std::uint32_t> region;
  for (std::uint32_t c = 0; c < 4096; ++c) {
    const double x = 10.0 * c;
    const std::uint32_t b = std::uint32_t(pts.size());
    pts.push_back({x, 0, 0});
    pts.push_back({x + 1, 0, 0});
    pts.push_back({x, 1, 0});
    pts.push_back({x, 0, 1});
    tets.insert(tets.end(), {b, b + 1, b + 2, b + 3});
    region.push_back(0);
  }
  NodeSet n = interior_nodes(pts);
  for (std::size_t k = 0; k < tets.size(); k += 4) ASSERT_GT(signed_volume(n, &tets[k]), 0);
  ImproveTets m(n, tets, region);
  SineCache cache(m, 1);  // its values keep the same room
  const double* values = cache.q().data();
  const std::uint32_t* before = m.v(4095);
  const std::array<std::uint32_t, 4> last = {before[0], before[1], before[2], before[3]};
  std::vector<std::uint32_t> pool = m.take_slots(100);
  std::vector<std::uint32_t> more = m.take_slots(28);  // 4,224 slots: the room is full
  EXPECT_EQ(m.capacity(), 4224u);
  cache.grow();
  EXPECT_EQ(cache.q().size(), 4224u);
  EXPECT_EQ(cache.q().data(), values);
  EXPECT_EQ(cache.q()[4223], std::numeric_limits<double>::infinity());
  EXPECT_EQ(m.v(4095), before);
  EXPECT_EQ((std::array<std::uint32_t, 4>{m.v(4095)[0], m.v(4095)[1], m.v(4095)[2], m.v(4095)[3]}), last);
  for (std::uint32_t t : pool) EXPECT_FALSE(m.alive(t));
  m.give_slots(pool);
  m.give_slots(more);
  EXPECT_EQ(m.live(), 4096u);
  expect_consistent(m);
}

// The quality pass's splits add nodes (add_interior_node). The node set's arrays were full, so
// the first one doubled and copied all of them (the paper gear box: 4.2M nodes, ~150 MB).
// ImproveTets now keeps room for a 64th more nodes (and 64): adding within it moves nothing.
TEST(ImproveTets, RegressionAddingNodesDoesNotMoveTheNodeArrays) {
  std::vector<std::array<double, 3>> pts;
  std::vector<std::uint32_t> tets, region;
  for (std::uint32_t c = 0; c < 1024; ++c) {  // 1,024 separate tets, 4,096 nodes
    const double x = 10.0 * c;
    const std::uint32_t b = std::uint32_t(pts.size());
    pts.insert(pts.end(), {{x, 0, 0}, {x + 1, 0, 0}, {x, 1, 0}, {x, 0, 1}});
    tets.insert(tets.end(), {b, b + 1, b + 2, b + 3});
    region.push_back(0);
  }
  NodeSet n = interior_nodes(pts);
  n.points.xyz.shrink_to_fit();  // full, as a node set built to size is
  ImproveTets m(n, tets, region);
  const double* xyz = n.points.xyz.data();
  const float* size = n.size.data();
  for (int k = 0; k < 128; ++k) {  // 4,096 + 128 nodes: the room (4,096 / 64 + 64) is full
    const double p[3] = {5.0 + k, 5, 5};
    EXPECT_EQ(m.add_interior_node(p, 1.0f), 4096u + std::uint32_t(k));
  }
  EXPECT_EQ(n.size_count(), 4224u);
  EXPECT_EQ(n.points.xyz.data(), xyz);
  EXPECT_EQ(n.size.data(), size);
  EXPECT_EQ(n.points.p(4223)[0], 132.0);
  expect_consistent(m);
}

// A tet with three boundary faces around its apex p (its only tet): removing it would leave p
// without a tet, so remove() refuses unless p may be orphaned; then the other tet stays, with
// the shared face now on the boundary, and write_back drops p (a flat cap of this shape was
// the worst tet, 1.3 deg, of a sphere after the cap pass).
TEST(ImproveTets, RemovingATetMayOrphanOnlyTheVertexAllowed) {
  NodeSet n = interior_nodes({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 0.05}, {1, 1, -1}});
  const std::uint32_t a = 0, b = 1, c = 2, p = 3, q = 4;
  std::vector<std::uint32_t> tets = positive(n, a, b, c, p);
  const auto t2 = positive(n, a, b, c, q);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  EXPECT_FALSE(m.remove(0));
  EXPECT_FALSE(m.remove(0, a));  // a has the other tet; p is still left without one
  EXPECT_EQ(m.live(), 2u);
  ASSERT_TRUE(m.remove(0, p));
  EXPECT_EQ(m.live(), 1u);
  EXPECT_FALSE(m.alive(0));
  for (int k = 0; k < 4; ++k) EXPECT_EQ(m.adj(1, k), kImproveNone);
  std::vector<std::uint32_t> star;
  m.star(p, star);
  EXPECT_TRUE(star.empty());
  m.star(a, star);
  EXPECT_EQ(star, std::vector<std::uint32_t>{1});
}

// A boundary edge's open ring, and splitting the edge through a new node (the boundary-edge
// split of the quality pass, mesher/improve/improve_split.h): two tets (a, b, c, p) and (a, b, p, d)
// around the edge ab, whose boundary faces at ab are (a, b, c) and (a, b, d). A replace that
// drops those two faces and creates four new ones is refused unless the boundary may change.
TEST(ImproveTets, OpenEdgeRingAndABoundaryChangingReplace) {
  NodeSet n = interior_nodes({{0, 0, 0}, {2, 0, 0}, {1, -1, 0}, {1, 1, 0}, {1, 0, 1}, {1, 0, 0}});
  const std::uint32_t a = 0, b = 1, c = 2, d = 3, p = 4, x = 5;
  std::vector<std::uint32_t> tets = positive(n, a, b, c, p);
  const auto t2 = positive(n, a, b, p, d);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  std::vector<std::uint32_t> ring, rtets;
  ASSERT_TRUE(m.open_edge_ring(0, a, b, 10, ring, rtets));
  ASSERT_EQ(ring.size(), 3u);
  ASSERT_EQ(rtets.size(), 2u);
  EXPECT_EQ(ring[1], p);  // the ends are c and d, in the order the orientation gives
  EXPECT_EQ((std::set<std::uint32_t>{ring[0], ring[2]}), (std::set<std::uint32_t>{c, d}));
  for (std::size_t k = 0; k < 2; ++k) {  // tet k is (a, b, r_k, r_k+1), positively oriented
    EXPECT_EQ(tet_sets({a, b, ring[k], ring[k + 1]}), tet_sets({m.v(rtets[k]), m.v(rtets[k]) + 4}));
    EXPECT_GT(pred::orient3d(m.p(a), m.p(b), m.p(ring[k]), m.p(ring[k + 1])), 0);
  }
  // From the other tet: the same ring.
  std::vector<std::uint32_t> ring2, rtets2;
  ASSERT_TRUE(m.open_edge_ring(1, a, b, 10, ring2, rtets2));
  EXPECT_EQ(ring2, ring);
  EXPECT_FALSE(m.open_edge_ring(0, a, b, 1, ring2, rtets2));  // longer than max_ring
  // Split ab at x (its midpoint).
  std::vector<std::uint32_t> fresh;
  for (std::size_t k = 0; k < 2; ++k)
    fresh.insert(fresh.end(), {a, x, ring[k], ring[k + 1], x, b, ring[k], ring[k + 1]});
  EXPECT_FALSE(m.replace(rtets, fresh));
  EXPECT_EQ(m.live(), 2u);
  std::vector<std::uint32_t> created;
  ASSERT_TRUE(m.replace(rtets, fresh, &created, true));
  EXPECT_EQ(m.live(), 4u);
  expect_consistent(m);
  // The four tets' 16 face sides: 4 inner faces (x c p, x p d, a x p, x b p), each seen from
  // both sides, and 8 boundary faces (the 6 kept, and a x c, x b c, a x d, x b d for the two
  // that went away).
  std::size_t boundary = 0, inner = 0;
  for (std::uint32_t t : created)
    for (int i = 0; i < 4; ++i) (m.adj(t, i) == kImproveNone ? boundary : inner) += 1;
  EXPECT_EQ(inner, 2u * 4);
  EXPECT_EQ(boundary, 8u);
  // A face of the cavity that is not a boundary face may never go unmatched: removing one
  // tet this way (its faces with the others would vanish) is refused.
  EXPECT_FALSE(m.replace({created[0]}, {}, nullptr, true));
  EXPECT_EQ(m.live(), 4u);
}

/// Appends a node of kind k at (x, y, z), size 0.5, to n; returns its id.
std::uint32_t add_node(NodeSet& n, double x, double y, double z, NodeKind k) {
  const double p[3] = {x, y, z};
  n.push_back(p, k, kNoFacet, 0.5f);
  return std::uint32_t(n.size_count() - 1);
}

/// The cube [0,1] x [0,1] x [-1,0] (z = 0 the top), prepared, with its query, a constant size
/// `h` and its 12 feature edges: what the boundary operations of the pass consult.
struct CubeContext {
  PreparedSurface surface;
  std::unique_ptr<SurfaceQuery> query;
  SizingField sizing;
  FeatureEdges features;
  BoundaryContext ctx;
  explicit CubeContext(double h) {
    SurfaceMesh cube;
    for (int i = 0; i < 8; ++i) cube.points.push_back(i & 1, (i >> 1) & 1, -((i >> 2) & 1));
    // Outward faces of [0,1] x [0,1] x [-1,0].
    for (std::uint32_t t : {0u, 3u, 1u, 0u, 2u, 3u, 4u, 5u, 7u, 4u, 7u, 6u, 0u, 1u, 5u, 0u, 5u, 4u,
                            2u, 6u, 7u, 2u, 7u, 3u, 0u, 4u, 6u, 0u, 6u, 2u, 1u, 3u, 7u, 1u, 7u, 5u})
      cube.tris.push_back(t);
    surface = prepare_surface(std::move(cube), "cube");
    query = std::make_unique<SurfaceQuery>(surface.mesh);
    SizingOptions so;
    so.max_size = h;
    sizing = build_sizing_field(surface.mesh, so);
    features = detect_sharp_edges(surface.mesh, 30);
    ctx.surface = &surface;
    ctx.query = query.get();
    ctx.sizing = &sizing;
    ctx.features = &features;
  }
};

// An edge between two feature nodes is kept as a feature edge unless it is a chord of the
// feature curve: helmet.ply at diag/40 had a boundary face from one rim node to another 17
// rim nodes on (over a 11 deg bend of the rim), under a stack of 0.01 deg tets, and no cap or
// flip could take that edge. On the unit cube's edge y = z = 0 (a feature edge), a and b are
// corners; c, a node of that curve 0.01 off it, lies between them: ab is a chord, ac is not.
TEST(ImproveBoundary, RegressionHelmetChordOfAFeatureCurveIsNoFeatureEdge) {
  const CubeContext cc(0.5);
  ASSERT_GT(cc.surface.volume, 0);
  const BoundaryContext& ctx = cc.ctx;
  NodeSet n;
  auto add = [&](double x, double y, double z, NodeKind k) { return add_node(n, x, y, z, k); };
  const std::uint32_t a = add(0, 0, 0, NodeKind::corner), b = add(1, 0, 0, NodeKind::corner),
                      c = add(0.5, 0.01, 0, NodeKind::edge), d = add(0.5, 0.5, 0, NodeKind::surface),
                      e = add(0.5, 0.3, -0.5, NodeKind::interior);
  {
    // Only the tet (a, b, d, e): nothing lies between a and b.
    NodeSet copy = n;
    ImproveTets m(copy, positive(copy, a, b, d, e), {0});
    EXPECT_TRUE(keeps_feature(m, a, b, ctx));
  }
  std::vector<std::uint32_t> tets = positive(n, a, b, d, e);
  const auto t2 = positive(n, a, c, b, e);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  EXPECT_TRUE(along_feature(m.p(a), m.p(b), ctx));  // geometrically, ab runs along the edge
  EXPECT_FALSE(keeps_feature(m, a, b, ctx));        // but it skips c
  EXPECT_TRUE(keeps_feature(m, a, c, ctx));
  EXPECT_TRUE(keeps_feature(m, c, b, ctx));
  EXPECT_FALSE(keeps_feature(m, d, e, ctx));
}

// A long boundary edge is a chord the Delaunay tets drew over nearly coplanar surface nodes
// (handle.ply at diag/20: boundary faces 10-23 h long, slivers on them). On the cube's top,
// the diagonal ab of the quadrilateral a c b d (c and d 0.1 from its midpoint: both triangles
// have an angle of 160 deg) over an interior node e under c (a 160 deg dihedral at ce): split
// at the surface point closest to its midpoint, the four tets are better, the volume and the covered part of the top are the same.
// Refused where it would not help: an edge shorter than the size, or a ring that gets no
// better. A feature edge is split on its curve.
TEST(ImproveSplitBoundary, LongBoundaryEdgeGetsASurfaceNodeOnTheSurface) {
  const CubeContext cc(0.5);
  NodeSet n;
  auto add = [&](double x, double y, double z, NodeKind k) { return add_node(n, x, y, z, k); };
  const std::uint32_t a = add(0.1, 0.1, 0, NodeKind::surface), b = add(0.9, 0.9, 0, NodeKind::surface),
                      c = add(0.57, 0.43, 0, NodeKind::surface), d = add(0.43, 0.57, 0, NodeKind::surface),
                      e = add(0.57, 0.43, -0.3, NodeKind::interior);
  std::vector<std::uint32_t> tets = positive(n, a, b, c, e);
  const auto t2 = positive(n, a, b, d, e);
  tets.insert(tets.end(), t2.begin(), t2.end());
  const double worst_before = std::min(tet_sine(n.points.p(tets[0]), n.points.p(tets[1]), n.points.p(tets[2]), n.points.p(tets[3])),
                                       tet_sine(n.points.p(tets[4]), n.points.p(tets[5]), n.points.p(tets[6]), n.points.p(tets[7])));
  {
    // The same edge with a size longer than it: refused, nothing changed.
    const CubeContext coarse(2.0);
    NodeSet copy = n;
    ImproveTets m(copy, tets, {0, 0});
    EXPECT_FALSE(split_boundary_edge(m, 0, a, b, 10, coarse.ctx));
    EXPECT_EQ(m.live(), 2u);
    EXPECT_EQ(copy.size_count(), 5u);
  }
  ImproveTets m(n, tets, {0, 0});
  EXPECT_FALSE(split_boundary_edge(m, 0, a, e, 10, cc.ctx));  // not a boundary edge
  std::vector<std::uint32_t> created;
  ASSERT_TRUE(split_boundary_edge(m, 0, a, b, 10, cc.ctx, &created));
  expect_consistent(m);
  ASSERT_EQ(m.live(), 4u);
  ASSERT_EQ(n.size_count(), 6u);
  const std::uint32_t x = 5;
  EXPECT_EQ(n.kind[x], NodeKind::surface);
  ASSERT_NE(n.facet[x], kNoFacet);
  EXPECT_NEAR(n.points.p(x)[0], 0.5, 1e-15);
  EXPECT_NEAR(n.points.p(x)[1], 0.5, 1e-15);
  EXPECT_EQ(n.points.p(x)[2], 0.0);  // on the top face
  double volume = 0, worst_after = 1;
  std::size_t on_top = 0;
  for (std::uint32_t t : created) {
    const std::uint32_t* v = m.v(t);
    volume += signed_volume(n, v);
    worst_after = std::min(worst_after, tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])));
    for (int f = 0; f < 4; ++f) on_top += m.adj(t, f) == kImproveNone && v[f] == e;
  }
  EXPECT_NEAR(volume, signed_volume(n, &tets[0]) + signed_volume(n, &tets[4]), 1e-15);
  EXPECT_EQ(on_top, 4u);  // a c x, x c b, a x d, x b d: the faces opposite e, all on the top
  EXPECT_GT(worst_after, worst_before);
  // Splitting a half again would make its ring worse: refused.
  for (std::uint32_t t : created) EXPECT_FALSE(split_boundary_edge(m, t, a, x, 10, cc.ctx));
  // A feature edge (the cube's edge y = z = 0, between two corners) is split on the curve:
  // the new node is an edge node, on the cube's edge.
  NodeSet f;
  auto addf = [&](double px, double py, double pz, NodeKind k) { return add_node(f, px, py, pz, k); };
  const std::uint32_t fa = addf(0, 0, 0, NodeKind::corner), fb = addf(1, 0, 0, NodeKind::corner),
                      fc = addf(0.5, 0.1, 0, NodeKind::surface), fd = addf(0.5, 0, -0.1, NodeKind::surface),
                      fe = addf(0.5, 0.3, -0.3, NodeKind::interior);
  std::vector<std::uint32_t> ft = positive(f, fa, fb, fc, fe);
  const auto ft2 = positive(f, fa, fb, fe, fd);
  ft.insert(ft.end(), ft2.begin(), ft2.end());
  ImproveTets fm(f, ft, {0, 0});
  ASSERT_TRUE(keeps_feature(fm, fa, fb, cc.ctx));
  ASSERT_TRUE(split_boundary_edge(fm, 0, fa, fb, 10, cc.ctx));
  expect_consistent(fm);
  EXPECT_EQ(fm.live(), 4u);
  const std::uint32_t fx = 5;
  EXPECT_EQ(f.kind[fx], NodeKind::edge);
  EXPECT_EQ(f.points.p(fx)[1], 0.0);
  EXPECT_EQ(f.points.p(fx)[2], 0.0);
  EXPECT_NEAR(f.points.p(fx)[0], 0.5, 1e-15);
  EXPECT_TRUE(keeps_feature(fm, fa, fx, cc.ctx));  // the curve keeps both halves
  EXPECT_TRUE(keeps_feature(fm, fx, fb, cc.ctx));
}

// When pq misses the face (q moved beyond edge bc), a new tet would be inverted: no flip.
TEST(ImproveFlips, FaceRemovalRefusesWhenTheNewEdgeMissesTheFace) {
  NodeSet n = interior_nodes({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 1}, {4, 4, -1}});
  std::vector<std::uint32_t> tets = positive(n, 0, 1, 2, 3);
  const auto t2 = positive(n, 0, 1, 2, 4);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  FlipCandidate cand;
  EXPECT_FALSE(face_removal(m, 0, index_in(m.v(0), 3), cand));
  EXPECT_FALSE(face_removal(m, 0, index_in(m.v(0), 0), cand));  // a boundary face
}

// The flip stage passes the better of the two tets' sine and its best candidate so far as a
// floor: a face removal whose worst new tet is not above it is refused, the rest unevaluated.
TEST(ImproveFlips, FaceRemovalRefusesWhatCannotBeatItsFloor) {
  NodeSet n = interior_nodes({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 1}, {1, 1, -1}});
  std::vector<std::uint32_t> tets = positive(n, 0, 1, 2, 3);
  const auto t2 = positive(n, 0, 1, 2, 4);
  tets.insert(tets.end(), t2.begin(), t2.end());
  ImproveTets m(n, tets, {0, 0});
  const int i = index_in(m.v(0), 3);
  FlipCandidate cand;
  ASSERT_TRUE(face_removal(m, 0, i, cand));
  const double q = cand.q_new;
  ASSERT_GT(q, 0);
  FlipCandidate at, below;
  EXPECT_FALSE(face_removal(m, 0, i, at, nullptr, true, q));
  ASSERT_TRUE(face_removal(m, 0, i, below, nullptr, true, std::nextafter(q, 0.0)));
  EXPECT_EQ(below.q_new, q);
  EXPECT_EQ(below.fresh, cand.fresh);
}

// 3-2 flip: the three tets around edge pq (the 2-3 flip's result) go back to the two tets
// {a, b, c, p}, {a, b, c, q} by edge removal of pq (ring of 3: one triangulation).
TEST(ImproveFlips, EdgeRemovalOfARingOfThreeIsTheThreeTwoFlip) {
  NodeSet n = interior_nodes({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 1}, {1, 1, -1}});
  const std::uint32_t a = 0, b = 1, c = 2, p = 3, q = 4;
  std::vector<std::uint32_t> tets;
  for (auto [x, y] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    const auto t = positive(n, x, y, p, q);
    tets.insert(tets.end(), t.begin(), t.end());
  }
  ImproveTets m(n, tets, {7, 7, 7});
  std::vector<std::uint32_t> ring, ring_tets;
  ASSERT_TRUE(m.edge_ring(0, p, q, ring, ring_tets));
  EXPECT_EQ(std::set<std::uint32_t>(ring.begin(), ring.end()), (std::set<std::uint32_t>{a, b, c}));
  // The ring's order: (p, q, r_k, r_k+1) positive.
  for (std::size_t k = 0; k < ring.size(); ++k)
    EXPECT_GT(pred::orient3d(n.points.p(p), n.points.p(q), n.points.p(ring[k]),
                             n.points.p(ring[(k + 1) % ring.size()])), 0);
  FlipCandidate cand;
  ASSERT_TRUE(edge_removal(m, 0, p, q, 10, cand));
  EXPECT_EQ(tet_sets(cand.fresh), (std::set<std::array<std::uint32_t, 4>>{{a, b, c, p}, {a, b, c, q}}));
  EXPECT_DOUBLE_EQ(cand.q_old, std::min({sine_of(m, 0), sine_of(m, 1), sine_of(m, 2)}));
  ASSERT_TRUE(m.replace(cand.old, cand.fresh));
  expect_consistent(m);
  EXPECT_EQ(m.live(), 2u);
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (m.alive(t)) {
      EXPECT_EQ(m.region(t), 7u);  // regions carried over
    }
}

// 4-4 flip: edge ab (a above, b below, length 3) with a ring of four that is a rhombus with a
// short diagonal r1 r3 (length 2) and a long one r0 r2 (length 4). Of the two triangulations
// of the ring, edge removal takes the one whose worst tet is better, computed here directly
// (and better than the four tets around the long edge ab).
TEST(ImproveFlips, EdgeRemovalOfARingOfFourPicksTheBetterDiagonal) {
  NodeSet n = interior_nodes({{0, 0, 1.5}, {0, 0, -1.5}, {2, 0, 0}, {0, 1, 0}, {-2, 0, 0}, {0, -1, 0}});
  const std::uint32_t a = 0, b = 1, r[4] = {2, 3, 4, 5};
  std::vector<std::uint32_t> tets;
  for (int k = 0; k < 4; ++k) {
    const auto t = positive(n, a, b, r[k], r[(k + 1) % 4]);
    tets.insert(tets.end(), t.begin(), t.end());
  }
  ImproveTets m(n, tets, {0, 0, 0, 0});
  auto worst = [&](std::uint32_t d0, std::uint32_t d1, std::uint32_t e0, std::uint32_t e1) {
    // Tets of the ring split by diagonal d0 d1 (the other two ring vertices e0, e1).
    double q = 1;
    for (std::uint32_t apex : {a, b})
      for (std::uint32_t e : {e0, e1}) {
        const auto t = positive(n, d0, d1, e, apex);
        q = std::min(q, tet_sine(n.points.p(t[0]), n.points.p(t[1]), n.points.p(t[2]), n.points.p(t[3])));
      }
    return q;
  };
  const double q_short = worst(r[1], r[3], r[0], r[2]), q_long = worst(r[0], r[2], r[1], r[3]);
  ASSERT_GT(q_short, q_long);  // the configuration is as intended
  FlipCandidate cand;
  ASSERT_TRUE(edge_removal(m, 0, a, b, 10, cand));
  EXPECT_GT(cand.q_new, cand.q_old);
  // With a floor at what the best triangulation reaches, nothing is proposed.
  FlipCandidate none;
  EXPECT_FALSE(edge_removal(m, 0, a, b, 10, none, q_short));
  EXPECT_DOUBLE_EQ(cand.q_new, q_short);
  ASSERT_EQ(cand.fresh.size(), 16u);
  for (const auto& t : tet_sets(cand.fresh)) {
    EXPECT_TRUE(std::count(t.begin(), t.end(), r[1]) && std::count(t.begin(), t.end(), r[3]));
    EXPECT_NE(std::count(t.begin(), t.end(), a), std::count(t.begin(), t.end(), b));
  }
  double before = 0, after = 0;
  for (std::size_t k = 0; k < tets.size(); k += 4) before += signed_volume(n, &tets[k]);
  for (std::size_t k = 0; k < cand.fresh.size(); k += 4) after += signed_volume(n, &cand.fresh[k]);
  EXPECT_NEAR(after, before, 1e-14);
  ASSERT_TRUE(m.replace(cand.old, cand.fresh));
  expect_consistent(m);
  // Every edge but the new diagonal lies on the boundary of the octahedron: open ring, no
  // removal. The diagonal's ring is (a, r0, b, r2).
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (m.alive(t)) {
      const std::uint32_t* v = m.v(t);
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          const bool diagonal = std::min(v[i], v[j]) == r[1] && std::max(v[i], v[j]) == r[3];
          std::vector<std::uint32_t> ring, rt;
          EXPECT_EQ(m.edge_ring(t, v[i], v[j], ring, rt), diagonal);
          if (diagonal) {
            EXPECT_EQ(std::set<std::uint32_t>(ring.begin(), ring.end()),
                      (std::set<std::uint32_t>{a, b, r[0], r[2]}));
          }
        }
    }
}

// A ring of n = 5 around a long vertical edge (an irregular, non-planar pentagon): edge
// removal makes 2 (n - 2) = 6 tets of the same volume, all valid, and its quality is the best
// over the pentagon's five triangulations (the fans from each vertex), computed here directly.
TEST(ImproveFlips, EdgeRemovalOfARingOfFive) {
  std::vector<std::array<double, 3>> pts = {{0, 0, 2}, {0, 0, -2.4}};
  const double radius[5] = {1, 1.3, 0.8, 1.1, 0.9};
  for (int k = 0; k < 5; ++k)
    pts.push_back({radius[k] * std::cos(2 * kPi * k / 5), radius[k] * std::sin(2 * kPi * k / 5), 0.05 * k});
  NodeSet n = interior_nodes(pts);
  std::vector<std::uint32_t> tets;
  for (std::uint32_t k = 0; k < 5; ++k) {
    const auto t = positive(n, 0, 1, 2 + k, 2 + (k + 1) % 5);
    tets.insert(tets.end(), t.begin(), t.end());
  }
  ImproveTets m(n, tets, std::vector<std::uint32_t>(5, 0));
  double best_fan = -1;
  for (std::uint32_t f = 0; f < 5; ++f) {
    double q = 1;
    for (std::uint32_t s = 1; s <= 3; ++s) {  // triangles (f, f+s, f+s+1)
      const std::uint32_t x = 2 + f, y = 2 + (f + s) % 5, z = 2 + (f + s + 1) % 5;
      for (std::uint32_t apex : {0u, 1u}) {
        const auto t = positive(n, x, y, z, apex);
        q = std::min(q, tet_sine(n.points.p(t[0]), n.points.p(t[1]), n.points.p(t[2]), n.points.p(t[3])));
      }
    }
    best_fan = std::max(best_fan, q);
  }
  FlipCandidate cand;
  ASSERT_TRUE(edge_removal(m, 0, 0, 1, 10, cand));
  EXPECT_EQ(cand.fresh.size(), 4u * 6);
  EXPECT_DOUBLE_EQ(cand.q_new, best_fan);
  EXPECT_GT(cand.q_new, cand.q_old);
  for (std::size_t k = 0; k < cand.fresh.size(); k += 4)
    EXPECT_GT(pred::orient3d(n.points.p(cand.fresh[k]), n.points.p(cand.fresh[k + 1]),
                             n.points.p(cand.fresh[k + 2]), n.points.p(cand.fresh[k + 3])), 0);
  double before = 0, after = 0;
  for (std::size_t k = 0; k < tets.size(); k += 4) before += signed_volume(n, &tets[k]);
  for (std::size_t k = 0; k < cand.fresh.size(); k += 4) after += signed_volume(n, &cand.fresh[k]);
  EXPECT_NEAR(after, before, 1e-13);
  EXPECT_FALSE(edge_removal(m, 0, 0, 1, 4, cand));  // ring larger than max_ring
  // Edge (apex, ring vertex) lies on the boundary of this 5-tet ball: open ring.
  EXPECT_FALSE(edge_removal(m, 0, 0, 2, 10, cand));
  ASSERT_TRUE(edge_removal(m, 0, 0, 1, 10, cand));
  ASSERT_TRUE(m.replace(cand.old, cand.fresh));
  expect_consistent(m);
  EXPECT_EQ(m.live(), 6u);
  // replace() refuses new tets that do not fill the cavity (a missing tet).
  std::vector<std::uint32_t> all;
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (m.alive(t)) all.push_back(t);
  std::vector<std::uint32_t> fewer = live_tets(m);
  fewer.resize(fewer.size() - 4);
  EXPECT_FALSE(m.replace(all, fewer));
  EXPECT_EQ(m.live(), 6u);
  expect_consistent(m);
}

// Smoothing: the centre vertex of an octahedron of six tets-pairs, pushed close to one face,
// moves back; the star's worst sine rises; it is never moved outside its kernel.
TEST(ImproveSmooth, InteriorVertexMovesToRaiseTheWorstTet) {
  std::vector<std::array<double, 3>> pts = {{0.9, 0.05, 0.02}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0},
                                            {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  NodeSet n = interior_nodes(pts);
  std::vector<std::uint32_t> tets;
  const std::uint32_t xs[2] = {1, 2}, ys[2] = {3, 4}, zs[2] = {5, 6};
  for (auto x : xs)
    for (auto y : ys)
      for (auto z : zs) {
        const auto t = positive(n, 0, x, y, z);
        tets.insert(tets.end(), t.begin(), t.end());
      }
  ImproveTets m(n, tets, std::vector<std::uint32_t>(8, 0));
  SmoothContext ctx;
  ctx.iterations = 20;
  double before = 0, after = 0;
  ASSERT_TRUE(smooth_vertex(m, 0, ctx, &before, &after));
  EXPECT_GT(after, before);
  // The optimum is the centre (the corner tets' sine is then sqrt(2/3)); 20 steps get close.
  EXPECT_GT(after, 0.9 * std::sqrt(2.0 / 3));
  expect_consistent(m);
  // Boundary-only vertices (here every other vertex: they have boundary faces) and a
  // surface-kind node without a surface do not move.
  EXPECT_FALSE(smooth_vertex(m, 1, ctx));
  // Relaxation to the centroid of the neighbours (the origin) from a displaced centre.
  m.p_mut(0)[0] = 0.5;
  EXPECT_TRUE(relax_vertex(m, 0, ctx, 0.0));
  EXPECT_NEAR(m.p(0)[0], 0, 1e-15);
  expect_consistent(m);
}

// Feature nodes slide along their curve (issue 18: caps folded along feature edges kept 3-4
// feature nodes that could not move). On the cube's edge y = z = 0 between the corners a and
// b, the edge node c sits at x = 0.1, close to a: the two tets (a c d e) and (c b d e), over
// the top face (d) and the front face (e), are poor. c moves along the edge towards the middle,
// stays exactly on it, both its edges still run along the feature, and the worst tet is
// better. With slide_features off, or for a corner, nothing moves.
TEST(ImproveSmooth, FeatureNodeSlidesAlongItsCurve) {
  const CubeContext cc(0.5);
  NodeSet n;
  auto add = [&](double x, double y, double z, NodeKind k) { return add_node(n, x, y, z, k); };
  const std::uint32_t a = add(0, 0, 0, NodeKind::corner), b = add(1, 0, 0, NodeKind::corner),
                      c = add(0.1, 0, 0, NodeKind::edge), d = add(0.5, 0.5, 0, NodeKind::surface),
                      e = add(0.5, 0, -0.5, NodeKind::surface);
  for (std::uint32_t v : {a, b, c, d, e}) {
    double cp[3];
    cc.query->closest(n.points.p(v), cp, &n.facet[v]);
    ASSERT_NE(n.facet[v], kNoFacet);
  }
  std::vector<std::uint32_t> tets = positive(n, a, c, d, e);
  const auto t2 = positive(n, c, b, d, e);
  tets.insert(tets.end(), t2.begin(), t2.end());
  SmoothContext ctx;
  ctx.surface = &cc.surface;
  ctx.query = cc.query.get();
  ctx.boundary = &cc.ctx;
  ctx.on_surface = 1e-11;
  {
    NodeSet copy = n;
    ImproveTets m(copy, tets, {0, 0});
    SmoothContext off = ctx;
    off.slide_features = false;
    EXPECT_FALSE(smooth_vertex(m, c, off));
    EXPECT_FALSE(smooth_vertex(m, a, ctx));  // a corner
    EXPECT_EQ(copy.points.p(c)[0], 0.1);
  }
  ImproveTets m(n, tets, {0, 0});
  double before = 0, after = 0;
  ASSERT_TRUE(smooth_vertex(m, c, ctx, &before, &after));
  EXPECT_GT(after, before);
  const double* x = m.p(c);
  EXPECT_EQ(x[1], 0.0);
  EXPECT_EQ(x[2], 0.0);
  EXPECT_GT(x[0], 0.3);  // the optimum is x = 0.5, by symmetry
  EXPECT_LT(x[0], 0.7);
  EXPECT_TRUE(keeps_feature(m, a, c, cc.ctx));
  EXPECT_TRUE(keeps_feature(m, c, b, cc.ctx));
  double worst = 1;
  for (std::uint32_t t = 0; t < 2; ++t) {
    const std::uint32_t* v = m.v(t);
    worst = std::min(worst, tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])));
  }
  EXPECT_DOUBLE_EQ(worst, after);
  expect_consistent(m);
}

// ---------------------------------------------------------------------------------------------
// Meshes from the pipeline.

/// Axis-aligned boxes [lo, hi], 12 outward triangles each, through prepare_surface.
PreparedSurface boxes(const std::vector<std::array<double, 6>>& bs) {
  SurfaceMesh s;
  for (const auto& b : bs) {
    const std::uint32_t o = std::uint32_t(s.points.size());
    for (int i = 0; i < 8; ++i)
      s.points.push_back((i & 1) ? b[3] : b[0], (i >> 1 & 1) ? b[4] : b[1], (i >> 2 & 1) ? b[5] : b[2]);
    for (std::uint32_t x : {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5})
      s.tris.push_back(o + x);
  }
  return prepare_surface(std::move(s), "boxes");
}

struct Piped {
  PreparedSurface surface;
  std::unique_ptr<SurfaceQuery> query;
  SizingField sizing;
  VolumeMesh mesh;
};

Piped pipeline(const std::vector<std::array<double, 6>>& bs, double h, double graded_at = -1) {
  Piped p;
  p.surface = boxes(bs);
  p.query = std::make_unique<SurfaceQuery>(p.surface.mesh);
  SizingOptions so;
  so.max_size = h;
  so.gradation = 0.3;
  if (graded_at >= 0) {
    SizingZone z;
    z.kind = SizingZone::Kind::point;
    z.size = h / 4;
    z.coords = {graded_at, graded_at, graded_at};
    so.zones.push_back(z);
  }
  p.sizing = build_sizing_field(p.surface.mesh, so);
  const NodeSet nodes = place_nodes({p.surface, *p.query, p.sizing}, detect_sharp_edges(p.surface.mesh, 30));
  p.mesh = mesh_volume({p.surface, *p.query, p.sizing}, nodes);
  return p;
}

std::string failures(const MeshCheck& c) {
  std::string s;
  for (auto& f : c.failures) s += f + "\n";
  return s;
}

double total_volume(const VolumeMesh& vm) {
  double v = 0;
  for (std::size_t t = 0; t < vm.num_tets(); ++t) v += signed_volume(vm.nodes, &vm.tets[4 * t]);
  return v;
}

std::multiset<std::array<std::uint32_t, 3>> boundary_set(const VolumeMesh& vm) {
  std::multiset<std::array<std::uint32_t, 3>> s;
  for (std::size_t k = 0; k + 2 < vm.boundary.size(); k += 3) {
    std::array<std::uint32_t, 3> f = {vm.boundary[k], vm.boundary[k + 1], vm.boundary[k + 2]};
    std::sort(f.begin(), f.end());
    s.insert(f);
  }
  return s;
}

// Node insertion: on the graded cube's Delaunay mesh, the 20 worst tets are replaced with
// their neighbours by a fan around a new interior node where one beats the sliver; each fan
// is valid, and the volume and the boundary faces are unchanged.
TEST(ImproveInsert, SliverAndItsNeighboursBecomeAFanAroundANewNode) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.15, 0.0);
  const std::size_t nodes_before = p.mesh.nodes.size_count();
  ImproveTets m(p.mesh.nodes, p.mesh.tets, p.mesh.tet_region);
  m.inside_query = p.query.get();
  std::vector<std::pair<double, std::uint32_t>> worst;
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    const std::uint32_t* v = m.v(t);
    worst.push_back({tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])), t});
  }
  std::sort(worst.begin(), worst.end());
  ASSERT_GE(worst.size(), 20u);
  ASSERT_LT(worst[0].first, std::sin(5 * kPi / 180));  // slivers to replace
  const double volume_before = total_volume(p.mesh);
  std::size_t inserted = 0;
  std::vector<std::uint32_t> created;
  for (std::size_t k = 0; k < 20; ++k) {
    const auto [q, t] = worst[k];
    if (!m.alive(t)) continue;
    created.clear();
    if (!insert_in_cavity(m, t, &created)) continue;
    ++inserted;
    // The fan: every new tet holds the new node, and the worst of them beats the sliver.
    const std::uint32_t x = std::uint32_t(m.nodes().size_count() - 1);
    EXPECT_EQ(m.nodes().kind[x], NodeKind::interior);
    double fan_worst = 1;
    for (std::uint32_t c : created) {
      const std::uint32_t* v = m.v(c);
      EXPECT_GE(index_in(v, x), 0);
      fan_worst = std::min(fan_worst, tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])));
    }
    EXPECT_GT(fan_worst, q);
  }
  EXPECT_GT(inserted, 0u);
  expect_consistent(m);
  const auto bset = boundary_set(p.mesh);
  VolumeMesh& vm = p.mesh;
  EXPECT_EQ(m.write_back(vm), 0u);  // no boundary face changed
  EXPECT_EQ(boundary_set(vm), bset);
  EXPECT_EQ(vm.nodes.size_count(), nodes_before + inserted);
  EXPECT_NEAR(total_volume(vm), volume_before, 1e-12);
  const MeshCheck c = check_volume_mesh(vm, {p.surface, *p.query, p.sizing});
  EXPECT_TRUE(c.ok()) << failures(c);
}

// The unit cube, graded towards a corner (sizes 0.0375 .. 0.15): every property the pass
// promises, on a mesh with slivers.
// The certificate of ImproveTets::inside_ok_moved (a known-inside centroid carried along a
// path clear of every facet box) never changes an answer: for moves small and large, some
// through the surface, it agrees with the full ray-parity test.
// The constructor checks every node reference on all threads and names the first bad one,
// whichever thread found it (40,000 tets: two workers' ranges); each node's tet is the last
// slot holding it, as a loop over the slots in order leaves it.
TEST(ImproveTets, TheFirstBadNodeReferenceIsNamedAndEachNodesTetIsItsLast) {
  NodeSet n = interior_nodes({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  std::vector<std::uint32_t> tets;
  for (int k = 0; k < 40000; ++k) tets.insert(tets.end(), {0, 1, 2, 3});
  auto message = [&](const std::vector<std::uint32_t>& t) {
    try {
      ImproveTets m(n, t, {});
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::vector<std::uint32_t> bad = tets;
  bad[4 * 30000 + 2] = 9;
  EXPECT_NE(message(bad).find("tet 30000 references node 9 of 4"), std::string::npos) << message(bad);
  bad[4 * 10000 + 1] = 7;
  EXPECT_NE(message(bad).find("tet 10000 references node 7 of 4"), std::string::npos) << message(bad);
  // A star's search starts from its node's tet: the last slot holding the node.
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.06);
  const ImproveTets m(p.mesh.nodes, p.mesh.tets, p.mesh.tet_region);
  ASSERT_GT(m.capacity(), 40000u);
  std::vector<std::uint32_t> last(p.mesh.nodes.size_count(), kImproveNone), star;
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    for (int i = 0; i < 4; ++i) last[m.v(t)[i]] = t;
  for (std::uint32_t v = 0; v < last.size(); ++v) {
    m.star(v, star);
    ASSERT_FALSE(star.empty()) << "node " << v;
    ASSERT_EQ(star.front(), last[v]) << "node " << v;
  }
}

TEST(ImproveTets, InsideOkMovedAgreesWithTheFullTest) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.25);
  ImproveTets m(p.mesh.nodes, p.mesh.tets, p.mesh.tet_region);
  m.inside_query = p.query.get();
  Rng rng(11);
  int checked = 0, rejected = 0;
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    const std::uint32_t* ids = m.v(t);
    const double* p0[4] = {m.p(ids[0]), m.p(ids[1]), m.p(ids[2]), m.p(ids[3])};
    if (!m.inside_ok(ids, p0)) continue;
    if (t % 2) m.mark_inside(t);  // half certified, half not
    for (int trial = 0; trial < 4; ++trial) {
      const int iv = int(rng.below(4));
      const double step = trial < 2 ? 0.01 : 0.5;
      double x[3];
      for (int k = 0; k < 3; ++k) x[k] = p0[iv][k] + rng.uniform(-step, step);
      const double* p1[4] = {p0[0], p0[1], p0[2], p0[3]};
      p1[iv] = x;
      const bool full = m.inside_ok(ids, p1);
      ASSERT_EQ(m.inside_ok_moved(t, iv, x), full) << "tet " << t;
      ++checked;
      rejected += !full;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(rejected, 10);  // some moves leave the solid
}

// relax_vertex with the star's values given (`known`, as relax_pass keeps them) and its star
// walked before any move (as colour_pass walks them) moves every vertex exactly as without
// them, and leaves the values of every tet current: a move that did not store its star's new
// values (or stored them in the wrong slots) makes a later vertex read stale ones, and the
// known values differ from the recomputed ones at the end.
TEST(ImproveSmooth, RelaxWithKnownStarsAndValuesMovesAlikeAndKeepsThemCurrent) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.2);
  VolumeMesh copy = p.mesh;
  ImproveTets plain(p.mesh.nodes, p.mesh.tets, p.mesh.tet_region);
  ImproveTets fast(copy.nodes, copy.tets, copy.tet_region);
  for (ImproveTets* m : {&plain, &fast}) m->inside_query = p.query.get();
  SmoothContext ctx;
  ctx.surface = &p.surface;
  ctx.query = p.query.get();
  ctx.on_surface = 1e-11 * std::sqrt(3.0);
  std::vector<double> sine(fast.capacity(), std::numeric_limits<double>::infinity()), ratio(fast.capacity(), 0);
  auto values = [&](std::uint32_t t) {
    const std::uint32_t* v = fast.v(t);
    return tet_sine_ratio(fast.p(v[0]), fast.p(v[1]), fast.p(v[2]), fast.p(v[3]));
  };
  for (std::uint32_t t = 0; t < fast.capacity(); ++t)
    if (fast.alive(t)) sine[t] = values(t).sine, ratio[t] = values(t).ratio;
  const StarValues known{sine.data(), ratio.data()};
  std::vector<std::vector<std::uint32_t>> stars(p.mesh.nodes.size_count());
  for (std::uint32_t v = 0; v < stars.size(); ++v) fast.star(v, stars[v]);
  std::size_t moved = 0, surface_moved = 0;
  for (int sweep = 0; sweep < 2; ++sweep)
    for (std::uint32_t v = 0; v < p.mesh.nodes.size_count(); ++v) {
      const bool a = relax_vertex(plain, v, ctx, 0.2);
      const KnownStar star{stars[v].data(), stars[v].size()};
      ASSERT_EQ(relax_vertex(fast, v, ctx, 0.2, &known, &star), a) << "vertex " << v;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(fast.p(v)[k], plain.p(v)[k]) << "vertex " << v;
      moved += a;
      surface_moved += a && p.mesh.nodes.kind[v] != NodeKind::interior;
    }
  EXPECT_GT(moved, 200u) << surface_moved;
  EXPECT_GT(surface_moved, 20u) << moved;
  for (std::uint32_t t = 0; t < fast.capacity(); ++t) {
    if (!fast.alive(t)) continue;
    ASSERT_EQ(sine[t], values(t).sine) << "tet " << t;
    ASSERT_EQ(ratio[t], values(t).ratio) << "tet " << t;
  }
  expect_consistent(fast);
}

// femur.ply at diag/40 failed its mesh check (exit 5) once surface nodes slid on curved
// surfaces: a tet of one surface and three interior vertices had its centroid outside the
// solid, and the inside rule asked only tets with two or more surface vertices. A tet with
// one surface vertex is asked too; with none it is not (its vertices are all inside).
TEST(ImproveTets, RegressionFemurTetWithOneSurfaceVertexOutside) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.5);
  NodeSet n;
  // A surface node on the face x = 1 and three nodes labelled interior beyond it: the tet's
  // centroid (x = 1.15) is outside the cube.
  const double pts[5][3] = {{1, 0.5, 0.5}, {1.2, 0.4, 0.4}, {1.2, 0.6, 0.4}, {1.2, 0.5, 0.6}, {0.5, 0.5, 0.5}};
  n.push_back(pts[0], NodeKind::surface, 0, 1.0f);
  for (int i = 1; i < 5; ++i) n.push_back(pts[i], NodeKind::interior, kNoFacet, 1.0f);
  const std::vector<std::uint32_t> tet = positive(n, 0, 1, 2, 3);
  ImproveTets m(n, tet, {0});
  m.inside_query = p.query.get();
  const double* q[4] = {m.p(tet[0]), m.p(tet[1]), m.p(tet[2]), m.p(tet[3])};
  EXPECT_FALSE(m.inside_ok(tet.data(), q));
  const int iv = index_in(m.v(0), 1);
  const double x[3] = {1.25, 0.4, 0.4};  // a move that keeps it outside
  EXPECT_FALSE(m.inside_ok_moved(0, iv, x));
  // The same tet with no surface vertex is not asked (interior nodes lie inside the solid).
  n.kind[0] = NodeKind::interior;
  EXPECT_TRUE(m.inside_ok(tet.data(), q));
}

// The quality pass takes the adjacency the Delaunay already had (VolumeMesh::tet_adj)
// instead of matching every face again: it must be the adjacency the matching finds, face
// reference for face reference, and the pass leaves it empty once the tets changed.
TEST(ImproveTets, TheMeshersAdjacencyIsTheOneFaceMatchingFinds) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.25, 0.2);
  const std::size_t nt = p.mesh.num_tets();
  ASSERT_EQ(p.mesh.tet_adj.size(), 4 * nt);
  std::size_t boundary = 0;
  for (std::size_t f = 0; f < 4 * nt; ++f) {
    const std::uint32_t a = p.mesh.tet_adj[f];
    if (a == kNoAdjacentTet) {
      ++boundary;
      continue;
    }
    ASSERT_LT(a / 4, nt);
    EXPECT_EQ(p.mesh.tet_adj[a], f) << "face reference " << f << " is not mutual";
  }
  EXPECT_EQ(boundary, p.mesh.boundary.size() / 3);
  NodeSet n1 = p.mesh.nodes, n2 = p.mesh.nodes;
  const ImproveTets matched(n1, p.mesh.tets, p.mesh.tet_region);
  const ImproveTets given(n2, p.mesh.tets, p.mesh.tet_region, &p.mesh.tet_adj);
  for (std::uint32_t t = 0; t < nt; ++t)
    for (int i = 0; i < 4; ++i) ASSERT_EQ(given.adj(t, i), matched.adj(t, i)) << "slot " << t << " face " << i;
  improve_mesh(p.mesh, {p.surface, *p.query, p.sizing});
  EXPECT_TRUE(p.mesh.tet_adj.empty());
}

TEST(MeshImprove, GradedCubeKeepsEveryInvariantAndRaisesTheWorstAngle) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.15, 0.0);
  const VolumeMesh before = p.mesh;
  const QualitySummary q0 = summarize_quality(to_tet_mesh(before));
  ASSERT_LT(q0.min_dihedral, 5.0);  // the Delaunay mesh has slivers to remove
  ImproveOptions o;
  o.cap_angle = 0;    // no boundary change and no new node: the pass's invariants alone
  o.split_angle = 0;  // (caps, splits and boundary flips: RealPartFailureClasses in
  o.flip_boundary = false;  // test_auto_sizing.cpp)
  std::vector<double> fractions;
  o.progress = [&](const std::string& stage, double f) {
    EXPECT_EQ(stage, "improve");
    fractions.push_back(f);
  };
  const ImproveStats st = improve_mesh(p.mesh, {p.surface, *p.query, p.sizing}, o);
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  const VolumeMesh& vm = p.mesh;
  const MeshCheck c = check_volume_mesh(vm, {p.surface, *p.query, p.sizing});
  EXPECT_TRUE(c.ok()) << failures(c);
  ASSERT_EQ(vm.tet_region.size(), vm.num_tets());
  ASSERT_EQ(vm.boundary_tet.size(), vm.boundary.size() / 3);
  for (std::size_t t = 0; t < vm.num_tets(); ++t) {
    const std::uint32_t* v = &vm.tets[4 * t];
    const double *a = vm.nodes.points.p(v[0]), *b = vm.nodes.points.p(v[1]),
                 *cc = vm.nodes.points.p(v[2]), *d = vm.nodes.points.p(v[3]);
    ASSERT_GT(pred::orient3d(a, b, cc, d), 0) << "tet " << t;
    ASSERT_GE(volume_length(a, b, cc, d), kZeroVolumeLength) << "tet " << t;
  }
  // Boundary unchanged: the same faces in the same order (node ids are kept: no node is
  // removed), each boundary_tet owning its face.
  EXPECT_EQ(st.boundary_changes, 0u);
  EXPECT_EQ(vm.boundary, before.boundary);
  for (std::size_t f = 0; f < vm.boundary_tet.size(); ++f) {
    const std::uint32_t* v = &vm.tets[4 * std::size_t(vm.boundary_tet[f])];
    for (int j = 0; j < 3; ++j) EXPECT_NE(index_in(v, vm.boundary[3 * f + j]), -1);
  }
  // Nodes: same count and kinds; corner and edge nodes exactly in place; surface nodes on
  // their face plane of the cube (a coordinate exactly 0 or 1 stays so up to rounding).
  ASSERT_EQ(vm.nodes.size_count(), before.nodes.size_count());
  std::size_t moved_surface = 0;
  for (std::size_t i = 0; i < vm.nodes.size_count(); ++i) {
    ASSERT_EQ(vm.nodes.kind[i], before.nodes.kind[i]);
    const double* x = vm.nodes.points.p(std::uint32_t(i));
    const double* x0 = before.nodes.points.p(std::uint32_t(i));
    if (vm.nodes.kind[i] == NodeKind::corner || vm.nodes.kind[i] == NodeKind::edge) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(x[k], x0[k]);
    } else if (vm.nodes.kind[i] == NodeKind::surface) {
      // (placed nodes may sit one ulp inside, e.g. at 1 - 2^-53; moved ones may round onto it)
      int on_face = 0;
      for (int k = 0; k < 3; ++k) {
        const double plane = std::round(x0[k]);
        on_face += std::fabs(x0[k] - plane) <= 1e-15 && std::fabs(x[k] - plane) <= 1e-15;
      }
      EXPECT_GE(on_face, 1) << "node " << i;
      moved_surface += !std::equal(x, x + 3, x0);
    }
  }
  EXPECT_GT(moved_surface, 0u);  // surface smoothing within the cube's faces took place
  // Volume: the cube's, to rounding.
  EXPECT_NEAR(total_volume(vm), 1.0, 1e-12);
  // Quality: strictly better worst angle, and what the pass reaches on this cube.
  const QualitySummary q1 = summarize_quality(to_tet_mesh(vm));
  EXPECT_GT(q1.min_dihedral, q0.min_dihedral);
  EXPECT_GE(q1.min_dihedral, 20.0);
  EXPECT_LE(q1.max_dihedral, 150.0);
  EXPECT_GE(q1.mean_radius_ratio, q0.mean_radius_ratio);
  EXPECT_GE(q1.mean_radius_ratio, 0.8);
  EXPECT_GT(st.edge_removals + st.face_removals, 0u);
  EXPECT_GT(st.smoothed + st.relaxed, 0u);
  // Stage records: input first, then the rounds.
  ASSERT_FALSE(st.stages.empty());
  EXPECT_EQ(st.stages.front().name, "input");
  EXPECT_EQ(st.stages.front().tets, before.num_tets());
  EXPECT_NEAR(st.stages.front().min_dihedral, q0.min_dihedral, 1e-4);
  EXPECT_NEAR(st.stages.back().min_dihedral, q1.min_dihedral, 1e-4);

  // Determinism: the same input and options give the same mesh, bit for bit, on one thread
  // as on several (the vertex passes run slabs in parallel).
  for (unsigned threads : {1u, 2u, 0u}) {
    VolumeMesh again = before;
    ImproveOptions ot = o;
    ot.progress = nullptr;
    ot.threads = threads;
    improve_mesh(again, {p.surface, *p.query, p.sizing}, ot);
    EXPECT_EQ(again.tets, vm.tets) << threads << " threads";
    EXPECT_EQ(again.nodes.points.xyz, vm.nodes.points.xyz) << threads << " threads";
    EXPECT_EQ(again.tet_region, vm.tet_region);
    EXPECT_EQ(again.boundary_tet, vm.boundary_tet);
  }
}

// The flip stage on several threads chooses the next tets' flips at once, in batches, on the
// mesh as it stands, and makes them in queue order: a choice that read a tet an earlier flip
// of the batch replaced is made again, a tet a new one would precede goes back to the queue
// with its choice (reused if still valid). The flips must be exactly those of one thread, on
// a graded cube whose first flip stage makes thousands (boundary flips included), and every
// one of those paths must have been taken.
//
// On the cubes alone, disabling either mechanism left the result unchanged; on the gear of
// models/gearbox, graded towards a cross-section as in the gear box, not sending tets back
// to the queue changes the tets, and keeping stale choices crashes (it flips tets an earlier
// flip already replaced), as it did on the gear box's housing.
Piped gear_towards_a_section() {
  Piped p;
  p.surface = prepare_surface(read_surface(std::string(KDMESH_SOURCE_DIR) + "/models/gearbox/gear.stl"),
                              "gear.stl", SurfaceOptions{});
  p.query = std::make_unique<SurfaceQuery>(p.surface.mesh);
  SizingOptions so;
  so.max_size = 4;
  so.gradation = 0.3;
  SizingZone z;
  z.kind = SizingZone::Kind::plane;
  z.size = 0.8;
  z.coords = {0, 0, 75, 1, 0, 0};
  so.zones.push_back(z);
  p.sizing = build_sizing_field(p.surface.mesh, so);
  const NodeSet nodes = place_nodes({p.surface, *p.query, p.sizing}, detect_sharp_edges(p.surface.mesh, 30));
  p.mesh = mesh_volume({p.surface, *p.query, p.sizing}, nodes);
  return p;
}

/// The boundary context of p's surface, with its sharp edges `features`.
BoundaryContext boundary_of(const Piped& p, const FeatureEdges& features) {
  BoundaryContext boundary;
  boundary.surface = &p.surface;
  boundary.query = p.query.get();
  boundary.sizing = &p.sizing;
  boundary.features = &features;
  return boundary;
}

/// p's mesh after one flip stage (30 deg, rings up to 10) on `threads` threads; checks that the
/// flips counted are those made, that the sine cache is current and the adjacency consistent.
VolumeMesh flipped(const Piped& p, const BoundaryContext& boundary, unsigned threads, FlipCounts& counts,
                   const FlipSchedule& schedule) {
  VolumeMesh vm = p.mesh;
  ImproveTets m(vm.nodes, vm.tets, vm.tet_region);
  m.inside_query = p.query.get();
  m.certify_inside();
  SineCache cache(m, threads);
  const std::size_t ops = flip_pass(m, cache, deg_to_sine(30), 10, counts, &boundary, threads, schedule);
  EXPECT_EQ(ops, counts.edge_removals + counts.face_removals + counts.boundary_flips);
  // The cache is current: the new tets' sines, computed with the choices, are refresh's.
  EXPECT_EQ(cache.q(), SineCache(m, 1).q()) << threads << " threads";
  expect_consistent(m);
  m.write_back(vm);
  return vm;
}

TEST(FlipPass, BatchesOnSeveralThreadsMakeTheOneThreadFlips) {
  FlipCounts all;
  FlipSchedule whole_queue;  // the batches on the one queue, without a parallel phase
  whole_queue.max_levels = 0;
  for (const auto& [h, at] : std::vector<std::pair<double, double>>{{0.07, 0.5}, {0.06, 0.2}, {0.05, 0.9}, {0, 0}}) {
    const Piped p = h > 0 ? pipeline({{0, 0, 0, 1, 1, 1}}, h, at) : gear_towards_a_section();
    const FeatureEdges features = detect_sharp_edges(p.surface.mesh, 30);
    const BoundaryContext boundary = boundary_of(p, features);
    auto run = [&](unsigned threads, FlipCounts& counts) { return flipped(p, boundary, threads, counts, whole_queue); };
    FlipCounts one;
    const VolumeMesh ref = run(1, one);
    EXPECT_GT(one.edge_removals, 1000u) << "h " << h;
    EXPECT_EQ(one.chosen_again + one.reused + one.requeued, 0u);  // one thread: no batches
    all.boundary_flips += one.boundary_flips;
    for (const unsigned threads : {2u, 3u}) {
      FlipCounts c;
      const VolumeMesh vm = run(threads, c);
      EXPECT_EQ(vm.tets, ref.tets) << "h " << h << ", " << threads << " threads";
      EXPECT_EQ(vm.boundary, ref.boundary) << "h " << h << ", " << threads << " threads";
      EXPECT_EQ(c.edge_removals, one.edge_removals);
      EXPECT_EQ(c.face_removals, one.face_removals);
      EXPECT_EQ(c.boundary_flips, one.boundary_flips);
      all.chosen_again += c.chosen_again;
      all.reused += c.reused;
      all.requeued += c.requeued;
    }
  }
  EXPECT_GT(all.boundary_flips, 0u);
  EXPECT_GT(all.chosen_again, 0u);
  EXPECT_GT(all.reused, 0u);
  EXPECT_GT(all.requeued, 0u);
}

// The flip stage's parallel phase works parts of the mesh apart, on different threads; a
// part's flips read and change only tets whose four vertices are deep in it. The result must
// not depend on the thread count, the mesh must pass the mesh check, and both phases must have
// worked: on the gear graded towards a section (boundary flips included) and a graded cube,
// split into 8 or 16 parts.
TEST(FlipPass, PartsWorkedOnAnyThreadCountMakeTheSameValidMesh) {
  FlipSchedule parts;
  parts.part_tets = 64;
  parts.max_levels = 4;
  for (const double h : {0.0, 0.06}) {
    const Piped p = h > 0 ? pipeline({{0, 0, 0, 1, 1, 1}}, h, 0.2) : gear_towards_a_section();
    const FeatureEdges features = detect_sharp_edges(p.surface.mesh, 30);
    const BoundaryContext boundary = boundary_of(p, features);
    {
      VolumeMesh vm = p.mesh;
      ImproveTets m(vm.nodes, vm.tets, vm.tet_region);
      EXPECT_GE(parts.levels(SineCache(m, 1).below(deg_to_sine(30)).size()), 3u) << "h " << h;
    }
    auto run = [&](unsigned threads, FlipCounts& counts) { return flipped(p, boundary, threads, counts, parts); };
    FlipCounts one;
    const VolumeMesh ref = run(1, one);
    EXPECT_GT(one.in_parts, 100u) << "h " << h;
    EXPECT_GT(one.left_by_parts, 0u) << "h " << h;
    EXPECT_GT(one.edge_removals + one.face_removals + one.boundary_flips, one.in_parts) << "h " << h;
    const MeshCheck c = check_volume_mesh(ref, {p.surface, *p.query, p.sizing});
    EXPECT_TRUE(c.ok()) << "h " << h << ": " << failures(c);
    for (const unsigned threads : {2u, 3u}) {
      FlipCounts n;
      const VolumeMesh vm = run(threads, n);
      EXPECT_EQ(vm.tets, ref.tets) << "h " << h << ", " << threads << " threads";
      EXPECT_EQ(vm.boundary, ref.boundary) << "h " << h << ", " << threads << " threads";
      EXPECT_EQ(n.in_parts, one.in_parts);
      EXPECT_EQ(n.left_by_parts, one.left_by_parts);
    }
  }
}

// A deep vertex's whole star lies in its part: the deep vertices of any tet share one part
// (a tet with vertices deep in two parts would let two threads change it at once), every part
// has some, the vertices near the cuts have none, and the split is the same on any thread count.
TEST(FlipParts, TheDeepVerticesOfATetShareTheirPart) {
  const Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.08, 0.5);
  VolumeMesh vm = p.mesh;
  ImproveTets m(vm.nodes, vm.tets, vm.tet_region);
  std::vector<std::uint32_t> seeds;  // every live tet
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (m.alive(t)) seeds.push_back(t);
  const FlipParts parts = flip_parts(m, seeds, 3, 1);
  ASSERT_EQ(parts.count, 8u);
  EXPECT_EQ(flip_parts(m, seeds, 3, 2).deep, parts.deep);
  std::vector<std::size_t> deep_in(parts.count + 1, 0);
  for (const std::uint8_t d : parts.deep) ++deep_in[d == kNoPart ? parts.count : d];
  for (unsigned q = 0; q < parts.count; ++q) EXPECT_GT(deep_in[q], 0u) << "part " << q;
  EXPECT_GT(deep_in[parts.count], 0u);
  std::vector<std::size_t> held(parts.count, 0);  // tets a part may flip
  for (const std::uint32_t t : seeds) {
    std::uint8_t part = kNoPart;
    for (int i = 0; i < 4; ++i) {
      const std::uint8_t d = parts.deep[m.v(t)[i]];
      if (d == kNoPart) continue;
      EXPECT_TRUE(part == kNoPart || part == d) << "tet " << t;
      part = d;
    }
    if (part != kNoPart && parts.holds(part, m.v(t))) ++held[part];
  }
  for (unsigned q = 0; q < parts.count; ++q) EXPECT_GT(held[q], 0u) << "part " << q;
  EXPECT_THROW(flip_parts(m, seeds, 8, 1), UsageError);
}

// Three rounds left handle.ply at diag/20 with 111 tets below the targets (min dihedral 5.1
// deg); rounds go on now while such tets remain and their count reaches new lows (15 rounds,
// none left, 13.4 deg). The mechanism, on the graded cube at h = 0.18 with a target of 35 deg
// (which one round of flips and smoothing leaves tets below): further rounds get strictly
// fewer, and stop by themselves before max_rounds. (The count is not monotone, and the test
// needs a case where the rounds find a new low. Since the Delaunay's tets are put in canonical
// order, h = 0.12, 0.15 and 0.18 do; 0.2 and 0.22 end where one round ends, at 87 and 68.)
TEST(MeshImprove, RegressionHandleRoundsGoOnWhileTetsBelowTheTargetGetFewer) {
  constexpr double kTarget = 35;
  auto below_target = [](const VolumeMesh& vm) {
    std::size_t n = 0;
    for (std::size_t t = 0; t < vm.num_tets(); ++t) {
      const std::uint32_t* v = &vm.tets[4 * t];
      n += tet_sine(vm.nodes.points.p(v[0]), vm.nodes.points.p(v[1]), vm.nodes.points.p(v[2]),
                    vm.nodes.points.p(v[3])) < std::sin(kTarget * kPi / 180);
    }
    return n;
  };
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.18, 0.0);
  ImproveOptions o;
  o.rounds = 1;
  o.max_rounds = 1;
  o.target_angle = kTarget;
  VolumeMesh one = p.mesh;
  const ImproveStats s1 = improve_mesh(one, {p.surface, *p.query, p.sizing}, o);
  EXPECT_EQ(s1.rounds, 1);
  const std::size_t after_one = below_target(one);
  ASSERT_GT(after_one, 0u);  // what further rounds are for
  o.max_rounds = 40;
  VolumeMesh more = p.mesh;
  const ImproveStats s2 = improve_mesh(more, {p.surface, *p.query, p.sizing}, o);
  EXPECT_GT(s2.rounds, 1);
  EXPECT_LT(s2.rounds, 40);
  EXPECT_LT(below_target(more), after_one);
  const MeshCheck c = check_volume_mesh(more, {p.surface, *p.query, p.sizing});
  EXPECT_TRUE(c.ok()) << failures(c);
  // The extra rounds, splits and insertions make no thread-dependent choice (split_angle 30:
  // on this cube nothing is below 12 deg when the split pass runs).
  ImproveOptions od = o;
  od.split_angle = 30;
  VolumeMesh first = p.mesh;
  od.threads = 1;
  const ImproveStats sf = improve_mesh(first, {p.surface, *p.query, p.sizing}, od);
  EXPECT_GT(sf.splits + sf.boundary_splits + sf.insertions, 0u);
  for (unsigned threads : {2u, 0u}) {
    VolumeMesh again = p.mesh;
    od.threads = threads;
    const ImproveStats sa = improve_mesh(again, {p.surface, *p.query, p.sizing}, od);
    EXPECT_EQ(sa.rounds, sf.rounds) << threads << " threads";
    EXPECT_EQ(sa.insertions, sf.insertions) << threads << " threads";
    EXPECT_EQ(again.tets, first.tets) << threads << " threads";
    EXPECT_EQ(again.nodes.points.xyz, first.nodes.points.xyz) << threads << " threads";
  }
  o.rounds = 0;  // no rounds at all: the mesh is left as it is, whatever max_rounds says
  VolumeMesh none = p.mesh;
  EXPECT_EQ(improve_mesh(none, {p.surface, *p.query, p.sizing}, o).rounds, 0);
  EXPECT_EQ(tet_sets(none.tets), tet_sets(p.mesh.tets));
}

// Two disjoint boxes: two regions, each keeps its tets and volume; the boundary face set is
// unchanged.
TEST(MeshImprove, TwoBodiesKeepTheirRegions) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}, {2, 0, 0, 3, 1, 0.5}}, 0.2);
  ASSERT_EQ(p.surface.num_bodies, 2u);
  const auto bset = boundary_set(p.mesh);
  ImproveOptions o;
  o.flip_boundary = false;  // the boundary face set stays as it is
  improve_mesh(p.mesh, {p.surface, *p.query, p.sizing}, o);
  const VolumeMesh& vm = p.mesh;
  const MeshCheck c = check_volume_mesh(vm, {p.surface, *p.query, p.sizing});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_EQ(boundary_set(vm), bset);
  double vol[2] = {0, 0};
  for (std::size_t t = 0; t < vm.num_tets(); ++t) {
    double x = 0;
    for (int i = 0; i < 4; ++i) x += vm.nodes.points.p(vm.tets[4 * t + i])[0] / 4;
    const std::uint32_t body = p.surface.shell_body[p.surface.tri_shell[x < 1.5 ? 0 : 12]];
    ASSERT_EQ(vm.tet_region[t], body) << "tet " << t;
    vol[body] += signed_volume(vm.nodes, &vm.tets[4 * t]);
  }
  const std::uint32_t b0 = p.surface.shell_body[p.surface.tri_shell[0]];
  EXPECT_NEAR(vol[b0], 1.0, 1e-12);
  EXPECT_NEAR(vol[1 - b0], 0.5, 1e-12);
}

TEST(MeshImprove, BadOptionsThrow) {
  Piped p = pipeline({{0, 0, 0, 1, 1, 1}}, 0.5);
  ImproveOptions o;
  o.work_angle = 0;
  EXPECT_THROW(improve_mesh(p.mesh, {p.surface, *p.query, p.sizing}, o), UsageError);
  o = {};
  o.max_ring = 2;
  EXPECT_THROW(improve_mesh(p.mesh, {p.surface, *p.query, p.sizing}, o), UsageError);
}

}  // namespace

namespace {

/// Two unit boxes touching on x = 1, meshed at h: bodies a (x < 1) and b, with their regions.
struct TwoBoxes {
  PreparedSurface surface;
  std::unique_ptr<SurfaceQuery> query;
  std::unique_ptr<RegionQuery> regions;
  SizingField sizing;
  VolumeMesh mesh;
};

std::unique_ptr<TwoBoxes> two_touching_boxes(double h) {
  auto b = std::make_unique<TwoBoxes>();
  std::vector<PreparedSurface> parts;
  parts.push_back(boxes({{0, 0, 0, 1, 1, 1}}));
  parts.push_back(boxes({{1, 0, 0, 2, 1, 1}}));
  b->surface = join_bodies(std::move(parts), {"a", "b"}, {"a.stl", "b.stl"});
  b->query = std::make_unique<SurfaceQuery>(b->surface.mesh);
  b->regions = std::make_unique<RegionQuery>(b->surface);
  SizingOptions so;
  so.max_size = h;
  b->sizing = build_sizing_field(b->surface.mesh, so);
  const Domain d{b->surface, *b->query, b->sizing, b->regions.get()};
  PlacementOptions po;
  po.interface_feature_angle = 30;
  const FeatureEdges features = detect_sharp_edges(b->surface.mesh, 30, interface_rim_edges(b->surface));
  b->mesh = mesh_volume(d, place_nodes(d, features, po));
  return b;
}

}  // namespace

// The flip stage tests its choices' new tets against the regions on its workers
// (fresh_in_region), not in replace(): the same answers as the centroid test of each tet.
TEST(ImproveTets, FreshInRegionIsTheCentroidTestOfEachTetWithASurfaceVertex) {
  const auto b = two_touching_boxes(0.2);
  ASSERT_FALSE(b->surface.interfaces.empty());
  VolumeMesh vm = b->mesh;
  ImproveTets m(vm.nodes, vm.tets, vm.tet_region);
  std::size_t tested = 0;
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    const std::vector<std::uint32_t> fresh(m.v(t), m.v(t) + 4);
    EXPECT_TRUE(m.fresh_in_region(fresh, 1 - m.region(t)));  // no region query: no test
  }
  m.region_query = b->regions.get();
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    const std::vector<std::uint32_t> fresh(m.v(t), m.v(t) + 4);
    bool surface = false;
    double c[3] = {0, 0, 0};
    for (int i = 0; i < 4; ++i) {
      surface = surface || vm.nodes.kind[fresh[i]] != NodeKind::interior;
      for (int k = 0; k < 3; ++k) c[k] += m.p(fresh[i])[k] / 4;
    }
    for (const std::uint32_t r : {0u, 1u})
      EXPECT_EQ(m.fresh_in_region(fresh, r), !surface || b->regions->in_body(c, r)) << "tet " << t;
    if (!surface) continue;
    ++tested;
    EXPECT_TRUE(m.fresh_in_region(fresh, m.region(t))) << "tet " << t;
    EXPECT_FALSE(m.fresh_in_region(fresh, 1 - m.region(t))) << "tet " << t;
  }
  EXPECT_GT(tested, 100u);
}

// With touching bodies the flip stage's choices carry their region test from the workers; the
// flips are still those of one thread, and every tet stays in its body.
TEST(FlipPass, TwoBodiesOnSeveralThreadsMakeTheOneThreadFlips) {
  const auto b = two_touching_boxes(0.15);
  auto run = [&](unsigned threads) {
    VolumeMesh vm = b->mesh;
    ImproveTets m(vm.nodes, vm.tets, vm.tet_region);
    m.inside_query = b->query.get();
    m.region_query = b->regions.get();
    m.certify_inside();
    SineCache cache(m, threads);
    FlipCounts counts;
    EXPECT_GT(flip_pass(m, cache, deg_to_sine(30), 10, counts, nullptr, threads), 100u);
    m.write_back(vm);
    return vm;
  };
  const VolumeMesh one = run(1);
  for (std::size_t t = 0; t < one.num_tets(); ++t) {
    double x = 0;
    for (int i = 0; i < 4; ++i) x += one.nodes.points.p(one.tets[4 * t + i])[0] / 4;
    EXPECT_EQ(one.tet_region[t], x > 1 ? 1u : 0u) << "tet " << t;  // bodies in list order
  }
  for (const unsigned threads : {2u, 3u}) EXPECT_EQ(run(threads).tets, one.tets) << threads << " threads";
}

}  // namespace kdmesh
