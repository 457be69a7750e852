// kdmesh — several named solids meshed together (mesh_solid on a list of NamedSurface, a job's
// `bodies`; issue 21): each body is its region, in list order; bodies apart or in another's
// void are meshed, touching, crossing or nested-in-material ones are refused naming both and
// a point decided exactly; each body's own surface errors name its own file.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/rng.h"
#include "mesher/mesh_solid.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_bodies.h"
#include "mesher/surface/surface_cells.h"
#include "mesher/tet_quality.h"
#include "mesher/volume/volume_mesh.h"
#include "tests/support/box_surface.h"
#include "tests/support/touching_boxes.h"

namespace kdmesh {
namespace {

using V3 = std::array<double, 3>;

using test::box_surface;

/// Two shells in one surface (`inner` is then a void of `outer`'s solid).
SurfaceMesh with_void(SurfaceMesh outer, const SurfaceMesh& inner) {
  const std::uint32_t off = std::uint32_t(outer.points.size());
  outer.points.xyz.insert(outer.points.xyz.end(), inner.points.xyz.begin(), inner.points.xyz.end());
  for (std::uint32_t v : inner.tris) outer.tris.push_back(v + off);
  return outer;
}

MeshParams params(double size) {
  MeshParams p;
  p.name = "assembly";
  p.sizing.max_size = size;
  p.sizing.min_size = size / 1000;
  return p;
}

std::vector<NamedSurface> two(const std::string& a, SurfaceMesh sa, const std::string& b, SurfaceMesh sb) {
  std::vector<NamedSurface> v;
  v.push_back({a, a + ".stl", std::move(sa)});
  v.push_back({b, b + ".stl", std::move(sb)});
  return v;
}

V3 centroid(const VolumeMesh& m, std::size_t t) {
  V3 c{0, 0, 0};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) c[k] += m.nodes.points.p(m.tets[4 * t + i])[k] / 4;
  return c;
}

bool inside(const V3& p, const V3& lo, const V3& hi) {
  for (int k = 0; k < 3; ++k)
    if (p[k] < lo[k] || p[k] > hi[k]) return false;
  return true;
}

/// The contact error of meshing `bodies`, which must be one.
BodyContactError contact_error(std::vector<NamedSurface> bodies) {
  try {
    mesh_solid(std::move(bodies), params(0.3));
  } catch (const BodyContactError& e) {
    return e;
  }
  ADD_FAILURE() << "no BodyContactError";
  return BodyContactError("none", {}, {0, 0}, {"", ""}, {0, 0, 0});
}

// "right" is listed first: the regions follow the list, not the geometry or the file order of
// the solids; the report and the FE volume groups carry the names.
TEST(MeshBodies, EachBodyIsItsRegionInListOrder) {
  MeshParams p = params(0.25);
  p.fe_groups = true;
  const MeshResult r = mesh_solid(two("right", box_surface({2, 0, 0}, {3, 1, 1}), "left", box_surface({0, 0, 0}, {1, 1, 1})), p);
  const VolumeMesh& m = r.mesh;
  ASSERT_EQ(r.report.bodies.size(), 2u);
  std::size_t in[2] = {0, 0}, wrong = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const std::uint32_t want = centroid(m, t)[0] > 1.5 ? 0 : 1;
    wrong += m.tet_region[t] != want;
    ++in[m.tet_region[t] < 2 ? m.tet_region[t] : 0];
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(in[0], 0u);
  EXPECT_GT(in[1], 0u);
  for (std::uint32_t k = 0; k < 2; ++k) {
    const MeshReport::Body& b = r.report.bodies[k];
    EXPECT_EQ(b.name, k == 0 ? "right" : "left");
    EXPECT_EQ(b.input, b.name + ".stl");
    EXPECT_EQ(b.tets, in[k]);
    EXPECT_NEAR(b.solid_volume, 1.0, 1e-12);
    EXPECT_NEAR(b.mesh_volume, 1.0, 1e-9);  // a box's boundary is recovered exactly
    EXPECT_LE(b.volume_error, 1e-9);
  }
  EXPECT_EQ(r.report.counts.bodies, 2u);
  int volume_groups = 0;
  for (const FeGroup& g : r.fe.groups) {
    if (g.dim != 3) continue;
    ++volume_groups;
    ASSERT_EQ(g.entities.size(), 1u) << g.name;
    EXPECT_EQ(g.name, g.entities[0] == 0 ? "right" : "left");
  }
  EXPECT_EQ(volume_groups, 2);
}

/// The faces between tets of two different regions (vertex ids, sorted, with the two regions),
/// found by matching the tets' faces: what a conforming interface is made of.
struct RegionFace {
  std::array<std::uint32_t, 3> v;
  std::uint32_t ra, rb;
};
std::vector<RegionFace> faces_between_regions(const VolumeMesh& m) {
  std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> f;
  static constexpr int kF[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (std::uint32_t t = 0; t < m.num_tets(); ++t)
    for (const auto& fi : kF) {
      std::array<std::uint32_t, 3> k{m.tets[4 * t + fi[0]], m.tets[4 * t + fi[1]], m.tets[4 * t + fi[2]]};
      std::sort(k.begin(), k.end());
      f.push_back({k, t});
    }
  std::sort(f.begin(), f.end());
  std::vector<RegionFace> out;
  for (std::size_t i = 0; i + 1 < f.size(); ++i)
    if (f[i].first == f[i + 1].first && m.tet_region[f[i].second] != m.tet_region[f[i + 1].second])
      out.push_back({f[i].first, std::min(m.tet_region[f[i].second], m.tet_region[f[i + 1].second]),
                     std::max(m.tet_region[f[i].second], m.tet_region[f[i + 1].second])});
  return out;
}

double area(const VolumeMesh& m, const std::array<std::uint32_t, 3>& v) {
  const double *a = m.nodes.points.p(v[0]), *b = m.nodes.points.p(v[1]), *c = m.nodes.points.p(v[2]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return std::hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]) / 2;
}

// Regression (issue 21): two boxes sharing the face x = 1 (separate points and triangles, as
// separately exported parts are) were refused; now one mesh, each box its region, the nodes of
// x = 1 shared: the faces between the two regions tile exactly the unit square there.
TEST(MeshBodies, TouchingBoxesAreMeshedWithOneConformingInterface) {
  MeshParams p = params(0.25);
  const MeshResult r = mesh_solid(two("a", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({1, 0, 0}, {2, 1, 1})), p);
  const VolumeMesh& m = r.mesh;
  std::size_t wrong = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) wrong += m.tet_region[t] != (centroid(m, t)[0] > 1 ? 1u : 0u);
  EXPECT_EQ(wrong, 0u);
  const std::vector<RegionFace> ifc = faces_between_regions(m);
  ASSERT_FALSE(ifc.empty());
  double sum = 0;
  for (const RegionFace& f : ifc) {
    for (std::uint32_t v : f.v) EXPECT_NEAR(m.nodes.points.p(v)[0], 1.0, 1e-12);
    sum += area(m, f.v);
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
  ASSERT_EQ(r.report.bodies.size(), 2u);
  for (const MeshReport::Body& b : r.report.bodies) EXPECT_LE(b.volume_error, 1e-9) << b.name;
  EXPECT_EQ(r.report.check.interface_faces, ifc.size());
  EXPECT_EQ(r.report.check.straddling_tets, 0u);
  EXPECT_GE(r.report.quality.min_dihedral, 12.0);
  // Each body's dihedral extremes are those of its own tets, exactly (one loop here; the
  // report gathers them on several threads as the quality pass goes).
  std::vector<double> lo(2, 180), hi(2, 0);
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const std::uint32_t* v = &m.tets[4 * t];
    const TetQuality q = tet_quality(m.nodes.points.p(v[0]), m.nodes.points.p(v[1]), m.nodes.points.p(v[2]),
                                     m.nodes.points.p(v[3]));
    lo[m.tet_region[t]] = std::min(lo[m.tet_region[t]], q.min_dihedral);
    hi[m.tet_region[t]] = std::max(hi[m.tet_region[t]], q.max_dihedral);
  }
  for (std::size_t b = 0; b < 2; ++b) {
    EXPECT_EQ(r.report.bodies[b].min_dihedral, lo[b]) << r.report.bodies[b].name;
    EXPECT_EQ(r.report.bodies[b].max_dihedral, hi[b]) << r.report.bodies[b].name;
  }
  EXPECT_EQ(std::min(lo[0], lo[1]), r.report.quality.min_dihedral);
}

