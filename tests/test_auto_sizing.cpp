// kdmesh — the automatic sizing terms (issue 18): wall thickness and gaps from rays, and the
// pipeline's creases, curvature and local refinement on parts that failed before.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "io/surface_io.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/improve/mesh_improve.h"
#include "mesher/placement/node_placement.h"
#include "mesher/tet_quality.h"
#include "mesher/volume/volume_mesh.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "mesher/surface/thickness_sizes.h"
#include "sizing/features.h"
#include "tests/support/icosphere.h"
#include "tests/support/scratch.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {
namespace {

/// A closed prism over a counter-clockwise polygon (x, y pairs) from z0 to z1, outward
/// oriented, caps fanned from vertex 0; appended to `s` (so several make several bodies).
void add_prism(SurfaceMesh& s, const std::vector<double>& xy, double z0, double z1) {
  const std::uint32_t n = std::uint32_t(xy.size() / 2), o = std::uint32_t(s.points.size());
  for (std::uint32_t i = 0; i < n; ++i) s.points.push_back(xy[2 * i], xy[2 * i + 1], z0);
  for (std::uint32_t i = 0; i < n; ++i) s.points.push_back(xy[2 * i], xy[2 * i + 1], z1);
  auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) { s.tris.insert(s.tris.end(), {o + a, o + b, o + c}); };
  for (std::uint32_t i = 1; i + 1 < n; ++i) {
    tri(0, i + 1, i);
    tri(n, n + i, n + i + 1);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    tri(i, j, n + j);
    tri(i, n + j, n + i);
  }
}

SurfaceMesh box(double x0, double y0, double z0, double x1, double y1, double z1) {
  SurfaceMesh s;
  add_prism(s, {x0, y0, x1, y0, x1, y1, x0, y1}, z0, z1);
  return s;
}

SurfaceMesh cylinder(std::uint32_t n, double r, double h) {
  std::vector<double> xy;
  for (std::uint32_t i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    xy.push_back(r * std::cos(a));
    xy.push_back(r * std::sin(a));
  }
  SurfaceMesh s;
  add_prism(s, xy, 0, h);
  return s;
}

PreparedSurface prepared(SurfaceMesh m) { return prepare_surface(std::move(m), "test"); }

TEST(SurfaceQueryRay, DistanceAndFacetOfTheFirstHit) {
  const PreparedSurface s = prepared(box(0, 0, 0, 2, 1, 1));
  const SurfaceQuery q(s.mesh);
  const double o[3] = {0.5, 0.5, 0.5}, px[3] = {1, 0, 0}, mz[3] = {0, 0, -2};
  std::uint32_t hit = kNoFacet;
  EXPECT_NEAR(q.ray_distance(o, px, kNoFacet, &hit), 1.5, 1e-12);
  ASSERT_NE(hit, kNoFacet);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(s.mesh.points.p(s.mesh.tri(hit)[k])[0], 2.0);
  EXPECT_NEAR(q.ray_distance(o, mz, kNoFacet), 0.25, 1e-12);  // in units of |dir| = 2
  const double out[3] = {5, 5, 5};
  EXPECT_EQ(q.ray_distance(out, px, kNoFacet, &hit), INFINITY);
  EXPECT_EQ(hit, kNoFacet);
}

/// The thickness term of surface m (walls and gaps sized below max_size), its segments into segs.
ThicknessStats thickness_of(SurfaceMesh m, double max_size, WeightedSegments& segs) {
  const PreparedSurface s = prepared(std::move(m));
  const SurfaceQuery q(s.mesh);
  ThicknessOptions o;
  o.max_size = max_size;
  return add_thickness_sizes(s, q, o, segs);
}

TEST(ThicknessSizes, ThinPlateGetsTwoLayersAcross) {
  WeightedSegments segs;
  const ThicknessStats st = thickness_of(box(0, 0, 0, 10, 10, 0.5), 2, segs);
  // The 4 facets of the two big faces see the other face 0.5 away; the side facets (10 or 0.5
  // wide) see the opposite side 10 away: above max_size.
  EXPECT_EQ(st.walls, 4u);
  EXPECT_EQ(st.gaps, 0u);
  EXPECT_NEAR(st.min_wall, 0.5, 1e-12);
  ASSERT_EQ(segs.size(), 4u);
  for (double w : segs.weight) EXPECT_NEAR(w, 0.25, 1e-12);
}

TEST(ThicknessSizes, NarrowGapBetweenTwoBodies) {
  SurfaceMesh m = box(0, 0, 0, 4, 4, 4);
  add_prism(m, {4.3, 0, 8, 0, 8, 4, 4.3, 4}, 0, 4);
  WeightedSegments segs;
  const ThicknessStats st = thickness_of(std::move(m), 1, segs);
  EXPECT_EQ(st.walls, 0u);
  EXPECT_EQ(st.gaps, 4u);  // two facets on each of the facing walls
  EXPECT_NEAR(st.min_gap, 0.3, 1e-12);
}

