// kdmesh — regression tests of the bug "kdmesh cannot mesh a torus (boundary recovery fails)":
// folds of all-surface tets on doubly curved and rough surfaces (mesher/volume/volume_mesh.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Before the fix, mesh_volume refused every torus: the tets whose four vertices are surface
// nodes lie across the saddle-shaped inner half of the tube (and across the bumps of a rough
// surface), their centroid-side classification folds the boundary into faces pointing into the
// solid, and the Steiner rounds cannot undo a fold. Both tori below were refused by the code
// before the fix (GeometryError "the boundary could not be recovered after 12 Steiner round(s)":
// 158 bad boundary faces on the smooth one, 126 and 22 non-manifold edges on the rough one).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mesher/volume/boundary_faces.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/placement/node_placement.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"
#include "tests/support/torus.h"

namespace kdmesh {
namespace {

/// Meshes the torus through the pipeline (as kdmesh mesh --size h --sharp-angle 60) and checks
/// the result; fails the test if mesh_volume throws.
void mesh_and_check(const SurfaceMesh& raw, double h, const std::string& name) {
  const PreparedSurface s = prepare_surface(raw, name);
  const SurfaceQuery q(s.mesh);
  SizingOptions so;
  so.max_size = h;
  const SizingField sizing = build_sizing_field(s.mesh, so);
  const NodeSet nodes = place_nodes({s, q, sizing}, detect_sharp_edges(s.mesh, 60));
  VolumeMesh vm;
  try {
    vm = mesh_volume({s, q, sizing}, nodes);
  } catch (const GeometryError& e) {
    FAIL() << name << ": " << e.what();
  }
  // The independent check, as strict as for any job.
  const MeshCheck c = check_volume_mesh(vm, {s, q, sizing});
  std::string failures;
  for (const std::string& f : c.failures) failures += f + "\n";
  EXPECT_TRUE(c.ok()) << name << ":\n" << failures;
  EXPECT_EQ(c.open_edges, 0u);
  EXPECT_EQ(c.nonmanifold_vertices, 0u);
  EXPECT_LT(c.volume_error, 0.005);

  // No fold: every boundary face faces the way of the facet closest to its centroid.
  // (b - a) x (c - a) points out of the solid, as the facet normals of a prepared surface do.
  std::size_t against = 0;
  for (std::size_t f = 0; f < vm.boundary.size() / 3; ++f) {
    const double* a = vm.nodes.points.p(vm.boundary[3 * f]);
    const double* b = vm.nodes.points.p(vm.boundary[3 * f + 1]);
    const double* d = vm.nodes.points.p(vm.boundary[3 * f + 2]);
    const double m[3] = {(a[0] + b[0] + d[0]) / 3, (a[1] + b[1] + d[1]) / 3, (a[2] + b[2] + d[2]) / 3};
    double cp[3];
    std::uint32_t facet = 0;
    q.closest(m, cp, &facet);
    const std::uint32_t* t = s.mesh.tri(facet);
    const double *p0 = s.mesh.points.p(t[0]), *p1 = s.mesh.points.p(t[1]), *p2 = s.mesh.points.p(t[2]);
    auto cross = [](const double* o, const double* x, const double* y, double* n) {
      const double u[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
      const double v[3] = {y[0] - o[0], y[1] - o[1], y[2] - o[2]};
      n[0] = u[1] * v[2] - u[2] * v[1];
      n[1] = u[2] * v[0] - u[0] * v[2];
      n[2] = u[0] * v[1] - u[1] * v[0];
    };
    double nf[3], ns[3];
    cross(a, b, d, nf);
    cross(p0, p1, p2, ns);
    against += nf[0] * ns[0] + nf[1] * ns[1] + nf[2] * ns[2] < 0;
  }
  EXPECT_EQ(against, 0u) << name << ": boundary faces facing into the solid";
}

// The smooth torus R = 40, r = 10 of 200 x 100 quads at h = 2.5.
TEST(TorusRecovery, SmoothTorusIsMeshed) {
  mesh_and_check(test::rough_torus(40, 10, 200, 100, 0, 7), 2.5, "smooth torus");
}

// The same torus with radial noise of 5% of the grid step (100 x 50 quads): the bumps make
// all-surface tets straddle the surface everywhere.
TEST(TorusRecovery, RoughTorusIsMeshed) {
  mesh_and_check(test::rough_torus(40, 10, 100, 50, 0.05, 7), 2.5, "rough torus");
}

// judge_face, which the fold removal uses to accept a peel, on one facet of a unit cube's
// surface: a face on the facet facing out is good, the same face reversed faces against it,
// one lifted off the surface is far.
TEST(TorusRecovery, JudgeFaceSeesFoldsAndDistance) {
  PreparedSurface s;
  const double c[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (auto& p : c) s.mesh.points.push_back(p[0], p[1], p[2]);
  s.mesh.tris = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  s = prepare_surface(s.mesh, "cube");
  const SurfaceQuery q(s.mesh);
  SizingOptions so;
  so.max_size = 1;
  const SizingField sizing = build_sizing_field(s.mesh, so);
  NodeSet n;
  const double top[4][3] = {{0.2, 0.2, 1}, {0.8, 0.2, 1}, {0.5, 0.8, 1}, {0.5, 0.5, 1.5}};
  for (auto& p : top) n.push_back(p, NodeKind::surface, kNoFacet, 1);
  const std::uint32_t out[3] = {0, 1, 2}, in[3] = {0, 2, 1}, lifted[3] = {0, 1, 3};
  EXPECT_EQ(judge_face(out, n, {s, q, sizing}, 0.08), 0);
  EXPECT_EQ(judge_face(in, n, {s, q, sizing}, 0.08), kFaceAgainst);
  float far = 0;
  EXPECT_TRUE(judge_face(lifted, n, {s, q, sizing}, 0.08, &far) & kFaceFar);
  EXPECT_GT(far, 0.08f);
  n.kind[1] = NodeKind::interior;
  EXPECT_EQ(judge_face(out, n, {s, q, sizing}, 0.08), kFaceInterior);
}

}  // namespace
}  // namespace kdmesh