// A slab lying across two blocks touches each on part of its bottom face; the three surfaces
// are triangulated independently (their facets do not match): imprinting makes the two
// interfaces, each half a unit square.
TEST(MeshBodies, SlabAcrossTwoBlocksTouchesEachOnPartOfItsFace) {
  std::vector<NamedSurface> b = two("left", box_surface({0, 0, 0}, {1, 1, 1}), "right", box_surface({2, 0, 0}, {3, 1, 1}));
  b.push_back({"slab", "slab.stl", box_surface({0.5, 0, 1}, {2.5, 1, 1.5})});
  const MeshResult r = mesh_solid(std::move(b), params(0.25));
  const VolumeMesh& m = r.mesh;
  std::size_t wrong = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const V3 c = centroid(m, t);
    wrong += m.tet_region[t] != (c[2] > 1 ? 2u : c[0] < 1.5 ? 0u : 1u);
  }
  EXPECT_EQ(wrong, 0u);
  double sum[2] = {0, 0};
  for (const RegionFace& f : faces_between_regions(m)) {
    ASSERT_EQ(f.rb, 2u);
    for (std::uint32_t v : f.v) EXPECT_NEAR(m.nodes.points.p(v)[2], 1.0, 1e-12);
    sum[f.ra] += area(m, f.v);
  }
  EXPECT_NEAR(sum[0], 0.5, 1e-9);
  EXPECT_NEAR(sum[1], 0.5, 1e-9);
  ASSERT_EQ(r.report.bodies.size(), 3u);
  EXPECT_NEAR(r.report.bodies[2].solid_volume, 1.0, 1e-12);
  for (const MeshReport::Body& x : r.report.bodies) EXPECT_LE(x.volume_error, 1e-9) << x.name;
}