TEST(ThicknessSizes, OpenGrooveFlanksAreNoGap) {
  // A block with a V notch of 90 deg opening cut into its top: the flanks face each other at
  // 90 deg, not back, so they set no gap size.
  SurfaceMesh m;
  add_prism(m, {2, 1.5, 1.5, 2, 0, 2, 0, 0, 4, 0, 4, 2, 2.5, 2}, 0, 1);  // fanned from the notch
  WeightedSegments segs;
  EXPECT_EQ(thickness_of(std::move(m), 1, segs).gaps, 0u);
}

// The two flanks of a wedge face back at each other but are no wall: their width goes to zero
// at the edge they share, at every scale (hand.ply's 2.14 deg fold was refused at every size
// while this term packed nodes into it). A prism whose cross-section has a 2.9 deg corner.
TEST(ThicknessSizes, WedgeFlanksAreNoWall) {
  SurfaceMesh m;
  add_prism(m, {0, 0, 10, 0, 10, 0.5}, 0, 4);
  WeightedSegments segs;
  const ThicknessStats st = thickness_of(std::move(m), 1, segs);
  EXPECT_EQ(st.walls, 0u);
  EXPECT_EQ(segs.size(), 0u);
}

MeshJob job_for(const SurfaceMesh& m, double size, const std::string& name) {
  MeshJob job;
  job.name = name;
  job.input = test::scratch_path("auto_sizing", ".stl");
  write_stl(m, job.input);
  job.sizing.max_size = size;
  job.sizing.min_size = size / 1000;
  return job;
}

// Failure class 1 of issue 18 (boundary faces a little over 0.1 h): a 14-sided prism's side
// edges are bent by 25.7 deg, below the 30 deg sharp angle, and a boundary face of size h
// across one lies up to (h/4) sin 25.7 = 0.108 h from the surface. They are kept as creases now.
TEST(RealPartFailureClasses, CreaseBelowTheSharpAngleIsKept) {
  MeshJob job = job_for(cylinder(14, 10, 30), 4, "crease");
  const MeshJobResult r = run_mesh_job(job);
  ASSERT_TRUE(r.ok()) << r.summary.dump(1);
  EXPECT_EQ(r.summary["counts"]["feature_edges"].get<std::size_t>(), 3u * 14);
  EXPECT_LE(r.summary["mesh_check"]["max_hausdorff"].get<double>(), 0.1);
  // With the creases off, the same job keeps only the 28 rim edges.
  job.auto_creases = false;
  job.max_refinements = 0;
  const MeshJobResult off = run_mesh_job(job);
  EXPECT_EQ(off.summary["counts"]["feature_edges"].get<std::size_t>(), 2u * 14);
}

// Failure class 2 (volume off by 0.64-1.8% at diag/20): a finely tessellated cylinder meshed
// at a size close to its radius lost its volume to chords. The curvature and chordal terms
// shrink the size on the side, and say so.
TEST(RealPartFailureClasses, CoarseSizeOnACurvedPartKeepsTheVolume) {
  MeshJob job = job_for(cylinder(96, 10, 30), 10, "curved");
  const MeshJobResult r = run_mesh_job(job);
  ASSERT_TRUE(r.ok()) << r.summary.dump(1);
  EXPECT_LE(r.summary["mesh_check"]["volume_error"].get<double>(), 0.005);
  EXPECT_GT(r.summary["automatic_sizing"]["curvature_places"].get<std::size_t>(), 0u);
  bool announced = false;
  for (const auto& n : r.summary["notices"]) announced |= n.get<std::string>().rfind("curvature:", 0) == 0;
  EXPECT_TRUE(announced) << r.summary["notices"].dump(1);
  // Without the automatic terms the volume check fails at this size, or the boundary is
  // refined locally until it passes: either way the terms are what keeps it in one attempt.
  job.curvature_angle = 0;
  job.chordal_deviation = 0;
  job.max_refinements = 0;
  const MeshJobResult off = run_mesh_job(job);
  EXPECT_FALSE(off.ok());
}

