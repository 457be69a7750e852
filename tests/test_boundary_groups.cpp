// kdmesh — tests of surface patches, boundary groups and FE assembly (mesher/fe/boundary_groups.h,
// mesher/fe/fe_assembly.h) on a cube and a finely faceted cylinder meshed by the real pipeline.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "core/error.h"
#include "mesher/fe/boundary_groups.h"
#include "mesher/fe/fe_assembly.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/placement/node_placement.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"

namespace kdmesh {
namespace {

const double kPi = std::acos(-1.0);

double dist(const double* a, const double* b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

double tri_area(const double* a, const double* b, const double* c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return 0.5 * std::hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]);
}

/// The cube [0, L]^3, each face an n x n grid of squares split into two triangles, outward.
SurfaceMesh cube_surface(double L, int n) {
  SurfaceMesh m;
  std::map<std::array<int, 3>, std::uint32_t> ids;
  auto pid = [&](std::array<int, 3> g) {
    auto [it, fresh] = ids.try_emplace(g, std::uint32_t(ids.size()));
    if (fresh) m.points.push_back(g[0] * L / n, g[1] * L / n, g[2] * L / n);
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::array<int, 3> c[4];
          for (auto& x : c) x[axis] = side * n;
          c[0][a1] = i, c[0][a2] = j;
          c[1][a1] = i + 1, c[1][a2] = j;
          c[2][a1] = i + 1, c[2][a2] = j + 1;
          c[3][a1] = i, c[3][a2] = j + 1;
          std::uint32_t v[4];
          for (int q = 0; q < 4; ++q) v[q] = pid(c[q]);
          if (side == 0) std::swap(v[1], v[3]);  // (a1, a2, axis) right-handed: +axis normal
          m.tris.insert(m.tris.end(), {v[0], v[1], v[2], v[0], v[2], v[3]});
        }
    }
  return m;
}

/// A prism over the regular N-gon of circumradius R ("cylinder"), z in [0, H], caps fanned
/// from their centres. Its volume is (N/2) R^2 sin(2 pi / N) H.
SurfaceMesh cylinder_surface(int N, double R, double H) {
  SurfaceMesh m;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < N; ++k)
      m.points.push_back(R * std::cos(2 * kPi * k / N), R * std::sin(2 * kPi * k / N), z * H);
  m.points.push_back(0, 0, 0);
  m.points.push_back(0, 0, H);
  const std::uint32_t c0 = 2 * N, c1 = 2 * N + 1;
  for (std::uint32_t k = 0; k < std::uint32_t(N); ++k) {
    const std::uint32_t b = k, b1 = (k + 1) % N, t = N + k, t1 = N + (k + 1) % N;
    m.tris.insert(m.tris.end(), {b, b1, t1, b, t1, t, c0, b1, b, c1, t, t1});
  }
  return m;
}

/// The pipeline up to the volume mesh, with a uniform size h.
struct Meshed {
  PreparedSurface surface;
  std::unique_ptr<SurfaceQuery> query;
  FeatureEdges features;
  SizingField sizing;
  VolumeMesh mesh;
  SurfacePatches patches;

  Meshed(const SurfaceMesh& raw, const std::string& name, double h, std::vector<SizingZone> zones = {}) {
    surface = prepare_surface(raw, name);
    query = std::make_unique<SurfaceQuery>(surface.mesh);
    features = detect_sharp_edges(surface.mesh, 30);
    SizingOptions so;
    so.max_size = h;
    so.zones = std::move(zones);
    sizing = build_sizing_field(surface.mesh, so);
    mesh = mesh_volume({surface, *query, sizing}, place_nodes({surface, *query, sizing}, features));
    const MeshCheck c = check_volume_mesh(mesh, {surface, *query, sizing});
    std::string f;
    for (const auto& x : c.failures) f += x + "\n";
    EXPECT_TRUE(c.ok()) << f;
    patches = segment_surface(surface.mesh, features);
  }
};

std::string problems(const BoundaryGroups& g) {
  std::string s;
  for (const auto& p : g.problems) s += p + "\n";
  return s;
}