// Three bodies whose contacts meet: c stands on a beside b and touches b, its corner on the
// edge of b's footprint. Each pair's faces conform (the faces between regions tile each
// contact exactly).
TEST(MeshBodies, ThreeBodiesWhoseContactsMeetConformOnEach) {
  std::vector<NamedSurface> b = two("a", box_surface({0, 0, 0}, {2, 1, 1}), "b", box_surface({0, 0, 1}, {1, 1, 2}));
  b.push_back({"c", "c.stl", box_surface({1, 0, 1}, {2, 0.25, 2})});
  const MeshResult r = mesh_solid(std::move(b), params(0.25));
  const VolumeMesh& m = r.mesh;
  EXPECT_TRUE(r.report.check.ok());
  std::size_t wrong = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const V3 c = centroid(m, t);
    wrong += m.tet_region[t] != (c[2] < 1 ? 0u : c[0] < 1 ? 1u : 2u);
  }
  EXPECT_EQ(wrong, 0u);
  std::map<std::pair<std::uint32_t, std::uint32_t>, double> sum;
  for (const RegionFace& f : faces_between_regions(m)) sum[{f.ra, f.rb}] += area(m, f.v);
  ASSERT_EQ(sum.size(), 3u);
  EXPECT_NEAR((sum[{0, 1}]), 1.0, 1e-9);
  EXPECT_NEAR((sum[{0, 2}]), 0.25, 1e-9);
  EXPECT_NEAR((sum[{1, 2}]), 0.25, 1e-9);
  for (const MeshReport::Body& x : r.report.bodies) EXPECT_LE(x.volume_error, 1e-9) << x.name;
}