// The summary counted the nodes before the quality pass, whose sliver splits add interior nodes:
// it said 274382 nodes for a gear box deck of 274384 (test_cli_calculix). It counts what is
// written now. The 20-sided prism at size 4 has a sliver to split (asserted, so that this test
// says when it stops exercising the bug; the sphere it used had none left once surface nodes
// slid and boundary edges flipped, the 14-sided prism none once the surface sweep changed, and
// the 20-sided one at size 3 none once the interior lattice was turned: of 35 prisms of 12-32
// sides at sizes 2-4, only this one still has one).
TEST(RealPartFailureClasses, SummaryCountsTheNodesWritten) {
  MeshJob job = job_for(cylinder(20, 10, 30), 4, "counts");
  job.nodes = test::scratch_path("auto_sizing_nodes", ".xyz");
  const MeshJobResult r = run_mesh_job(job);
  ASSERT_TRUE(r.ok()) << r.summary.dump(1);
  ASSERT_GT(r.summary["improve"]["splits"].get<std::size_t>(), 0u);
  std::ifstream in(job.nodes);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') ++lines;
  EXPECT_EQ(r.summary["counts"]["nodes"].get<std::size_t>(), lines);
  std::size_t by_kind = 0;
  for (const auto& [k, v] : r.summary["counts"]["nodes_by_kind"].items()) by_kind += v.get<std::size_t>();
  EXPECT_EQ(by_kind, lines);
}

/// The Delaunay mesh of a sphere of radius 10 and 1,280 facets at size 4, with the automatic
/// terms of the pipeline's defaults (curvature 15 deg, chordal deviation for 0.5% of volume).
struct SphereMesh {
  PreparedSurface s;
  std::unique_ptr<SurfaceQuery> q;
  SizingField h;
  VolumeMesh delaunay;
  SphereMesh() {
    SurfaceMesh sphere = test::icosphere(3);
    for (double& x : sphere.points.xyz) x *= 10;
    s = prepared(std::move(sphere));
    q = std::make_unique<SurfaceQuery>(s.mesh);
    SizingOptions so;
    so.max_size = 4;
    so.curvature_angle_deg = 15;
    so.chordal_deviation = 0.5 * 0.005 * 10 / 3;  // half the volume tolerance x V / A (r / 3)
    so.feature_angle_deg = 14.25;
    h = build_sizing_field(s.mesh, so);
    const FeatureEdges features = detect_sharp_edges(s.mesh, 14.25);
    delaunay = mesh_volume({s, *q, h}, place_nodes({s, *q, h}, features));
  }
  /// The improved mesh, checked by the mesh check.
  VolumeMesh improved(const ImproveOptions& base, ImproveStats& st, QualitySummary& qs) const {
    VolumeMesh m = delaunay;
    ImproveOptions o = base;
    o.feature_angle = 14.25;
    st = improve_mesh(m, {s, *q, h}, o);
    const MeshCheck c = check_volume_mesh(m, {s, *q, h});
    EXPECT_TRUE(c.ok()) << (c.failures.empty() ? "" : c.failures[0]);
    qs = summarize_quality(to_tet_mesh(m));
    return m;
  }
  /// The pass with one of its switches off ([0]) and on ([1]), the rest as in `base`.
  struct OnOff {
    ImproveStats st[2];
    QualitySummary q[2];
    VolumeMesh mesh[2];
  };
  OnOff on_off(bool ImproveOptions::*flag, ImproveOptions base = {}) const {
    OnOff r;
    for (int on = 0; on < 2; ++on) {
      base.*flag = on == 1;
      r.mesh[on] = improved(base, r.st[on], r.q[on]);
    }
    return r;
  }
};

// Quality at the boundary (issue 18: 84% of the meshes of real parts had near-flat tets, 98% of
// them with four boundary vertices). On a sphere of 1,280 facets the Delaunay boundary layer
// has flat caps and slivers lying in the surface; the caps are taken out and the slivers split,
// and the mesh still passes its check.
TEST(RealPartFailureClasses, BoundaryCapsAndSliversAreRemoved) {
  const SphereMesh sm;
  ImproveOptions o;
  o.slide_curved = false;  // caps and splits alone
  o.flip_boundary = false;
  // In the three rounds these were measured with: further rounds (max_rounds) let flips and
  // smoothing alone reach 12.4 deg here, and caps and splits stall them at 6.4.
  o.max_rounds = 3;
  ImproveStats off, on;
  QualitySummary q_off, q_on;
  o.cap_angle = 0;
  o.split_angle = 0;
  sm.improved(o, off, q_off);
  o.cap_angle = 15;
  o.split_angle = 12;
  sm.improved(o, on, q_on);
  EXPECT_EQ(off.caps_removed + off.splits, 0u);
  EXPECT_GT(on.caps_removed, 0u);
  EXPECT_GT(q_on.min_dihedral, q_off.min_dihedral);
  // With the surface nodes sliding and the boundary edges flipping too (the default pass),
  // no tet is under 5 deg, the target (19.9 deg here). Caps and splits alone reached
  // 5.0 deg on one surface sampling and 4.7 on the next (from 1.7): not their guarantee.
  ImproveStats all;
  QualitySummary q_all;
  sm.improved(ImproveOptions{}, all, q_all);
  EXPECT_GE(q_all.min_dihedral, 5.0);
}