/// Outward unit normal of facet f.
std::array<double, 3> facet_normal(const SurfaceMesh& s, std::size_t f) {
  const double *a = s.points.p(s.tri(f)[0]), *b = s.points.p(s.tri(f)[1]), *c = s.points.p(s.tri(f)[2]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  std::array<double, 3> n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double l = std::hypot(n[0], n[1], n[2]);
  for (double& x : n) x /= l;
  return n;
}

// ---------------------------------------------------------------------------------------------
// A cube with 3 x 3 squares per face: 6 patches of area L^2 (18 facets each), 12 curves of
// length L (3 feature edges each) joining the 8 corners, each between two different patches.
TEST(SegmentSurface, CubeHasSixPatchesTwelveCurves) {
  const double L = 2;
  const PreparedSurface s = prepare_surface(cube_surface(L, 3), "cube");
  const FeatureEdges fe = detect_sharp_edges(s.mesh, 30);
  ASSERT_EQ(fe.corners.size(), 8u);
  const SurfacePatches p = segment_surface(s.mesh, fe);
  ASSERT_EQ(p.num_patches, 6u);
  EXPECT_EQ(p.facet_patch[0], 0u);  // numbered by smallest facet
  std::vector<std::size_t> facets(6, 0);
  for (std::size_t f = 0; f < s.mesh.num_tris(); ++f) {
    ++facets[p.facet_patch[f]];
    // All facets of a patch share its normal (one cube face each).
    const std::size_t first = std::find(p.facet_patch.begin(), p.facet_patch.end(), p.facet_patch[f]) -
                              p.facet_patch.begin();
    const auto n = facet_normal(s.mesh, f), m = facet_normal(s.mesh, first);
    EXPECT_NEAR(n[0] * m[0] + n[1] * m[1] + n[2] * m[2], 1.0, 1e-12);
  }
  for (std::size_t q = 0; q < 6; ++q) {
    EXPECT_EQ(p.patch_planar[q], 1);
    EXPECT_EQ(facets[q], 18u);
    EXPECT_NEAR(p.patch_area[q], L * L, 1e-12);
  }
  ASSERT_EQ(p.num_curves(), 12u);
  std::set<std::uint32_t> corners(fe.corners.begin(), fe.corners.end()), ends;
  for (std::size_t c = 0; c < 12; ++c) {
    EXPECT_FALSE(p.curve_closed[c]);
    EXPECT_EQ(p.curve_size(c), 4u);  // 3 feature edges
    EXPECT_NEAR(p.curve_length[c], L, 1e-12);
    EXPECT_TRUE(corners.count(p.curve(c)[0]));
    EXPECT_TRUE(corners.count(p.curve(c)[3]));
    ends.insert(p.curve(c)[0]), ends.insert(p.curve(c)[3]);
    EXPECT_LT(p.curve_patches[2 * c], p.curve_patches[2 * c + 1]);
  }
  EXPECT_EQ(ends, corners);
  for (std::uint32_t c : p.edge_curve) EXPECT_LT(c, 12u);
  // Deterministic: the same input gives the same numbering.
  const SurfacePatches again = segment_surface(s.mesh, fe);
  EXPECT_EQ(again.facet_patch, p.facet_patch);
  EXPECT_EQ(again.curve_points, p.curve_points);
}

// A 96-gon prism: the side facets meet at 3.75 degrees (no feature), so there are 3 patches
// (side, two caps) and 2 closed curves (the rims) of length 96 * 2R sin(pi/96).
TEST(SegmentSurface, CylinderHasThreePatchesTwoLoops) {
  const int N = 96;
  const double R = 1, H = 1;
  const PreparedSurface s = prepare_surface(cylinder_surface(N, R, H), "cylinder");
  const FeatureEdges fe = detect_sharp_edges(s.mesh, 30);
  const SurfacePatches p = segment_surface(s.mesh, fe);
  ASSERT_EQ(p.num_patches, 3u);
  ASSERT_EQ(p.num_curves(), 2u);
  const double chord = 2 * R * std::sin(kPi / N), cap = N / 2.0 * R * R * std::sin(2 * kPi / N);
  std::vector<double> areas(p.patch_area);
  std::sort(areas.begin(), areas.end());
  EXPECT_NEAR(areas[0], cap, 1e-12);
  EXPECT_NEAR(areas[1], cap, 1e-12);
  EXPECT_NEAR(areas[2], N * chord * H, 1e-12);
  for (std::size_t q = 0; q < 3; ++q)  // the caps are planar, the side is not
    EXPECT_EQ(p.patch_planar[q], std::fabs(p.patch_area[q] - cap) < 1e-12 ? 1 : 0) << "patch " << q;
  for (std::size_t c = 0; c < 2; ++c) {
    EXPECT_TRUE(p.curve_closed[c]);
    EXPECT_EQ(p.curve_size(c), std::size_t(N + 1));
    EXPECT_EQ(p.curve(c)[0], p.curve(c)[N]);
    EXPECT_NEAR(p.curve_length[c], N * chord, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// The meshed cube: every boundary face gets the patch of the cube face it lies in (same
// normal), per-patch area L^2, and the mesh feature edges chain along the 12 edges.
TEST(AssignBoundary, CubePatchesAndCurves) {
  const double L = 1;
  Meshed m(cube_surface(L, 3), "cube", 0.2);
  const BoundaryGroups g = assign_boundary(m.mesh, m.surface.mesh, m.patches, *m.query);
  EXPECT_TRUE(g.ok()) << problems(g);
  const std::size_t nb = m.mesh.boundary.size() / 3;
  ASSERT_EQ(g.face_patch.size(), nb);
  std::vector<double> area(6, 0);
  std::vector<std::array<double, 3>> patch_normal(6);
  for (std::size_t f = 0; f < m.surface.mesh.num_tris(); ++f)
    patch_normal[m.patches.facet_patch[f]] = facet_normal(m.surface.mesh, f);
  for (std::size_t f = 0; f < nb; ++f) {
    ASSERT_LT(g.face_patch[f], 6u);
    const double *a = m.mesh.nodes.points.p(m.mesh.boundary[3 * f]),
                 *b = m.mesh.nodes.points.p(m.mesh.boundary[3 * f + 1]),
                 *c = m.mesh.nodes.points.p(m.mesh.boundary[3 * f + 2]);
    area[g.face_patch[f]] += tri_area(a, b, c);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const auto& pn = patch_normal[g.face_patch[f]];
    EXPECT_NEAR((n[0] * pn[0] + n[1] * pn[1] + n[2] * pn[2]) / std::hypot(n[0], n[1], n[2]), 1.0, 1e-9)
        << "face " << f;
  }
  for (std::size_t q = 0; q < 6; ++q) {
    EXPECT_NEAR(area[q], m.patches.patch_area[q], 1e-12) << "patch " << q;
    EXPECT_GT(g.patch_faces[q], 0u);
  }
  EXPECT_EQ(g.topological_faces + g.geometric_faces, nb);
  // Curves: each one's mesh edges chain from one end corner to the other, lie on it, and
  // sum to its length. Every boundary edge between two patches is one of them.
  ASSERT_EQ(g.edge_curve.size() * 2, g.edges.size());
  std::map<std::uint32_t, std::vector<std::size_t>> by_curve;
  for (std::size_t e = 0; e < g.edge_curve.size(); ++e) by_curve[g.edge_curve[e]].push_back(e);
  ASSERT_EQ(by_curve.size(), 12u);
  const PointSet& P = m.mesh.nodes.points;
  for (const auto& [c, es] : by_curve) {
    const double* c0 = m.surface.mesh.points.p(m.patches.curve(c)[0]);
    const double* c1 = m.surface.mesh.points.p(m.patches.curve(c)[m.patches.curve_size(c) - 1]);
    double len = 0;
    EXPECT_EQ(dist(P.p(g.edges[2 * es.front()]), c0), 0.0);
    EXPECT_EQ(dist(P.p(g.edges[2 * es.back() + 1]), c1), 0.0);
    for (std::size_t k = 0; k < es.size(); ++k) {
      const double *a = P.p(g.edges[2 * es[k]]), *b = P.p(g.edges[2 * es[k] + 1]);
      len += dist(a, b);
      if (k + 1 < es.size()) {
        EXPECT_EQ(g.edges[2 * es[k] + 1], g.edges[2 * es[k + 1]]);
      }
      // On the segment c0 c1: distance to c0 + distance to c1 = L.
      EXPECT_NEAR(dist(a, c0) + dist(a, c1), L, 1e-12);
    }
    EXPECT_NEAR(len, m.patches.curve_length[c], 1e-12);
    EXPECT_NEAR(len, L, 1e-12);
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edge_patches;
  for (std::size_t f = 0; f < nb; ++f)
    for (int k = 0; k < 3; ++k)
      edge_patches[std::minmax(m.mesh.boundary[3 * f + k], m.mesh.boundary[3 * f + (k + 1) % 3])].push_back(
          g.face_patch[f]);
  std::set<std::pair<std::uint32_t, std::uint32_t>> between, features;
  for (const auto& [e, ps] : edge_patches) {
    ASSERT_EQ(ps.size(), 2u);
    if (ps[0] != ps[1]) between.insert(e);
  }
  for (std::size_t e = 0; e < g.edge_curve.size(); ++e) features.insert(std::minmax(g.edges[2 * e], g.edges[2 * e + 1]));
  EXPECT_EQ(between, features);
}

// The cylinder: a face with all nodes at z = 0 (z = H) lies in the bottom (top) cap's plane
// and belongs to it, every other face to the side. Faces whose three nodes are all on a rim
// need the geometric decision; they must still come out right.
TEST(AssignBoundary, CylinderFacesByGeometry) {
  const double H = 1;
  Meshed m(cylinder_surface(96, 1.0, H), "cylinder", 0.25);
  const BoundaryGroups g = assign_boundary(m.mesh, m.surface.mesh, m.patches, *m.query);
  EXPECT_TRUE(g.ok()) << problems(g);
  // Which patch is which: by a facet of each.
  std::uint32_t bottom = kNoEntity, top = kNoEntity, side = kNoEntity;
  for (std::size_t f = 0; f < m.surface.mesh.num_tris(); ++f) {
    const auto n = facet_normal(m.surface.mesh, f);
    (n[2] < -0.5 ? bottom : n[2] > 0.5 ? top : side) = m.patches.facet_patch[f];
  }
  const PointSet& P = m.mesh.nodes.points;
  for (std::size_t f = 0; f < g.face_patch.size(); ++f) {
    const std::uint32_t* v = &m.mesh.boundary[3 * f];
    const bool z0 = P.p(v[0])[2] == 0 && P.p(v[1])[2] == 0 && P.p(v[2])[2] == 0;
    const bool zH = P.p(v[0])[2] == H && P.p(v[1])[2] == H && P.p(v[2])[2] == H;
    EXPECT_EQ(g.face_patch[f], z0 ? bottom : zH ? top : side) << "face " << f;
  }
  // Each rim: a closed chain of mesh edges, each node in two of them, all on the rim's plane.
  for (std::uint32_t c = 0; c < 2; ++c) {
    std::map<std::uint32_t, int> degree;
    double len = 0;
    const double z = m.surface.mesh.points.p(m.patches.curve(c)[0])[2];
    for (std::size_t e = 0; e < g.edge_curve.size(); ++e)
      if (g.edge_curve[e] == c) {
        ++degree[g.edges[2 * e]], ++degree[g.edges[2 * e + 1]];
        len += dist(P.p(g.edges[2 * e]), P.p(g.edges[2 * e + 1]));
        EXPECT_EQ(P.p(g.edges[2 * e])[2], z);
      }
    EXPECT_GE(degree.size(), 3u);
    for (const auto& [v, d] : degree) EXPECT_EQ(d, 2) << "node " << v;
    EXPECT_LE(len, m.patches.curve_length[c]);
    EXPECT_GT(len, 0.98 * m.patches.curve_length[c]);  // chords of ~h on a unit circle
  }
}

/// A facet of `s` having point v as a corner.
std::uint32_t facet_with(const SurfaceMesh& s, std::uint32_t v) {
  for (std::size_t f = 0; f < s.num_tris(); ++f)
    for (int k = 0; k < 3; ++k)
      if (s.tri(f)[k] == v) return std::uint32_t(f);
  return kNoFacet;
}

// Hand-made boundaries: a cap face whose three nodes are all on the bottom rim (decided by
// distance: 0 to the cap, > 0 to the side), a face spanning both rims (decided by topology:
// only the side touches both rims), and, on the cube, a flat face lying along an edge (its
// distance to both patches is 0): reported as ambiguous, not guessed silently. A node given
// no facet is located by the surface query.
TEST(AssignBoundary, GeometricAndAmbiguousDecisions) {
  const int N = 96;
  const PreparedSurface s = prepare_surface(cylinder_surface(N, 1, 1), "cylinder");
  const SurfaceQuery q(s.mesh);
  const SurfacePatches p = segment_surface(s.mesh, detect_sharp_edges(s.mesh, 30));
  VolumeMesh vm;
  for (std::uint32_t v : {0u, 10u, 20u, std::uint32_t(N + 5)})
    vm.nodes.push_back(s.mesh.points.p(v), NodeKind::edge, v == 0 ? kNoFacet : facet_with(s.mesh, v), 0.1f);
  vm.boundary = {0, 2, 1,   // bottom cap, normal -z
                 0, 1, 3};  // side
  const BoundaryGroups g = assign_boundary(vm, s.mesh, p, q);
  std::uint32_t bottom = kNoEntity, side = kNoEntity;
  for (std::size_t f = 0; f < s.mesh.num_tris(); ++f) {
    const auto n = facet_normal(s.mesh, f);
    if (n[2] < -0.5) bottom = p.facet_patch[f];
    if (std::fabs(n[2]) < 0.5) side = p.facet_patch[f];
  }
  EXPECT_EQ(g.face_patch, (std::vector<std::uint32_t>{bottom, side}));
  EXPECT_EQ(g.geometric_faces, 1u);
  EXPECT_EQ(g.topological_faces, 1u);
  EXPECT_TRUE(g.ambiguous_faces.empty()) << problems(g);
  EXPECT_EQ(g.relocated_nodes, 1u);
  // The bottom rim's nodes 0, 10, 20 are joined all around by the cap face's edges; the top
  // rim has one node, hence no edge, and the top cap no face: reported, not accepted.
  EXPECT_EQ(g.missing_curve_edges, 0u);
  EXPECT_EQ(g.curve_edges[0] + g.curve_edges[1], 3u);
  EXPECT_EQ(g.empty_curves, 1u);
  EXPECT_EQ(g.empty_patches, 1u);
  EXPECT_FALSE(g.ok());

  const PreparedSurface cube = prepare_surface(cube_surface(1, 2), "cube");
  const SurfaceQuery cq(cube.mesh);
  const SurfacePatches cp = segment_surface(cube.mesh, detect_sharp_edges(cube.mesh, 30));
  VolumeMesh flat;
  const double xs[3][3] = {{0, 0, 0}, {0.5, 0, 0}, {1, 0, 0}};
  for (const auto& x : xs) {
    double c[3];
    std::uint32_t f = kNoFacet;
    cq.closest(x, c, &f);
    flat.nodes.push_back(x, NodeKind::edge, f, 0.1f);
  }
  flat.boundary = {0, 1, 2};
  const BoundaryGroups h = assign_boundary(flat, cube.mesh, cp, cq);
  EXPECT_EQ(h.ambiguous_faces, std::vector<std::uint32_t>{0});
  ASSERT_FALSE(h.problems.empty());
  EXPECT_NE(h.problems[0].find("boundary face 0 at (0.5, 0, 0): patch"), std::string::npos) << h.problems[0];
  EXPECT_NE(h.problems[0].find("is not certain"), std::string::npos) << h.problems[0];
}

// ---------------------------------------------------------------------------------------------
// Regression (gear box, size 3): edge sampling skipped a vertex V of a faceted circle (no
// corner there) and boundary recovery put a crease Steiner point S on the feature edge next to
// V, 1e-7 from it. S's facet was a sliver of the fanned face: its diagonal from V runs at
// pi/N to the feature edge, so S is within the location tolerance (1e-9 of the facet's longest
// edge) of the diagonal too. Taking the first edge within tolerance put S inside the face's
// patch: the curve was reported missing between the sampled nodes, the edges through S as
// stray, and the side faces at S as uncertain. The surface: a 64-gon prism of radius 40 whose
// top cap is fanned from rim vertex t0 (slivers at t0), bottom cap fanned from its centre.
// The boundary: the top ring t1 .. t(N-1), S' (1e-7 from t0 towards t(N-1)), S (1e-7 from t0
// towards t1) - t0 itself skipped, one of S, S' meets the diagonal first in its facet whatever
// the winding -, the bottom ring b0 .. b(N-1), the caps fanned from their centres.
TEST(AssignBoundary, SteinerNodeOnFeatureCurveJoinsTheCurve) {
  const int N = 64;
  const double R = 40, H = 10, delta = 1e-7;
  SurfaceMesh raw;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < N; ++k)
      raw.points.push_back(R * std::cos(2 * kPi * k / N), R * std::sin(2 * kPi * k / N), z * H);
  raw.points.push_back(0, 0, 0);
  const std::uint32_t c0 = 2 * N;
  auto T = [&](int k) { return std::uint32_t(N + (k % N)); };
  for (std::uint32_t k = 0; k < std::uint32_t(N); ++k) {
    const std::uint32_t b = k, b1 = (k + 1) % N;
    raw.tris.insert(raw.tris.end(), {b, b1, T(k + 1), b, T(k + 1), T(k), c0, b1, b});
  }
  for (int k = 1; k + 1 < N; ++k) raw.tris.insert(raw.tris.end(), {T(0), T(k), T(k + 1)});  // +z
  const PreparedSurface s = prepare_surface(raw, "fanned prism");
  const SurfaceQuery q(s.mesh);
  const SurfacePatches p = segment_surface(s.mesh, detect_sharp_edges(s.mesh, 30));
  ASSERT_EQ(p.num_patches, 3u);
  ASSERT_EQ(p.num_curves(), 2u);  // the rims, closed; t0 is no corner (5.625 degree bend)
  // Raw point i in the prepared surface (found by its coordinates); facet with corners a, b, c.
  auto pid = [&](std::uint32_t i) {
    for (std::uint32_t j = 0; j < s.mesh.points.size(); ++j)
      if (dist(s.mesh.points.p(j), raw.points.p(i)) == 0) return j;
    ADD_FAILURE() << "point " << i << " lost";
    return 0u;
  };
  auto facet_of = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    const std::set<std::uint32_t> want{pid(a), pid(b), pid(c)};
    for (std::uint32_t f = 0; f < s.mesh.num_tris(); ++f)
      if (std::set<std::uint32_t>(s.mesh.tri(f), s.mesh.tri(f) + 3) == want) return f;
    ADD_FAILURE() << "no facet " << a << " " << b << " " << c;
    return kNoFacet;
  };
  const double* t0 = raw.points.p(T(0));
  auto toward = [&](std::uint32_t v, double* out) {
    const double* x = raw.points.p(v);
    const double l = dist(t0, x);
    for (int k = 0; k < 3; ++k) out[k] = t0[k] + delta / l * (x[k] - t0[k]);
  };
  double S[3], S2[3];
  toward(T(1), S);
  toward(T(N - 1), S2);
  {  // The fixture's premise: S is 1e-7 from t0 yet within 1e-9 * (longest edge) of the diagonal.
    const double* t2 = raw.points.p(T(2));
    const double longest = dist(t0, t2);  // of facet (t0, t1, t2)
    const double u[3] = {t2[0] - t0[0], t2[1] - t0[1], t2[2] - t0[2]};
    const double w[3] = {S[0] - t0[0], S[1] - t0[1], S[2] - t0[2]};
    const double cr = std::hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]);
    EXPECT_LT(cr / longest, 1e-9 * longest);
    EXPECT_GT(dist(S, t0), 2e-9 * longest);
  }
  auto build = [&](const double* s_pos) {
    VolumeMesh vm;
    // Nodes: top ring 0 .. N-2 = t1 .. t(N-1), N-1 = S', N = S; bottom ring N+1+k = bk; then
    // the top centre 2N+1 and the bottom centre 2N+2. Only S and S' are given their facet (the
    // slivers at t0); the others are located by the surface query.
    for (int k = 1; k < N; ++k) vm.nodes.push_back(raw.points.p(T(k)), NodeKind::edge, kNoFacet, 1.f);
    vm.nodes.push_back(S2, NodeKind::edge, facet_of(T(0), T(N - 2), T(N - 1)), 1.f);
    vm.nodes.push_back(s_pos, NodeKind::edge, facet_of(T(0), T(1), T(2)), 1.f);
    for (int k = 0; k < N; ++k) vm.nodes.push_back(raw.points.p(k), NodeKind::edge, kNoFacet, 1.f);
    const double ct[3] = {0, 0, H}, cb[3] = {0, 0, 0};
    vm.nodes.push_back(ct, NodeKind::surface, kNoFacet, 1.f);
    vm.nodes.push_back(cb, NodeKind::corner, kNoFacet, 1.f);
    const std::uint32_t n = N + 1, Ct = 2 * N + 1, Cb = 2 * N + 2;
    auto b = [&](int k) { return std::uint32_t(N + 1 + (k % N)); };
    for (std::uint32_t i = 0; i < n; ++i) vm.boundary.insert(vm.boundary.end(), {Ct, i, (i + 1) % n});
    for (int k = 0; k < N; ++k) vm.boundary.insert(vm.boundary.end(), {Cb, b(k + 1), b(k)});
    for (int k = 1; k + 1 < N; ++k)  // quads (tk, tk+1) over (bk, bk+1); node of tk is k-1
      vm.boundary.insert(vm.boundary.end(), {b(k), b(k + 1), std::uint32_t(k), b(k), std::uint32_t(k), std::uint32_t(k - 1)});
    vm.boundary.insert(vm.boundary.end(), {b(N - 1), b(0), N - 1, b(N - 1), N - 1, N - 2,  // t(N-1) S'
                                           b(0), N, N - 1,                                  // S' S
                                           b(0), b(1), 0, b(0), 0, N});                     // S t1
    return vm;
  };
  std::uint32_t top = kNoEntity, bottom = kNoEntity, side = kNoEntity;
  for (std::size_t f = 0; f < s.mesh.num_tris(); ++f) {
    const auto nf = facet_normal(s.mesh, f);
    (nf[2] > 0.5 ? top : nf[2] < -0.5 ? bottom : side) = p.facet_patch[f];
  }
  const VolumeMesh vm = build(S);
  const BoundaryGroups g = assign_boundary(vm, s.mesh, p, q);
  EXPECT_TRUE(g.ok()) << problems(g);
  const std::size_t nb = vm.boundary.size() / 3;
  ASSERT_EQ(g.face_patch.size(), nb);
  const PointSet& P = vm.nodes.points;
  for (std::size_t f = 0; f < nb; ++f) {  // all nodes at z = H: top; at z = 0: bottom; else side
    int at_top = 0, at_bottom = 0;
    for (int k = 0; k < 3; ++k) {
      at_top += P.p(vm.boundary[3 * f + k])[2] == H;
      at_bottom += P.p(vm.boundary[3 * f + k])[2] == 0;
    }
    EXPECT_EQ(g.face_patch[f], at_top == 3 ? top : at_bottom == 3 ? bottom : side) << "face " << f;
  }
  // The top rim's mesh edges are the N + 1 edges of the top ring, through S' and S; the
  // bottom rim's the N edges of the bottom ring.
  std::set<std::pair<std::uint32_t, std::uint32_t>> top_edges, want;
  std::size_t bottom_edges = 0;
  for (std::size_t e = 0; e < g.edge_curve.size(); ++e) {
    const double z = P.p(g.edges[2 * e])[2];
    EXPECT_EQ(P.p(g.edges[2 * e + 1])[2], z);
    if (z == H) top_edges.insert(std::minmax(g.edges[2 * e], g.edges[2 * e + 1]));
    else ++bottom_edges;
  }
  for (std::uint32_t i = 0; i < N + 1; ++i) want.insert(std::minmax(i, (i + 1) % (N + 1)));
  EXPECT_EQ(top_edges, want);
  EXPECT_EQ(bottom_edges, std::size_t(N));

  // Still strict: S moved 1e-6 into the cap (off the rim, far beyond the tolerance) leaves the
  // top rim's nodes S' and t1 consecutive and not joined by a boundary edge.
  double off[3] = {S[0] - 1e-6 * t0[0] / R, S[1] - 1e-6 * t0[1] / R, S[2]};
  const BoundaryGroups h = assign_boundary(build(off), s.mesh, p, q);
  EXPECT_FALSE(h.ok());
  EXPECT_EQ(h.missing_curve_edges, 1u) << problems(h);
  EXPECT_GT(h.stray_patch_edges, 0u) << problems(h);
  bool named = false;
  for (const std::string& line : h.problems)
    named |= line.find("consecutive nodes " + std::to_string(N - 1)) != std::string::npos &&
             line.find(" and 0 (") != std::string::npos;
  EXPECT_TRUE(named) << problems(h);
}

// ---------------------------------------------------------------------------------------------
// Named groups on the unit cube, each checked against what the geometry says.
class CubeGroups : public ::testing::Test {
 protected:
  void SetUp() override {
    s = prepare_surface(cube_surface(1, 2), "cube");
    p = segment_surface(s.mesh, detect_sharp_edges(s.mesh, 30));
    for (std::size_t f = 0; f < s.mesh.num_tris(); ++f) {
      const auto n = facet_normal(s.mesh, f);
      if (n[2] > 0.5) top = p.facet_patch[f];
    }
  }
  /// The curves whose both end points satisfy `pred`.
  template <class Pred>
  std::vector<std::uint32_t> curves_with_ends(Pred pred) const {
    std::vector<std::uint32_t> out;
    for (std::uint32_t c = 0; c < p.num_curves(); ++c)
      if (pred(s.mesh.points.p(p.curve(c)[0])) && pred(s.mesh.points.p(p.curve(c)[p.curve_size(c) - 1])))
        out.push_back(c);
    return out;
  }
  const FeGroup& find(const std::vector<FeGroup>& gs, const std::string& name) const {
    for (const FeGroup& g : gs)
      if (g.name == name) return g;
    ADD_FAILURE() << "no group " << name;
    return gs.front();
  }
  PreparedSurface s;
  SurfacePatches p;
  std::uint32_t top = kNoEntity;
};

TEST_F(CubeGroups, ByZonePointAndBox) {
  std::vector<SizingZone> zones(3);
  zones[0].kind = SizingZone::Kind::polyline, zones[0].name = "fixed", zones[0].size = 0.05;
  zones[0].coords = {0, 0, 0, 1, 0, 0};
  zones[1].kind = SizingZone::Kind::segment, zones[1].name = "fixed", zones[1].size = 0.05;
  zones[1].coords = {0, 1, 1, 0, 1, 0};  // reversed direction: still that edge
  zones[2].kind = SizingZone::Kind::plane, zones[2].name = "lid", zones[2].size = 0.05;
  zones[2].coords = {0.3, 0.3, 1, 0, 0, 2};
  std::vector<GroupSpec> specs(6);
  specs[0].name = "fixed", specs[0].by = GroupSpec::Select::zone, specs[0].zone = "fixed";
  specs[1].name = "lid", specs[1].by = GroupSpec::Select::zone, specs[1].zone = "lid";
  specs[2].name = "load", specs[2].dim = 2, specs[2].by = GroupSpec::Select::point;
  specs[2].point[0] = 0.5, specs[2].point[1] = 0.4, specs[2].point[2] = 1.3;
  specs[3].name = "x_edge", specs[3].dim = 1, specs[3].by = GroupSpec::Select::point;
  specs[3].point[0] = 0.5, specs[3].point[1] = -0.1, specs[3].point[2] = -0.2;
  specs[4].name = "upper", specs[4].dim = 2, specs[4].by = GroupSpec::Select::box;
  specs[5].name = "upper", specs[5].dim = 1, specs[5].by = GroupSpec::Select::box;  // same name, other dim
  for (int k : {4, 5}) {
    const double lo[3] = {-0.1, -0.1, 0.9}, hi[3] = {1.1, 1.1, 1.1};
    std::copy(lo, lo + 3, specs[k].box_min), std::copy(hi, hi + 3, specs[k].box_max);
  }
  GroupOptions o;
  o.patch_groups = o.curve_groups = true;
  const std::vector<FeGroup> gs = make_groups(specs, s.mesh, p, zones, 1, o);
  ASSERT_EQ(gs.size(), 1 + specs.size() + 6 + 12);
  EXPECT_EQ(gs[0].name, "body_1");
  EXPECT_EQ(gs[0].dim, 3);
  EXPECT_EQ(gs[0].entities, std::vector<std::uint32_t>{0});
  // fixed: the edge y = z = 0 and the edge x = 0, y = 1 (dim 1 from the zone types).
  auto on = [](double x, double y, double z) {
    return [=](const double* q) {
      return (std::isnan(x) || q[0] == x) && (std::isnan(y) || q[1] == y) && (std::isnan(z) || q[2] == z);
    };
  };
  const double any = std::nan("");
  std::vector<std::uint32_t> expect = curves_with_ends(on(any, 0, 0));
  const auto e2 = curves_with_ends(on(0, 1, any));
  expect.insert(expect.end(), e2.begin(), e2.end());
  std::sort(expect.begin(), expect.end());
  ASSERT_EQ(expect.size(), 2u);
  EXPECT_EQ(find(gs, "fixed").dim, 1);
  EXPECT_EQ(find(gs, "fixed").entities, expect);
  EXPECT_EQ(find(gs, "lid").dim, 2);
  EXPECT_EQ(find(gs, "lid").entities, std::vector<std::uint32_t>{top});
  EXPECT_EQ(find(gs, "load").entities, std::vector<std::uint32_t>{top});
  EXPECT_EQ(find(gs, "x_edge").entities, curves_with_ends(on(any, 0, 0)));
  EXPECT_EQ(gs[5].name, "upper");
  EXPECT_EQ(gs[5].entities, std::vector<std::uint32_t>{top});
  EXPECT_EQ(gs[6].entities, curves_with_ends(on(any, any, 1)));
  EXPECT_EQ(gs[6].entities.size(), 4u);
  EXPECT_EQ(gs[7].name, "patch_1");
  EXPECT_EQ(gs.back().name, "curve_12");
  EXPECT_EQ(gs.back().entities, std::vector<std::uint32_t>{11});
}

TEST_F(CubeGroups, ErrorsNameTheSpecAndItsOrigin) {
  std::vector<SizingZone> zones(1);
  zones[0].kind = SizingZone::Kind::segment, zones[0].name = "diag", zones[0].size = 0.05;
  zones[0].coords = {0, 0, 0, 1, 1, 1};  // through the solid: lies on no curve
  auto fails = [&](GroupSpec g, const std::string& expect) {
    g.origin = "job.yaml:7";
    try {
      make_groups({g}, s.mesh, p, zones, 1);
      ADD_FAILURE() << "expected a UsageError mentioning " << expect;
    } catch (const UsageError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("group '" + g.name + "'"), std::string::npos) << w;
      EXPECT_NE(w.find("job.yaml:7"), std::string::npos) << w;
      EXPECT_NE(w.find(expect), std::string::npos) << w;
    }
  };
  GroupSpec g;
  g.name = "nothing", g.by = GroupSpec::Select::zone, g.zone = "diag";
  fails(g, "selects no feature curve");
  g.zone = "dag";
  fails(g, "no sizing zone is named 'dag' (named zones: diag)");
  g.by = GroupSpec::Select::box, g.dim = 2;
  g.box_min[0] = g.box_min[1] = g.box_min[2] = 0.2, g.box_max[0] = g.box_max[1] = g.box_max[2] = 0.8;
  fails(g, "selects no surface patch");
  g.by = GroupSpec::Select::point;
  g.point[0] = 1.5, g.point[1] = 1.5, g.point[2] = 0.5;  // as near to x = 1 as to y = 1
  fails(g, "equally near");
  g.dim = 3;
  fails(g, "dim must be 1");
  g.dim = 2, g.name = "bad name";
  g.point[1] = 0.5;
  fails(g, "[A-Za-z0-9_-]");
  g.name = "body_1", g.dim = 2;  // a dim 2 group may share the name of the dim 3 body group
  EXPECT_EQ(make_groups({g}, s.mesh, p, zones, 1).size(), 2u);
  try {
    make_groups({g, g}, s.mesh, p, zones, 1);
    ADD_FAILURE() << "duplicate name accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("already exists"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// The shape functions: straight edges give det J = 6 V everywhere; moving the mid-node of
// edge (0,1) of the unit corner tet by d along e1 gives det J = 1 + 4 d (L0 - L1), so
// 1 + 4d at corner 0, 1 - 4d at corner 1 and the volume unchanged (1/6).
TEST(Quadratic, JacobianOfTheUnitTet) {
  double pts[10][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int e[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int k = 0; k < 6; ++k)
    for (int q = 0; q < 3; ++q) pts[4 + k][q] = (pts[e[k][0]][q] + pts[e[k][1]][q]) / 2;
  const double* x[10];
  for (int i = 0; i < 10; ++i) x[i] = pts[i];
  const double L0[4] = {1, 0, 0, 0}, L1[4] = {0, 1, 0, 0}, Lg[4] = {0.1, 0.2, 0.3, 0.4};
  EXPECT_NEAR(quadratic_tet_jacobian(x, Lg), 1.0, 1e-15);
  EXPECT_NEAR(quadratic_tet_min_jacobian_ratio(x), 1.0, 1e-15);
  EXPECT_NEAR(quadratic_tet_volume(x), 1.0 / 6, 1e-16);
  for (double d : {0.1, -0.2, 0.3}) {
    pts[4][0] = 0.5 + d;
    EXPECT_NEAR(quadratic_tet_jacobian(x, L0), 1 + 4 * d, 1e-14);
    EXPECT_NEAR(quadratic_tet_jacobian(x, L1), 1 - 4 * d, 1e-14);
    EXPECT_NEAR(quadratic_tet_jacobian(x, Lg), 1 + 4 * d * (0.1 - 0.2), 1e-14);
    EXPECT_NEAR(quadratic_tet_min_jacobian_ratio(x), 1 - 4 * std::fabs(d), 1e-14);
    EXPECT_NEAR(quadratic_tet_volume(x), 1.0 / 6, 1e-15);
  }
  // Moving it by w = -0.1 e2 (out of face (0,1,3), y = 0) displaces that face by 4 L0 L1 w:
  // the volume grows by 0.1 * integral of 4 L0 L1 over the face (area 1/2) = 0.4 * 2 (1/2) / 4!
  // = 1/60. Directly: det J = 1 + 0.4 L1, whose integral is 1/6 + 0.4 / 24.
  pts[4][0] = 0.5, pts[4][1] = -0.1;
  EXPECT_NEAR(quadratic_tet_jacobian(x, Lg), 1 + 0.4 * Lg[1], 1e-15);
  EXPECT_NEAR(quadratic_tet_volume(x), 1.0 / 6 + 1.0 / 60, 1e-15);
}

/// For each mesh edge (a < b), the mid-node id the order-2 tets give it; and checks that faces
/// and edges use the same ids.
std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid_nodes(const FeMesh& fe) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
  const int te[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (std::size_t t = 0; t < fe.num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      const auto key = std::minmax(fe.tets[10 * t + te[k][0]], fe.tets[10 * t + te[k][1]]);
      auto [it, fresh] = mid.try_emplace(key, fe.tets[10 * t + 4 + k]);
      EXPECT_EQ(it->second, fe.tets[10 * t + 4 + k]) << "edge shared with another mid-node";
    }
  for (std::size_t f = 0; f < fe.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(mid.at(std::minmax(fe.faces[6 * f + k], fe.faces[6 * f + (k + 1) % 3])), fe.faces[6 * f + 3 + k]);
  for (std::size_t e = 0; e < fe.num_edges(); ++e)
    EXPECT_EQ(mid.at(std::minmax(fe.edges[3 * e], fe.edges[3 * e + 1])), fe.edges[3 * e + 2]);
  return mid;
}

// Flat faces: every mid-edge node is at its edge's midpoint; the volume stays L^3 and det J
// is 6 V at every sample point. Mid-nodes: one per edge, numbered after the corners by edge.
TEST(Quadratic, CubeMidNodesAreMidpoints) {
  Meshed m(cube_surface(1, 2), "cube", 0.25);
  const BoundaryGroups g = assign_boundary(m.mesh, m.surface.mesh, m.patches, *m.query);
  ASSERT_TRUE(g.ok()) << problems(g);
  FeMesh fe = make_fe_mesh(m.mesh, g, make_groups({}, m.surface.mesh, m.patches, {}, 1));
  EXPECT_EQ(fe.num_tets(), m.mesh.num_tets());
  EXPECT_EQ(fe.num_faces(), m.mesh.boundary.size() / 3);
  EXPECT_NEAR(fe_mesh_volume(fe), 1.0, 1e-12);
  const std::size_t n0 = fe.points.size();
  const QuadraticStats st = make_quadratic(fe, m.surface.mesh, *m.query, m.patches);
  ASSERT_EQ(fe.order, 2);
  const auto mid = mid_nodes(fe);
  EXPECT_EQ(mid.size(), st.mid_nodes);
  EXPECT_EQ(fe.points.size(), n0 + mid.size());
  std::uint32_t expect_id = std::uint32_t(n0);
  for (const auto& [e, id] : mid) {  // std::map iterates edges in (a, b) order
    EXPECT_EQ(id, expect_id++);
    for (int q = 0; q < 3; ++q)
      EXPECT_NEAR(fe.points.p(id)[q], (fe.points.p(e.first)[q] + fe.points.p(e.second)[q]) / 2, 1e-15);
  }
  EXPECT_EQ(st.far_projections, 0u);
  EXPECT_EQ(st.straightened_elements, 0u);
  EXPECT_GT(st.curve_mid_nodes, 0u);
  EXPECT_GT(st.patch_mid_nodes, 0u);
  EXPECT_NEAR(st.min_jacobian_ratio, 1.0, 1e-9);
  EXPECT_NEAR(fe_mesh_volume(fe), 1.0, 1e-12);
  EXPECT_THROW(make_quadratic(fe, m.surface.mesh, *m.query, m.patches), UsageError);
}

// The cylinder: boundary mid-nodes go onto the input surface (rim ones onto the rim polylines,
// cap ones stay at the midpoints), every element keeps det J > 0 at its corners and Gauss
// points, and the volume gets closer to the faceted solid's than the linear mesh's.
TEST(Quadratic, CylinderMidNodesOnTheSurface) {
  const int N = 96;
  const double R = 1, H = 1, true_volume = N / 2.0 * R * R * std::sin(2 * kPi / N) * H;
  Meshed m(cylinder_surface(N, R, H), "cylinder", 0.25);
  const BoundaryGroups g = assign_boundary(m.mesh, m.surface.mesh, m.patches, *m.query);
  ASSERT_TRUE(g.ok()) << problems(g);
  FeMesh fe = make_fe_mesh(m.mesh, g, {});
  const double linear = fe_mesh_volume(fe);
  FeMesh straight = fe;
  QuadraticOptions so;
  so.curved = false;
  make_quadratic(straight, m.surface.mesh, *m.query, m.patches, so);
  EXPECT_NEAR(fe_mesh_volume(straight), linear, 1e-12);
  const QuadraticStats st = make_quadratic(fe, m.surface.mesh, *m.query, m.patches);
  const auto mid = mid_nodes(fe);
  EXPECT_GT(st.moved_mid_nodes, 0u);
  EXPECT_EQ(st.invalid_linear, 0u);
  // Boundary mid-nodes on the surface, except those the validity fallback pulled back towards
  // their midpoints; cap ones at their midpoints.
  std::size_t off_surface = 0;
  std::set<std::uint32_t> boundary_mid;
  for (std::size_t f = 0; f < fe.num_faces(); ++f)
    for (int k = 3; k < 6; ++k) boundary_mid.insert(fe.faces[6 * f + k]);
  for (const auto& [e, id] : mid) {
    if (!boundary_mid.count(id)) continue;
    const double *a = fe.points.p(e.first), *b = fe.points.p(e.second), *x = fe.points.p(id);
    off_surface += m.query->distance(x) > 1e-12;
    if (a[2] == b[2] && (a[2] == 0 || a[2] == H) && std::hypot(x[0], x[1]) < 0.99 * std::cos(kPi / N)) {
      EXPECT_NEAR(dist(x, std::array<double, 3>{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, a[2]}.data()), 0, 1e-15);
    }
  }
  EXPECT_LE(off_surface, st.reduced_edges + st.straightened_edges);
  EXPECT_LT(off_surface, boundary_mid.size() / 4);  // most of them do lie on the surface
  // Every element valid at its corners and Gauss points (an independent evaluation).
  double worst = 1e300;
  for (std::size_t t = 0; t < fe.num_tets(); ++t) {
    const double* x[10];
    for (int i = 0; i < 10; ++i) x[i] = fe.points.p(fe.tets[10 * t + i]);
    worst = std::min(worst, quadratic_tet_min_jacobian_ratio(x));
  }
  EXPECT_GE(worst, QuadraticOptions{}.min_jacobian_ratio);
  EXPECT_GT(QuadraticOptions{}.min_jacobian_ratio, 0.0);
  EXPECT_NEAR(worst, st.min_jacobian_ratio, 1e-12);
  const double quadratic = fe_mesh_volume(fe);
  EXPECT_LT(linear, true_volume);
  EXPECT_LT(std::fabs(quadratic - true_volume), 0.5 * std::fabs(linear - true_volume))
      << "linear " << linear << " quadratic " << quadratic << " true " << true_volume;

  // A demanding validity threshold forces the straight-midpoint fallback: afterwards every
  // element passes it, and the fallback elements are straight.
  FeMesh strict = make_fe_mesh(m.mesh, g, {});
  QuadraticOptions q;
  q.min_jacobian_ratio = 0.999;
  const QuadraticStats ss = make_quadratic(strict, m.surface.mesh, *m.query, m.patches, q);
  EXPECT_GT(ss.straightened_elements, 0u);
  EXPECT_GT(ss.straightened_edges, 0u);
  EXPECT_GE(ss.min_jacobian_ratio, 0.999);
  EXPECT_LT(ss.moved_mid_nodes - ss.straightened_edges, st.moved_mid_nodes);
}

}  // namespace
}  // namespace kdmesh