// Regression: imprinting ran passes over every pair in contact until one changed nothing; on
// the paper gear box that second pass over its five pairs took 1.18 s of the 1.32 s of
// imprinting (exact arithmetic on faces that already coincide) and changed nothing. A pair is
// now imprinted again only where the imprint of a third body added a vertex on its contact.
TEST(MeshBodies, RegressionAPairIsImprintedAgainOnlyWhereAThirdAddedAVertexOnItsContact) {
  auto imprints = [](const std::vector<std::array<V3, 2>>& boxes) {
    std::vector<PreparedSurface> parts;
    std::vector<std::string> names, inputs;
    for (const auto& [lo, hi] : boxes) {
      names.push_back(std::string(1, char('a' + names.size())));
      inputs.push_back(names.back() + ".stl");
      parts.push_back(prepare_surface(box_surface(lo, hi), inputs.back()));
    }
    return join_bodies(std::move(parts), names, inputs).interfaces.imprints;
  };
  EXPECT_EQ(imprints({{{{0, 0, 0}, {1, 1, 1}}}, {{{1, 0, 0}, {2, 1, 1}}}}), 1u);
  // The slab gains vertices from the second block away from the first: each pair once.
  EXPECT_EQ(imprints({{{{0, 0, 0}, {1, 1, 1}}}, {{{2, 0, 0}, {3, 1, 1}}}, {{{0.5, 0, 1}, {2.5, 1, 1.5}}}}), 2u);
  // a gains c's corner on the edge of b's footprint (and b gains it from c): a and b again.
  EXPECT_EQ(imprints({{{{0, 0, 0}, {2, 1, 1}}}, {{{0, 0, 1}, {1, 1, 2}}}, {{{1, 0, 1}, {2, 0.25, 2}}}}), 4u);
}

// Faces meant to coincide but off by rounding (as parts exported separately often are): an
// overlap, refused, and the message says how thin it is and what to do.
TEST(MeshBodies, OverlapAsThinAsRoundingIsRefusedWithAHint) {
  const BodyContactError e =
      contact_error(two("a", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({1 - 1e-9, 0.25, 0.25}, {2, 0.75, 0.75})));
  const std::string what = e.what();
  EXPECT_NE(what.find("overlap"), std::string::npos) << what;
  EXPECT_NE(what.find("exactly the same coordinates"), std::string::npos) << what;
}

// Surfaces that coincide facing the same way: both solids on one side (a copy of a body).
TEST(MeshBodies, CoincidingBodiesAreRefusedAsOverlapping) {
  const BodyContactError e = contact_error(two("a", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({0, 0, 0}, {1, 1, 1})));
  EXPECT_NE(std::string(e.what()).find("overlap"), std::string::npos) << e.what();
}

/// The boxes as one surface with internal walls: their facets with the points welded by
/// coordinates, a facet shared by two boxes kept once (the boxes' shared faces are triangulated
/// alike by box_surface).
SurfaceMesh walled(const std::vector<std::pair<V3, V3>>& boxes) {
  SurfaceMesh out;
  std::map<V3, std::uint32_t> id;
  std::map<std::array<std::uint32_t, 3>, std::size_t> seen;  // sorted corners -> facet
  std::vector<std::uint8_t> twice;
  for (const auto& [lo, hi] : boxes) {
    const SurfaceMesh b = box_surface(lo, hi);
    for (std::size_t f = 0; f < b.num_tris(); ++f) {
      std::array<std::uint32_t, 3> v;
      for (int k = 0; k < 3; ++k) {
        const double* p = b.points.p(b.tri(f)[k]);
        auto [it, fresh] = id.emplace(V3{p[0], p[1], p[2]}, std::uint32_t(out.points.size()));
        if (fresh) out.points.push_back(p[0], p[1], p[2]);
        v[std::size_t(k)] = it->second;
      }
      std::array<std::uint32_t, 3> key = v;
      std::sort(key.begin(), key.end());
      if (seen.count(key)) continue;  // the wall, already there from the other box
      seen[key] = out.num_tris();
      out.tris.insert(out.tris.end(), v.begin(), v.end());
    }
  }
  return out;
}