// The quality pass never moved surface nodes on curved surfaces, so the tets at a curved
// boundary kept the shape node placement gave them (issue 18: 0.0-5 deg on most real parts;
// across the 26 parts at diag/40 the sliding took the parts with a min dihedral >= 12 deg from
// 8 to 17). Surface nodes now slide on the input surface: the moved ones lie on it, the mesh
// passes its check (boundary within tolerance, volume), and the worst angle rises.
TEST(RealPartFailureClasses, SurfaceNodesSlideOnCurvedSurfaces) {
  const SphereMesh sm;
  ImproveOptions o;
  o.flip_boundary = false;  // the sliding alone: no boundary flips, boundary-edge splits or
  o.split_boundary = false;  // node insertions (each of which lowers this sphere's worst angle
  o.insert_nodes = false;    // in this setting, to 10.3 deg with both), in the three rounds it
  o.max_rounds = 3;          // was measured with
  const SphereMesh::OnOff r = sm.on_off(&ImproveOptions::slide_curved, o);
  const VolumeMesh &fixed = r.mesh[0], &slid = r.mesh[1];
  const QualitySummary &fixed_q = r.q[0], &slide_q = r.q[1];
  // Surface nodes that moved (not at a position of the Delaunay mesh: ids shift where a cap
  // removal drops a node) lie on the sphere.
  std::set<std::array<double, 3>> placed;
  for (std::uint32_t i = 0; i < sm.delaunay.nodes.size_count(); ++i) {
    const double* x = sm.delaunay.nodes.points.p(i);
    placed.insert({x[0], x[1], x[2]});
  }
  auto count_moved = [&](const VolumeMesh& m) {
    std::size_t moved = 0;
    for (std::uint32_t i = 0; i < m.nodes.size_count(); ++i) {
      if (m.nodes.kind[i] != NodeKind::surface) continue;
      const double* x = m.nodes.points.p(i);
      if (placed.count({x[0], x[1], x[2]})) continue;
      ++moved;
      EXPECT_LE(sm.q->distance(x), 1e-12 * 10) << "node " << i;
    }
    return moved;
  };
  const std::size_t moved_fixed = count_moved(fixed), moved = count_moved(slid);
  // Without sliding only nodes whose fan lies in one facet's plane move (some do here).
  EXPECT_GT(moved, 2 * moved_fixed);  // 850 and 119 when written
  EXPECT_GT(slide_q.min_dihedral, fixed_q.min_dihedral);  // 21.9 and 8.6 deg when written
  EXPECT_GE(slide_q.min_dihedral, 12.0);
}

// A boundary triangulation that placement left with long, skinny faces could not change
// (issue 18: handle.ply kept 22 tets under 5 deg at diag/40 after the sliding; boundary edge
// flips took it to 3). Boundary edges now flip within the surface where the worst tet gains:
// the boundary faces change, every new one within the tolerance (the mesh check passes), and
// the worst angle rises.
TEST(RealPartFailureClasses, BoundaryEdgesFlipWithinTheSurface) {
  const SphereMesh sm;
  const SphereMesh::OnOff r = sm.on_off(&ImproveOptions::flip_boundary);
  const ImproveStats &off_st = r.st[0], &on_st = r.st[1];
  const QualitySummary &off_q = r.q[0], &on_q = r.q[1];
  const VolumeMesh& on = r.mesh[1];
  EXPECT_EQ(off_st.boundary_flips, 0u);
  EXPECT_GT(on_st.boundary_flips, 0u);
  EXPECT_GT(on_st.boundary_changes, 0u);
  EXPECT_GT(on_q.min_dihedral, off_q.min_dihedral);  // 25.1 and 21.9 deg, 582 flips, when written
  // Every boundary vertex on the sphere (the flips add no node and move none).
  for (std::uint32_t f : on.boundary) EXPECT_LE(sm.q->distance(on.nodes.points.p(f)), 1e-12 * 10);
  // Deterministic whatever the thread count (the sliding runs in colour classes on threads).
  for (unsigned threads : {1u, 2u}) {
    ImproveOptions o;
    o.threads = threads;
    ImproveStats st;
    QualitySummary q;
    const VolumeMesh again = sm.improved(o, st, q);
    EXPECT_EQ(again.tets, on.tets) << threads << " threads";
    EXPECT_EQ(again.nodes.points.xyz, on.nodes.points.xyz) << threads << " threads";
    EXPECT_EQ(again.boundary, on.boundary) << threads << " threads";
  }
}

}  // namespace
}  // namespace kdmesh