// Internal walls (issue 21): one surface file, non-manifold only where the walls meet, is a
// multi-region domain with one region per cell. Four boxes in a 2 x 2 grid: two walls crossing
// at the line x = 1, y = 1 (four facets around each of its edges, three at the walls' rims).
TEST(MeshBodies, SurfaceWithInternalWallsIsOneRegionPerCell) {
  const SurfaceMesh s = walled({{{0, 0, 0}, {1, 1, 1}}, {{1, 0, 0}, {2, 1, 1}}, {{0, 1, 0}, {1, 2, 1}}, {{1, 1, 0}, {2, 2, 1}}});
  EXPECT_TRUE(has_nonmanifold_edges(s));
  const std::vector<SurfaceMesh> cells = split_cells(s, "walls.stl");
  ASSERT_EQ(cells.size(), 4u);
  MeshParams p = params(0.25);
  p.fe_groups = true;
  p.input = "walls.stl";
  const MeshResult r = mesh_solid(s, p);
  const VolumeMesh& m = r.mesh;
  ASSERT_EQ(r.report.bodies.size(), 4u);
  // each region is one quadrant's box, each box one region
  std::map<std::uint32_t, std::uint32_t> quadrant_of;  // region -> quadrant
  std::size_t wrong = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const V3 c = centroid(m, t);
    const std::uint32_t q = (c[0] > 1 ? 1 : 0) + (c[1] > 1 ? 2 : 0);
    wrong += quadrant_of.emplace(m.tet_region[t], q).first->second != q;
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(quadrant_of.size(), 4u);
  std::set<std::uint32_t> quadrants;
  for (const auto& [r, q] : quadrant_of) quadrants.insert(q);
  EXPECT_EQ(quadrants.size(), 4u);
  double wall = 0;
  for (const RegionFace& f : faces_between_regions(m)) wall += area(m, f.v);
  EXPECT_NEAR(wall, 4.0, 1e-9);  // the two walls, 2 x 1 each
  for (const MeshReport::Body& b : r.report.bodies) {
    EXPECT_EQ(b.name.rfind("region_", 0), 0u) << b.name;
    EXPECT_NEAR(b.mesh_volume, 1.0, 1e-9) << b.name;
  }
  bool named = false;
  for (const FeGroup& g : r.fe.groups) named = named || g.name == "region_1-region_2";
  EXPECT_TRUE(named);
}

// A wall that divides nothing (a fin inside one cell, its far edges free) is an open surface,
// named as such; so is an unwalled surface with an open edge.
TEST(MeshBodies, WallsThatDivideNothingAreRefused) {
  SurfaceMesh s = walled({{{0, 0, 0}, {1, 1, 1}}, {{1, 0, 0}, {2, 1, 1}}});
  s.points.push_back(0.5, 0.5, 0.5);  // a fin from the wall's edge at x = 1, y = 0 into the first box
  const std::uint32_t fin = std::uint32_t(s.points.size() - 1);
  std::uint32_t a = kNoFacet, b = kNoFacet;
  for (std::uint32_t i = 0; i < s.points.size(); ++i) {
    const double* q = s.points.p(i);
    if (q[0] == 1 && q[1] == 0 && q[2] == 0) a = i;
    if (q[0] == 1 && q[1] == 0 && q[2] == 1) b = i;
  }
  s.tris.insert(s.tris.end(), {a, b, fin});
  EXPECT_THROW(split_cells(s, "fin.stl"), SurfaceError);
}

// Touching along one edge only (x = 1, y = 1) is contact too: closed facets.
TEST(MeshBodies, BodiesTouchingAlongAnEdgeAreRefused) {
  const BodyContactError e = contact_error(two("a", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({1, 1, 0}, {2, 2, 1})));
  EXPECT_EQ(e.where()[0], 1.0);
  EXPECT_EQ(e.where()[1], 1.0);
  EXPECT_TRUE(inside(e.where(), {1, 1, 0}, {1, 1, 1}));
}

// A bar pushed halfway into a box: the point lies on both surfaces.
TEST(MeshBodies, CrossingBodiesAreRefusedAtAPointOnBothSurfaces) {
  const V3 blo{0.5, 0.25, 0.25}, bhi{1.5, 0.75, 0.75};
  const BodyContactError e = contact_error(two("box", box_surface({0, 0, 0}, {1, 1, 1}), "bar", box_surface(blo, bhi)));
  const V3 w = e.where();
  EXPECT_TRUE(inside(w, {0, 0, 0}, {1, 1, 1}));
  EXPECT_TRUE(inside(w, blo, bhi));
  auto on_face = [&](V3 lo, V3 hi) {
    for (int k = 0; k < 3; ++k)
      if (w[k] == lo[k] || w[k] == hi[k]) return true;
    return false;
  };
  EXPECT_TRUE(on_face({0, 0, 0}, {1, 1, 1}));
  EXPECT_TRUE(on_face(blo, bhi));
}

// A body wholly inside another's material: its surface would be read as a void of the other;
// refused, at a corner of the inner body.
TEST(MeshBodies, BodyInsideAnothersMaterialIsRefused) {
  const BodyContactError e = contact_error(two("outer", box_surface({0, 0, 0}, {3, 3, 3}), "inner", box_surface({1, 1, 1}, {2, 2, 2})));
  EXPECT_EQ(e.names()[0], "outer");
  EXPECT_EQ(e.names()[1], "inner");
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(e.where()[k] == 1.0 || e.where()[k] == 2.0) << k;
  EXPECT_NE(std::string(e.what()).find("'inner' lies inside the material of 'outer'"), std::string::npos) << e.what();
}

// A core in the void of a hollow body is apart from it: both are meshed, each its region, the
// hollow one without the void.
TEST(MeshBodies, BodyInAnothersVoidIsKept) {
  const SurfaceMesh hollow = with_void(box_surface({0, 0, 0}, {3, 3, 3}), box_surface({0.5, 0.5, 0.5}, {2.5, 2.5, 2.5}));
  const MeshResult r = mesh_solid(two("hollow", hollow, "core", box_surface({1, 1, 1}, {2, 2, 2})), params(0.4));
  ASSERT_EQ(r.report.bodies.size(), 2u);
  EXPECT_NEAR(r.report.bodies[0].solid_volume, 27.0 - 8.0, 1e-9);
  EXPECT_NEAR(r.report.bodies[1].solid_volume, 1.0, 1e-12);
  EXPECT_NEAR(r.report.bodies[0].mesh_volume, 19.0, 1e-8);
  EXPECT_NEAR(r.report.bodies[1].mesh_volume, 1.0, 1e-9);
  std::size_t wrong = 0, in_void = 0;
  for (std::size_t t = 0; t < r.mesh.num_tets(); ++t) {
    const V3 c = centroid(r.mesh, t);
    wrong += r.mesh.tet_region[t] != (inside(c, {1, 1, 1}, {2, 2, 2}) ? 1u : 0u);
    in_void += inside(c, {0.5, 0.5, 0.5}, {2.5, 2.5, 2.5}) && !inside(c, {1, 1, 1}, {2, 2, 2});
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(in_void, 0u);
}

// One body's own defect is reported as for a single surface: its file and its own facet ids.
TEST(MeshBodies, ABodysSurfaceErrorNamesItsOwnInput) {
  SurfaceMesh open = box_surface({2, 0, 0}, {3, 1, 1});
  open.tris.resize(open.tris.size() - 3);  // facet 11 gone: an open surface
  try {
    mesh_solid(two("whole", box_surface({0, 0, 0}, {1, 1, 1}), "open", open), params(0.3));
    FAIL() << "no SurfaceError";
  } catch (const BodyContactError& e) {
    FAIL() << "a contact error for a defect of one body: " << e.what();
  } catch (const SurfaceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("open.stl"), std::string::npos) << what;
    EXPECT_EQ(what.find("whole.stl"), std::string::npos) << what;
    for (std::uint32_t f : e.facets()) EXPECT_LT(f, 11u);  // the body's own ids
  }
}

TEST(MeshBodies, BadBodyListsAreUsageErrors) {
  EXPECT_THROW(mesh_solid(std::vector<NamedSurface>{}, params(0.3)), UsageError);
  EXPECT_THROW(mesh_solid(two("", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({2, 0, 0}, {3, 1, 1})), params(0.3)),
               UsageError);
  EXPECT_THROW(mesh_solid(two("a b", box_surface({0, 0, 0}, {1, 1, 1}), "b", box_surface({2, 0, 0}, {3, 1, 1})), params(0.3)),
               UsageError);
  EXPECT_THROW(mesh_solid(two("a", box_surface({0, 0, 0}, {1, 1, 1}), "a", box_surface({2, 0, 0}, {3, 1, 1})), params(0.3)),
               UsageError);
}

// Regression (paper-size gear box, shaft | gear interface: boundary recovery failed twice with
// outer-boundary faces inside the gear's bore). Interface nodes that are coplanar and
// cocircular up to rounding (a square lattice on a planar interface facet whose coordinates
// are rounded: the cylinders' facet strips) make flat Delaunay tets of four interface nodes.
// They used to be classified outside like flat tets on the outer surface, leaving holes inside
// the solid; they lie inside, on the interface, and are split by a Steiner point on it.
// Here: boxes [0,1]^3 and [1,2]x[0,1]^2, nodes on a lattice of spacing 0.1, those of the
// interface x = 1 one ulp off it at random.
TEST(MeshBodies, FlatTetsOfInterfaceNodesAreSplitNotCarvedOut) {
  const test::TouchingBoxes boxes;
  ASSERT_FALSE(boxes.surface.interfaces.empty());
  const SurfaceQuery& q = boxes.query;
  const Domain domain = boxes.domain();

  NodeSet nodes;
  Rng rng(7);
  const int m = 10;
  const double h = 1.0 / m;
  for (int i = 0; i <= 2 * m; ++i)
    for (int j = 0; j <= m; ++j)
      for (int k = 0; k <= m; ++k) {
        double p[3] = {i * h, j * h, k * h};
        const bool outer = i == 0 || i == 2 * m || j == 0 || j == m || k == 0 || k == m;
        if (outer) {
          double cp[3];
          std::uint32_t facet = kNoFacet;
          q.closest(p, cp, &facet);
          nodes.push_back(p, NodeKind::surface, facet, float(h));
        } else if (i == m) {
          p[0] = std::nextafter(1.0, rng.uniform() < 0.5 ? 0.0 : 2.0);
          nodes.push_back(p, NodeKind::surface, kNoFacet, float(h));
        } else {
          for (double& x : p) x += rng.uniform(-0.15, 0.15) * h;
          nodes.push_back(p, NodeKind::interior, kNoFacet, float(h));
        }
      }
  const VolumeMesh vm = mesh_volume(domain, nodes);
  EXPECT_GT(vm.stats.interface_slivers, 0u);  // the case arose
  const MeshCheck c = check_volume_mesh(vm, domain);
  std::string why;
  for (const std::string& f : c.failures) why += f + "\n";
  EXPECT_TRUE(c.ok()) << why;
  EXPECT_EQ(c.straddling_tets, 0u);
  EXPECT_NEAR(c.mesh_volume, 2.0, 1e-9);
  double min_volume = 1;
  for (std::size_t t = 0; t < vm.num_tets(); ++t) {
    const std::uint32_t* v = &vm.tets[4 * t];
    min_volume = std::min(min_volume, std::abs(volume_length(vm.nodes.points.p(v[0]), vm.nodes.points.p(v[1]),
                                                             vm.nodes.points.p(v[2]), vm.nodes.points.p(v[3]))));
  }
  EXPECT_GT(min_volume, 1e-6);  // no flat tet is left

  // The check finds tets labelled with the other body's region (their centroids' sides are
  // carried between neighbours of one region only): each one relabelled is counted.
  VolumeMesh wrong = vm;
  std::size_t relabelled = 0;
  for (std::size_t t = 0; t < wrong.num_tets(); ++t) {
    const std::uint32_t* v = &wrong.tets[4 * t];
    double x = 0;
    for (int i = 0; i < 4; ++i) x += wrong.nodes.points.p(v[i])[0] / 4;
    if (x > 0.3 && x < 0.4) wrong.tet_region[t] = 1 - wrong.tet_region[t], ++relabelled;
  }
  ASSERT_GT(relabelled, 10u);
  const MeshCheck cw = check_volume_mesh(wrong, domain);
  EXPECT_EQ(cw.straddling_tets, relabelled);
  EXPECT_EQ(cw.outside_tets, 0u);
  EXPECT_FALSE(cw.ok());
}

}  // namespace
}  // namespace kdmesh
