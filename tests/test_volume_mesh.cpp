// kdmesh — tests of the volume mesher (mesher/volume/volume_mesh.h) and of its independent checker
// (mesher/quality/mesh_check.h), on solids made of unit voxels with hand-built node sets.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include "core/error.h"
#include "core/rng.h"
#include "io/surface_io.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/boundary_faces.h"
#include "mesher/improve/mesh_improve.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/placement/node_placement.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/tet_quality.h"
#include "mesher/volume/volume_mesh.h"
#include "tests/support/icosphere.h"

namespace kdmesh {
namespace {

// ---------------------------------------------------------------------------------------------
// A solid made of axis-aligned voxels of edge L, voxel (i,j,k) = [i,i+1]x[j,j+1]x[k,k+1] * L.
struct Voxels {
  int nx = 1, ny = 1, nz = 1;
  double L = 1;
  std::vector<char> filled;
  bool at(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return false;
    return filled[std::size_t((k * ny + j) * nx + i)] != 0;
  }
  void set(int i, int j, int k, bool v = true) { filled[std::size_t((k * ny + j) * nx + i)] = v; }
  static Voxels block(int nx, int ny, int nz, double L) {
    Voxels v;
    v.nx = nx, v.ny = ny, v.nz = nz, v.L = L;
    v.filled.assign(std::size_t(nx * ny * nz), 1);
    return v;
  }
};

/// The boundary squares between filled and empty voxels, two triangles each, normal pointing
/// out of the filled voxel. Shells are the facet components (through shared edges); a shell
/// with negative signed volume is a void and belongs to the body of the outer shell whose
/// bounding box contains it.
PreparedSurface voxel_surface(const Voxels& vx) {
  PreparedSurface s;
  std::map<std::array<int, 3>, std::uint32_t> ids;
  auto pid = [&](int i, int j, int k) {
    auto [it, fresh] = ids.try_emplace({i, j, k}, std::uint32_t(ids.size()));
    if (fresh) s.mesh.points.push_back(i * vx.L, j * vx.L, k * vx.L);
    return it->second;
  };
  for (int k = 0; k < vx.nz; ++k)
    for (int j = 0; j < vx.ny; ++j)
      for (int i = 0; i < vx.nx; ++i) {
        if (!vx.at(i, j, k)) continue;
        for (int axis = 0; axis < 3; ++axis)
          for (int dir = -1; dir <= 1; dir += 2) {
            int n[3] = {i, j, k};
            n[axis] += dir;
            if (vx.at(n[0], n[1], n[2])) continue;
            // The square at coordinate c on `axis`, spanned by the two other axes.
            const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            std::array<int, 3> corner[4];
            for (int q = 0; q < 4; ++q) {
              corner[q] = {i, j, k};
              corner[q][axis] += dir > 0 ? 1 : 0;
            }
            corner[1][a1] += 1;
            corner[2][a1] += 1, corner[2][a2] += 1;
            corner[3][a2] += 1;
            // (a1, a2, axis) is right-handed: the loop 0,1,2,3 has normal +axis.
            std::uint32_t v[4];
            for (int q = 0; q < 4; ++q) v[q] = pid(corner[q][0], corner[q][1], corner[q][2]);
            if (dir < 0) std::swap(v[1], v[3]);
            s.mesh.tris.insert(s.mesh.tris.end(), {v[0], v[1], v[2], v[0], v[2], v[3]});
          }
      }
  // Shells: union-find of facets through shared edges.
  const std::size_t nf = s.mesh.num_tris();
  std::vector<std::uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_face;
  for (std::uint32_t f = 0; f < nf; ++f)
    for (int e = 0; e < 3; ++e) {
      const auto key = std::minmax(s.mesh.tris[3 * f + e], s.mesh.tris[3 * f + (e + 1) % 3]);
      auto [it, fresh] = edge_face.try_emplace(key, f);
      if (!fresh) parent[find(f)] = find(it->second);
    }
  std::map<std::uint32_t, std::uint32_t> shell_of_root;
  s.tri_shell.resize(nf);
  for (std::uint32_t f = 0; f < nf; ++f) {
    auto [it, fresh] = shell_of_root.try_emplace(find(f), std::uint32_t(shell_of_root.size()));
    s.tri_shell[f] = it->second;
  }
  const std::size_t ns = shell_of_root.size();
  s.shell_volume.assign(ns, 0);
  std::vector<std::array<double, 6>> box(ns, {1e300, 1e300, 1e300, -1e300, -1e300, -1e300});
  for (std::uint32_t f = 0; f < nf; ++f) {
    const double *a = s.mesh.points.p(s.mesh.tris[3 * f]), *b = s.mesh.points.p(s.mesh.tris[3 * f + 1]),
                 *c = s.mesh.points.p(s.mesh.tris[3 * f + 2]);
    s.shell_volume[s.tri_shell[f]] += (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                                       a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    for (const double* p : {a, b, c})
      for (int q = 0; q < 3; ++q) {
        box[s.tri_shell[f]][q] = std::min(box[s.tri_shell[f]][q], p[q]);
        box[s.tri_shell[f]][3 + q] = std::max(box[s.tri_shell[f]][3 + q], p[q]);
      }
  }
  s.shell_body.assign(ns, 0);
  s.shell_parent.assign(ns, kNoFacet);
  std::uint32_t bodies = 0;
  for (std::size_t sh = 0; sh < ns; ++sh)
    if (s.shell_volume[sh] > 0) s.shell_body[sh] = bodies++;
  for (std::size_t sh = 0; sh < ns; ++sh) {
    if (s.shell_volume[sh] > 0) continue;
    for (std::size_t o = 0; o < ns; ++o)
      if (s.shell_volume[o] > 0 && box[o][0] <= box[sh][0] && box[o][3] >= box[sh][3] &&
          box[o][1] <= box[sh][1] && box[o][4] >= box[sh][4] && box[o][2] <= box[sh][2] &&
          box[o][5] >= box[sh][5])
        s.shell_body[sh] = s.shell_body[o], s.shell_parent[sh] = std::uint32_t(o);
  }
  s.num_bodies = bodies;
  s.volume = std::accumulate(s.shell_volume.begin(), s.shell_volume.end(), 0.0);
  for (int q = 0; q < 3; ++q) {
    s.bbox_min[q] = 1e300, s.bbox_max[q] = -1e300;
  }
  for (std::size_t p = 0; p < s.mesh.points.size(); ++p)
    for (int q = 0; q < 3; ++q) {
      s.bbox_min[q] = std::min(s.bbox_min[q], s.mesh.points.p(std::uint32_t(p))[q]);
      s.bbox_max[q] = std::max(s.bbox_max[q], s.mesh.points.p(std::uint32_t(p))[q]);
    }
  return s;
}

/// Nodes: a structured m x m grid on every boundary square (shared nodes once), then interior
/// lattice points of spacing h = L/m jittered by +-0.15 h, kept if strictly inside and at least
/// 0.8 h from the surface. `skip(p)` drops surface nodes (to make the sampling too coarse).
template <class Skip>
NodeSet voxel_nodes(const Voxels& vx, const PreparedSurface& s, const SurfaceQuery& q, int m,
                    std::uint64_t seed, Skip skip) {
  NodeSet nodes;
  const double h = vx.L / m;
  std::set<std::array<int, 3>> seen;
  for (std::size_t f = 0; f < s.mesh.num_tris(); f += 2) {  // one square = facets f, f+1
    const double *a = s.mesh.points.p(s.mesh.tris[3 * f]), *c = s.mesh.points.p(s.mesh.tris[3 * f + 2]);
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = int(std::lround(std::min(a[k], c[k]) / h));
      hi[k] = int(std::lround(std::max(a[k], c[k]) / h));
    }
    for (int i = lo[0]; i <= hi[0]; ++i)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int k = lo[2]; k <= hi[2]; ++k) {
          if (!seen.insert({i, j, k}).second) continue;
          const double p[3] = {i * h, j * h, k * h};
          if (skip(p)) continue;
          double cp[3];
          std::uint32_t facet = kNoFacet;
          q.closest(p, cp, &facet);
          nodes.push_back(p, NodeKind::surface, facet, float(h));
        }
  }
  Rng rng(seed);
  for (int i = 1; i < vx.nx * m; ++i)
    for (int j = 1; j < vx.ny * m; ++j)
      for (int k = 1; k < vx.nz * m; ++k) {
        double p[3] = {i * h, j * h, k * h};
        for (double& x : p) x += rng.uniform(-0.15, 0.15) * h;
        if (q.side(p) == 1 && q.distance(p) >= 0.8 * h) nodes.push_back(p, NodeKind::interior, kNoFacet, float(h));
      }
  return nodes;
}
NodeSet voxel_nodes(const Voxels& vx, const PreparedSurface& s, const SurfaceQuery& q, int m,
                    std::uint64_t seed = 1) {
  return voxel_nodes(vx, s, q, m, seed, [](const double*) { return false; });
}

SizingField uniform_size(const PreparedSurface& s, double h) {
  SizingOptions o;
  o.max_size = h;
  return build_sizing_field(s.mesh, o);
}

std::string failures(const MeshCheck& c) {
  std::string s;
  for (auto& f : c.failures) s += f + "\n";
  return s;
}

void expect_basic_invariants(const VolumeMesh& vm) {
  ASSERT_EQ(vm.tet_region.size(), vm.num_tets());
  ASSERT_EQ(vm.boundary.size(), 3 * vm.boundary_tet.size());
  for (std::uint32_t v : vm.tets) ASSERT_LT(v, vm.nodes.points.size());
  // Every node is used (no orphan points in an FE mesh).
  std::vector<char> used(vm.nodes.points.size(), 0);
  for (std::uint32_t v : vm.tets) used[v] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
}

// ---------------------------------------------------------------------------------------------
// Box [0,2]x[0,1]x[0,1] (two voxels), h = 1/6. Every boundary face lies on a box face and the
// tets tile the box, so the volume is 2 up to the rounding of the tet volume sum.
TEST(VolumeMesh, BoxPassesEveryCheck) {
  const Voxels vx = Voxels::block(2, 1, 1, 1.0);
  const PreparedSurface s = voxel_surface(vx);
  ASSERT_DOUBLE_EQ(s.volume, 2.0);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 1.0 / 6);
  const NodeSet nodes = voxel_nodes(vx, s, q, 6);
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_EQ(c.nonpositive_tets + c.outside_tets + c.offsurface_vertices + c.offsurface_faces +
                c.open_edges + c.nonmanifold_vertices, 0u);
  EXPECT_LT(c.volume_error, 1e-12);
  EXPECT_NEAR(c.mesh_volume, 2.0, 1e-12);
  EXPECT_LT(c.max_hausdorff, 1e-12);  // boundary faces lie in the box's face planes
  // Surface nodes: the box's 13 x 7 x 7 lattice points minus the 11 x 5 x 5 interior ones,
  // 637 - 275 = 362; none is dropped or unused.
  std::size_t surface_nodes = 0;
  for (NodeKind k : vm.nodes.kind) surface_nodes += k != NodeKind::interior;
  EXPECT_EQ(surface_nodes, 362u);
  // The boundary is a triangulated sphere on those V = 362 vertices: Euler V - E + F = 2 with
  // 3F = 2E gives F = 2V - 4 = 720.
  EXPECT_EQ(c.boundary_faces, 2 * 362u - 4);
  for (std::uint32_t r : vm.tet_region) EXPECT_EQ(r, 0u);
  EXPECT_EQ(vm.stats.steiner_points, 0u);
  EXPECT_EQ(vm.stats.dropped_nodes, 0u);
  EXPECT_GT(vm.stats.side_queries, 0u);
  EXPECT_LT(vm.stats.side_queries, vm.stats.classified_tets);  // components, not every tet
}

// Two disjoint unit cubes two units apart: two regions, one per body, each of volume 1.
TEST(VolumeMesh, TwoBoxesGiveTwoRegions) {
  Voxels vx = Voxels::block(4, 1, 1, 1.0);
  vx.set(1, 0, 0, false), vx.set(2, 0, 0, false);
  const PreparedSurface s = voxel_surface(vx);
  ASSERT_EQ(s.num_bodies, 2u);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.2);
  const VolumeMesh vm = mesh_volume({s, q, h}, voxel_nodes(vx, s, q, 5));
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_NEAR(c.mesh_volume, 2.0, 1e-12);
  // Each tet's region is the body whose box holds its centroid: body of shell 0 is the
  // lower-x cube (its facets come first), so region = (centroid x > 2) ? body 1 : body 0.
  double vol[2] = {0, 0};
  for (std::size_t t = 0; t < vm.num_tets(); ++t) {
    const std::uint32_t* v = &vm.tets[4 * t];
    double x = 0;
    for (int i = 0; i < 4; ++i) x += vm.nodes.points.p(v[i])[0] / 4;
    const std::uint32_t expect = s.shell_body[s.tri_shell[x < 2 ? 0 : s.mesh.num_tris() - 1]];
    ASSERT_EQ(vm.tet_region[t], expect) << "tet " << t;
    vol[vm.tet_region[t]] += tet_quality(vm.nodes.points.p(v[0]), vm.nodes.points.p(v[1]),
                                         vm.nodes.points.p(v[2]), vm.nodes.points.p(v[3])).volume;
  }
  EXPECT_NEAR(vol[0], 1.0, 1e-12);
  EXPECT_NEAR(vol[1], 1.0, 1e-12);
}

// A 3x3x3 block with the centre voxel removed: a void of volume 1 inside a body of 27.
TEST(VolumeMesh, BoxWithVoid) {
  Voxels vx = Voxels::block(3, 3, 3, 1.0);
  vx.set(1, 1, 1, false);
  const PreparedSurface s = voxel_surface(vx);
  ASSERT_EQ(s.num_bodies, 1u);
  ASSERT_EQ(s.shell_volume.size(), 2u);
  ASSERT_DOUBLE_EQ(s.volume, 26.0);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.5);
  const VolumeMesh vm = mesh_volume({s, q, h}, voxel_nodes(vx, s, q, 2));
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_NEAR(c.mesh_volume, 27.0 - 1.0, 1e-11);
  for (std::size_t t = 0; t < vm.num_tets(); ++t) {
    double m[3] = {0, 0, 0};
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) m[k] += vm.nodes.points.p(vm.tets[4 * t + i])[k] / 4;
    const bool in_void = m[0] > 1 && m[0] < 2 && m[1] > 1 && m[1] < 2 && m[2] > 1 && m[2] < 2;
    ASSERT_FALSE(in_void) << "tet " << t << " lies in the void";
    ASSERT_EQ(vm.tet_region[t], 0u);
  }
}

// A 16-gon prism ("cylinder") of circumradius 1 and height 1, h = 0.2: its side facets are not
// axis-aligned. Nodes: on each side rectangle, columns at its corners and its mid-width, rows
// every 0.2; on each cap, the lattice points (0.2 i, 0.2 j) at least 0.5 h inside the polygon;
// interior lattice points jittered, 0.8 h clear of the surface. The tets tile the prism, whose
// volume is (16/2) sin(2 pi/16) * 1 = 8 sin(pi/8).
TEST(VolumeMesh, PolygonalCylinder) {
  const int N = 16;
  const double pi = std::acos(-1.0), hsize = 0.2;
  PreparedSurface s;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < N; ++k) s.mesh.points.push_back(std::cos(2 * pi * k / N), std::sin(2 * pi * k / N), z);
  s.mesh.points.push_back(0, 0, 0);
  s.mesh.points.push_back(0, 0, 1);
  const std::uint32_t c0 = 2 * N, c1 = 2 * N + 1;
  for (std::uint32_t k = 0; k < std::uint32_t(N); ++k) {
    const std::uint32_t b = k, b1 = (k + 1) % N, t = N + k, t1 = N + (k + 1) % N;
    s.mesh.tris.insert(s.mesh.tris.end(), {b, b1, t1, b, t1, t, c0, b1, b, c1, t, t1});
  }
  s.tri_shell.assign(s.mesh.num_tris(), 0);
  s.shell_body = {0};
  s.shell_parent = {kNoFacet};
  s.num_bodies = 1;
  s.volume = N / 2.0 * std::sin(2 * pi / N);
  s.shell_volume = {s.volume};
  for (int q = 0; q < 2; ++q) s.bbox_min[q] = -1, s.bbox_max[q] = 1;
  s.bbox_min[2] = 0, s.bbox_max[2] = 1;
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, hsize);
  NodeSet nodes;
  auto add_surface = [&](double x, double y, double z) {
    const double p[3] = {x, y, z};
    double cp[3];
    std::uint32_t f = kNoFacet;
    ASSERT_LT(q.closest(p, cp, &f), 1e-15);
    nodes.push_back(p, NodeKind::surface, f, float(hsize));
  };
  for (int k = 0; k < N; ++k) {
    const double* a = s.mesh.points.p(std::uint32_t(k));
    const double* b = s.mesh.points.p(std::uint32_t((k + 1) % N));
    for (int j = 0; j <= 5; ++j) {
      add_surface(a[0], a[1], j * hsize);
      add_surface((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, j * hsize);
    }
  }
  const double inradius = std::cos(pi / N);
  auto polygon_clearance = [&](double x, double y) {  // distance inside the polygon (2D)
    double worst = 1e300;
    for (int k = 0; k < N; ++k) {
      const double phi = 2 * pi * (k + 0.5) / N;
      worst = std::min(worst, inradius - (x * std::cos(phi) + y * std::sin(phi)));
    }
    return worst;
  };
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j)
      if (polygon_clearance(i * hsize, j * hsize) >= 0.5 * hsize)
        for (double z : {0.0, 1.0}) add_surface(i * hsize, j * hsize, z);
  Rng rng(3);
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j)
      for (int k = 1; k < 5; ++k) {
        double p[3] = {i * hsize, j * hsize, k * hsize};
        for (double& x : p) x += rng.uniform(-0.15, 0.15) * hsize;
        if (q.side(p) == 1 && q.distance(p) >= 0.8 * hsize) nodes.push_back(p, NodeKind::interior, kNoFacet, float(hsize));
      }
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_NEAR(c.mesh_volume, 8 * std::sin(pi / 8), 1e-12);
  EXPECT_LT(c.max_hausdorff, 1e-12);
}

// L-shaped prism (three voxels of a 2x2x1 block) whose surface nodes on the re-entrant edge
// x = y = 1 are left out: the Delaunay tets cut across the notch there, so those boundary
// faces miss the surface by ~h/2 and surface Steiner points must recover it.
TEST(VolumeMesh, ConcaveEdgeNeedsSteinerPoints) {
  Voxels vx = Voxels::block(2, 2, 1, 1.0);
  vx.set(1, 1, 0, false);
  const PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const int m = 5;
  const SizingField h = uniform_size(s, 1.0 / m);
  const NodeSet nodes = voxel_nodes(vx, s, q, m, 7, [](const double* p) {
    return std::fabs(p[0] - 1) < 1e-9 && std::fabs(p[1] - 1) < 1e-9 && p[2] > 1e-9 && p[2] < 1 - 1e-9;
  });
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  EXPECT_GT(vm.stats.steiner_points, 0u);
  EXPECT_GE(vm.stats.rounds, 1);
  EXPECT_LE(vm.stats.insert_rounds, vm.stats.rounds);
  // Faces across the re-entrant edge are only recovered by points on it: some Steiner points
  // are edge-kind and lie exactly on x = y = 1 (closest points on that crease segment).
  std::size_t on_edge = 0;
  for (std::size_t i = 0; i < vm.nodes.points.size(); ++i) {
    const double* p = vm.nodes.points.p(std::uint32_t(i));
    on_edge += vm.nodes.kind[i] == NodeKind::edge && p[0] == 1 && p[1] == 1;
  }
  EXPECT_GT(on_edge, 0u);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_LT(c.volume_error, 0.005);
}

// An interior node 0.01 from the void's face x = 1 (the 3x3x3 block without its centre voxel,
// h = 0.5), near the centre of the surface square [1,1.5]^2 at x = 1. Every sphere through
// that square's corners either holds the node (centre at x = 1 + d, d <= 0.5: the node's
// squared distance (d+0.01)^2 + 2e-4 < 0.125 + d^2) or the node (2, 1.5, 1.5) of the opposite
// void face (d > 0.5), so the square's faces are not Delaunay: the node lands on boundary
// faces and must be dropped. (Next to a convex hull face it would not: hull faces are always
// Delaunay.)
// The recovery judges only the boundary faces it has not judged in an earlier round. A verdict
// depends on the face's orientation (a face whose normal points against the surface is bad),
// so the cache finds a face under any rotation of its vertices but never reversed.
TEST(FaceVerdicts, KeyedByTheOrientedFace) {
  FaceVerdicts c;
  const std::uint32_t f[3] = {7, 3, 5};
  c.put(f, {kFaceAgainst, 0.25f});
  for (const std::array<std::uint32_t, 3> r : {std::array<std::uint32_t, 3>{7, 3, 5}, {3, 5, 7}, {5, 7, 3}}) {
    const FaceVerdicts::Verdict* v = c.find(r.data());
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->why, kFaceAgainst);
    EXPECT_EQ(v->how_far, 0.25f);
  }
  for (const std::array<std::uint32_t, 3> r : {std::array<std::uint32_t, 3>{7, 5, 3}, {3, 7, 5}, {5, 3, 7}})
    EXPECT_EQ(c.find(r.data()), nullptr);
  EXPECT_EQ(c.size(), 1u);
  c.clear();
  EXPECT_EQ(c.find(f), nullptr);
}

// The table grows from empty through many rehashes; a put of a face already there replaces
// its verdict. Oracle: a std::map keyed by the rotation that starts at the smallest id.
TEST(FaceVerdicts, ManyFacesThroughRehashesMatchAMap) {
  FaceVerdicts c;
  std::map<std::array<std::uint32_t, 3>, std::pair<std::uint8_t, float>> want;
  auto oriented = [](std::array<std::uint32_t, 3> f) {
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    return f;
  };
  Rng rng(7);
  std::vector<std::array<std::uint32_t, 3>> faces;
  for (int k = 0; k < 20000; ++k) {
    std::array<std::uint32_t, 3> f{};
    if (!faces.empty() && rng.next() % 4 == 0) {  // the same face again, another rotation
      f = faces[rng.next() % faces.size()];
      std::rotate(f.begin(), f.begin() + std::ptrdiff_t(rng.next() % 3), f.end());
    } else {
      for (auto& v : f) v = std::uint32_t(rng.next() % 3000);
      if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) continue;
      faces.push_back(f);
    }
    const std::uint8_t why = std::uint8_t(rng.next() % 8);
    const float far = float(rng.next() % 1000) / 100;
    c.put(f.data(), {why, far});
    want[oriented(f)] = {why, far};
  }
  EXPECT_EQ(c.size(), want.size());
  for (const auto& f : faces) {
    const FaceVerdicts::Verdict* v = c.find(f.data());
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->why, want.at(oriented(f)).first);
    EXPECT_EQ(v->how_far, want.at(oriented(f)).second);
    const std::array<std::uint32_t, 3> reversed{f[0], f[2], f[1]};
    EXPECT_EQ(c.find(reversed.data()) != nullptr, want.count(oriented(reversed)) == 1);
  }
  const std::uint32_t reserved[3] = {1, 2, 0xFFFFFFFFu};
  EXPECT_THROW(c.put(reserved, {0, 0.0f}), UsageError);
}

// manifold_defects groups the edges and corners with counting sorts on a few threads. The
// oracle is the one-thread version it replaced: all (edge, face) and (vertex, face) pairs
// sorted, runs read in order. Soups: two icospheres of 40,962 vertices each (vertex ids over
// several of the parallel version's blocks, with unused ids between the spheres), with faces
// removed (edges in one face), repeated (edges in three) and two spheres glued at a vertex
// (two fans around it); each also with its ids spread up to 3.7e9, and one triangle with the
// largest ids (the groups would take O(largest id) memory: sparse ids are renamed first).
namespace {
ManifoldDefects manifold_defects_by_sorting(const std::vector<std::uint32_t>& verts) {
  ManifoldDefects d;
  const std::size_t nf = verts.size() / 3;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
  for (std::size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t a = verts[3 * f + j], b = verts[3 * f + (j + 1) % 3];
      edges.push_back({(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), std::uint32_t(f)});
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0, j = 0; i < edges.size(); i = j) {
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 2) continue;
    d.bad_edges.push_back(std::uint32_t(edges[i].first >> 32));
    d.bad_edges.push_back(std::uint32_t(edges[i].first));
    for (std::size_t k = i; k < j; ++k) d.faces_at_bad_edges.push_back(edges[k].second);
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> vf;
  for (std::size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) vf.push_back({verts[3 * f + j], std::uint32_t(f)});
  std::sort(vf.begin(), vf.end());
  for (std::size_t i = 0, j = 0; i < vf.size(); i = j) {
    while (j < vf.size() && vf[j].first == vf[i].first) ++j;
    const std::uint32_t v = vf[i].first;
    std::map<std::uint32_t, std::uint32_t> parent;  // link vertex -> parent
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x];
      return x;
    };
    for (std::size_t k = i; k < j; ++k) {
      std::vector<std::uint32_t> o;
      for (int c = 0; c < 3; ++c)
        if (verts[3 * std::size_t(vf[k].second) + c] != v) o.push_back(verts[3 * std::size_t(vf[k].second) + c]);
      for (const std::uint32_t x : o) parent.try_emplace(x, x);
      const std::uint32_t x = find(o[0]), y = find(o[1]);
      if (x != y) parent[x] = y;
    }
    std::size_t roots = 0;
    for (const auto& [x, up] : parent) roots += x == up;
    if (roots <= 1) continue;
    d.bad_vertices.push_back(v);
    for (std::size_t k = i; k < j; ++k) d.faces_at_bad_vertices.push_back(vf[k].second);
  }
  return d;
}
}  // namespace

TEST(ManifoldDefects, SameAsSortingEveryEdgeAndCornerOnDamagedSpheres) {
  const SurfaceMesh sphere = test::icosphere(6);
  const std::uint32_t nv = std::uint32_t(sphere.points.size());
  ASSERT_GT(nv, 2u * (1u << 14));
  // Sphere 2's ids start 10,000 past sphere 1's; its vertex 0 is sphere 1's vertex 0 (glued).
  auto sphere2 = [&](std::uint32_t v) { return v == 0 ? 0u : v + nv + 10000; };
  Rng rng(22);
  for (int round = 0; round < 4; ++round) {
    std::vector<std::uint32_t> verts;
    for (std::size_t f = 0; f < sphere.num_tris(); ++f) {
      const std::uint32_t* t = sphere.tri(f);
      const std::uint64_t r = rng.next() % 1000;
      if (r < std::uint64_t(round)) continue;  // removed
      const int copies = round > 0 && r >= 998 ? 2 : 1;  // repeated
      for (int c = 0; c < copies; ++c) {
        verts.insert(verts.end(), t, t + 3);
        if (round % 2 == 1) verts.insert(verts.end(), {sphere2(t[0]), sphere2(t[1]), sphere2(t[2])});
      }
    }
    const ManifoldDefects got = manifold_defects(verts), want = manifold_defects_by_sorting(verts);
    EXPECT_EQ(got.bad_edges, want.bad_edges) << "round " << round;
    EXPECT_EQ(got.faces_at_bad_edges, want.faces_at_bad_edges) << "round " << round;
    EXPECT_EQ(got.bad_vertices, want.bad_vertices) << "round " << round;
    EXPECT_EQ(got.faces_at_bad_vertices, want.faces_at_bad_vertices) << "round " << round;
    // Sparse ids (up to 3.7e9), which manifold_defects renames to their ranks first.
    std::vector<std::uint32_t> sparse(verts);
    for (std::uint32_t& v : sparse) v = v * 40000u + 7u;
    const ManifoldDefects got_sparse = manifold_defects(sparse), want_sparse = manifold_defects_by_sorting(sparse);
    EXPECT_EQ(got_sparse.bad_edges, want_sparse.bad_edges) << "round " << round;
    EXPECT_EQ(got_sparse.faces_at_bad_edges, want_sparse.faces_at_bad_edges) << "round " << round;
    EXPECT_EQ(got_sparse.bad_vertices, want_sparse.bad_vertices) << "round " << round;
    EXPECT_EQ(got_sparse.faces_at_bad_vertices, want_sparse.faces_at_bad_vertices) << "round " << round;
    EXPECT_EQ(got_sparse.bad_edges.size(), got.bad_edges.size());
    if (round == 0) {
      EXPECT_TRUE(want.bad_edges.empty() && want.bad_vertices.empty());
    }
    if (round >= 1) {
      EXPECT_FALSE(want.bad_edges.empty()) << "round " << round;
    }
    if (round % 2 == 1) {
      EXPECT_FALSE(want.bad_vertices.empty()) << "round " << round;
    }
  }
  EXPECT_TRUE(manifold_defects({}).bad_edges.empty());
  // The largest id: one triangle, its three edges in one face each.
  const ManifoldDefects top = manifold_defects({0xFFFFFFFEu, 0xFFFFFFFFu, 0xFFFFFFFDu});
  EXPECT_EQ(top.bad_edges, (std::vector<std::uint32_t>{0xFFFFFFFDu, 0xFFFFFFFEu, 0xFFFFFFFDu, 0xFFFFFFFFu,
                                                      0xFFFFFFFEu, 0xFFFFFFFFu}));
}

TEST(VolumeMesh, InteriorNodeTooCloseToSurfaceIsDropped) {
  Voxels vx = Voxels::block(3, 3, 3, 1.0);
  vx.set(1, 1, 1, false);
  const PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.5);
  NodeSet nodes = voxel_nodes(vx, s, q, 2);
  const double p[3] = {0.99, 1.26, 1.24};
  nodes.push_back(p, NodeKind::interior, kNoFacet, 0.5f);
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  EXPECT_GE(vm.stats.dropped_nodes, 1u);
  EXPECT_EQ(vm.nodes.points.size(), nodes.points.size() - vm.stats.dropped_nodes + vm.stats.steiner_points);
  for (std::size_t i = 0; i < vm.nodes.points.size(); ++i)
    EXPECT_FALSE(vm.nodes.points.p(std::uint32_t(i))[0] == p[0] && vm.nodes.points.p(std::uint32_t(i))[1] == p[1])
        << "the close node survived";
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_NEAR(c.mesh_volume, 26.0, 1e-11);
}

// A surface node that the recovered boundary passes over is no boundary vertex, yet it kept
// its surface kind, so the quality pass never moved it off the surface: fandisk.ply at
// diag/40 kept a 0.04 deg tet on such a node (its boundary face 0.02 h above it). Here a
// surface-kind node 0.004 h under the top face of a cube is inside the convex hull, so no
// boundary face can use it: it becomes an interior node, and the pass then lifts the flat tets
// it makes with the top face.
TEST(VolumeMesh, RegressionFandiskBuriedSurfaceNodeBecomesInterior) {
  const Voxels vx = Voxels::block(1, 1, 1, 1.0);
  PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.25);
  NodeSet nodes = voxel_nodes(vx, s, q, 4);
  const double p[3] = {0.55, 0.6, 0.999};
  double cp[3];
  std::uint32_t facet = kNoFacet;
  q.closest(p, cp, &facet);
  nodes.push_back(p, NodeKind::surface, facet, 0.25f);
  VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  EXPECT_EQ(vm.stats.buried_nodes, 1u);
  std::vector<char> on_boundary(vm.nodes.size_count(), 0);
  for (std::uint32_t v : vm.boundary) on_boundary[v] = 1;
  std::uint32_t buried = kNoFacet;
  for (std::uint32_t v = 0; v < vm.nodes.size_count(); ++v) {
    EXPECT_EQ(bool(on_boundary[v]), vm.nodes.kind[v] != NodeKind::interior) << "node " << v;
    if (vm.nodes.points.p(v)[2] == p[2]) buried = v;
  }
  ASSERT_NE(buried, kNoFacet);
  EXPECT_EQ(vm.nodes.kind[buried], NodeKind::interior);
  EXPECT_EQ(vm.nodes.facet[buried], kNoFacet);
  const double before = summarize_quality(to_tet_mesh(vm)).min_dihedral;
  ImproveOptions o;
  o.threads = 1;
  improve_mesh(vm, {s, q, h}, o);
  const double after = summarize_quality(to_tet_mesh(vm)).min_dihedral;
  EXPECT_LT(before, 1.0);  // the flat tets under the top face
  EXPECT_GE(after, 12.0);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
}

TEST(VolumeMesh, ToTetMeshCarriesTheData) {
  const Voxels vx = Voxels::block(1, 1, 1, 1.0);
  const PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.25);
  const VolumeMesh vm = mesh_volume({s, q, h}, voxel_nodes(vx, s, q, 4));
  const TetMesh tm = to_tet_mesh(vm);
  EXPECT_EQ(tm.tets, vm.tets);
  ASSERT_EQ(tm.point_data.size(), 2u);
  EXPECT_EQ(tm.point_data[0].name, "node_kind");
  EXPECT_EQ(tm.point_data[1].name, "target_size");
  ASSERT_EQ(tm.point_data[0].ints.size(), vm.nodes.points.size());
  for (std::size_t i = 0; i < vm.nodes.points.size(); ++i) {
    EXPECT_EQ(tm.point_data[0].ints[i], int(vm.nodes.kind[i]));
    ASSERT_EQ(tm.point_data[1].floats.size(), vm.nodes.points.size());
    EXPECT_EQ(tm.point_data[1].floats[i], vm.nodes.size[i]);
    EXPECT_EQ(tm.point_data[1].floats[i], 0.25f);
  }
  ASSERT_EQ(tm.cell_data.size(), 3u);
  EXPECT_EQ(tm.cell_data[0].name, "region");
  EXPECT_EQ(tm.cell_data[1].name, "min_dihedral");
  EXPECT_EQ(tm.cell_data[2].name, "radius_ratio");
  for (std::size_t t = 0; t < tm.num_tets(); ++t) {
    const std::uint32_t* v = &tm.tets[4 * t];
    const TetQuality tq = tet_quality(tm.points.p(v[0]), tm.points.p(v[1]), tm.points.p(v[2]), tm.points.p(v[3]));
    // Float32 in the file: each tet's measure rounded once to 32 bits.
    ASSERT_EQ(tm.cell_data[1].floats.size(), tm.num_tets());
    ASSERT_EQ(tm.cell_data[2].floats.size(), tm.num_tets());
    EXPECT_EQ(tm.cell_data[1].floats[t], float(tq.min_dihedral));
    EXPECT_EQ(tm.cell_data[2].floats[t], float(tq.radius_ratio));
    EXPECT_GT(tm.cell_data[1].floats[t], 0);
    EXPECT_GT(tm.cell_data[2].floats[t], 0);
  }
}

TEST(VolumeMesh, BadOptionsAndNodeSets) {
  const Voxels vx = Voxels::block(1, 1, 1, 1.0);
  const PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.5);
  NodeSet nodes = voxel_nodes(vx, s, q, 2);
  NodeSet broken = nodes;
  broken.kind.pop_back();
  EXPECT_THROW(mesh_volume({s, q, h}, broken), UsageError);
  VolumeMeshOptions o;
  o.hausdorff_tolerance = 0;
  EXPECT_THROW(mesh_volume({s, q, h}, nodes, o), UsageError);
  NodeSet nan = nodes;
  nan.points.xyz[3 * 2 + 1] = std::nan("");
  try {
    mesh_volume({s, q, h}, nan);
    ADD_FAILURE() << "expected GeometryError";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("node 2 "), std::string::npos) << e.what();
  }
  // Nodes all outside the solid: no tet inside.
  NodeSet far;
  for (int i = 0; i < 8; ++i) {
    const double p[3] = {5.0 + (i & 1), 5.0 + ((i >> 1) & 1), 5.0 + (i >> 2)};
    far.push_back(p, NodeKind::interior, kNoFacet, 0.5f);
  }
  EXPECT_THROW(mesh_volume({s, q, h}, far), GeometryError);
}

// With no Steiner rounds allowed, the notch case cannot be recovered: GeometryError naming
// where (a face position).
TEST(VolumeMesh, UnrecoverableBoundaryThrowsNamingTheFaces) {
  Voxels vx = Voxels::block(2, 2, 1, 1.0);
  vx.set(1, 1, 0, false);
  const PreparedSurface s = voxel_surface(vx);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.2);
  const NodeSet nodes = voxel_nodes(vx, s, q, 5, 7, [](const double* p) {
    return std::fabs(p[0] - 1) < 1e-9 && std::fabs(p[1] - 1) < 1e-9 && p[2] > 1e-9 && p[2] < 1 - 1e-9;
  });
  VolumeMeshOptions o;
  o.max_steiner_rounds = 0;
  try {
    mesh_volume({s, q, h}, nodes, o);
    FAIL() << "expected GeometryError";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("face at ("), std::string::npos) << e.what();
  }
}

// The whole pipeline on an L-shaped prism (three voxels, h = 0.125): prepare_surface, sharp
// edges, place_nodes, mesh_volume, check_volume_mesh.
TEST(VolumeMesh, PipelineWithPlacedNodes) {
  Voxels vx = Voxels::block(2, 2, 1, 1.0);
  vx.set(1, 1, 0, false);
  const PreparedSurface raw = voxel_surface(vx);
  const PreparedSurface s = prepare_surface(raw.mesh, "L-prism");
  ASSERT_NEAR(s.volume, 3.0, 1e-12);
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.125);
  const FeatureEdges fe = detect_sharp_edges(s.mesh, 30);
  const NodeSet nodes = place_nodes({s, q, h}, fe);
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_LT(c.volume_error, 1e-9);
}

// A curved solid: the 320-facet icosphere, h = 0.12, nodes from place_nodes. Its facets are
// not axis-aligned, so the surface nodes of one facet are coplanar only up to rounding and the
// Delaunay tets include flat slivers lying in the surface; they must not make the boundary
// zigzag. The mesh must fill the polyhedron (its volume is prepare_surface's), every check passing.
TEST(VolumeMesh, PipelineOnIcosphere) {
  const PreparedSurface s = prepare_surface(test::icosphere(2), "icosphere");
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 0.12);
  const NodeSet nodes = place_nodes({s, q, h}, detect_sharp_edges(s.mesh, 30));
  const VolumeMesh vm = mesh_volume({s, q, h}, nodes);
  expect_basic_invariants(vm);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_TRUE(c.ok()) << failures(c);
  EXPECT_LT(c.volume_error, 1e-9);
}

// The volume mesh does not depend on the Delaunay's thread count: the parallel kernel stores
// the same tets in another order, and the triangulation is put in canonical order before the
// classification, the recovery and the quality pass break their ties by tet id. The gear of
// models/gearbox at size 1.9 (above the ~40k nodes from which the kernel uses its threads).
TEST(VolumeMesh, TheSameMeshOnOneTwoAndThreeDelaunayThreads) {
  const PreparedSurface s = prepare_surface(
      read_surface(std::string(KDMESH_SOURCE_DIR) + "/models/gearbox/gear.stl"), "gear.stl", SurfaceOptions{});
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 1.9);
  const NodeSet nodes = place_nodes({s, q, h}, detect_sharp_edges(s.mesh, 30));
  ASSERT_GT(nodes.size_count(), 45000u);
  VolumeMesh first;
  for (const unsigned threads : {1u, 2u, 3u}) {
    VolumeMeshOptions o;
    o.threads = threads;
    VolumeMesh vm = mesh_volume({s, q, h}, nodes, o);
    if (threads == 1) {
      EXPECT_EQ(vm.stats.delaunay.parallel_rounds, 0u);
      first = std::move(vm);
      continue;
    }
    EXPECT_GE(vm.stats.delaunay.parallel_rounds, 1u) << threads << " threads";
    EXPECT_TRUE(vm.tets == first.tets) << threads << " threads";
    EXPECT_TRUE(vm.boundary == first.boundary) << threads << " threads";
    EXPECT_TRUE(vm.tet_region == first.tet_region) << threads << " threads";
    EXPECT_TRUE(vm.nodes.points.xyz == first.nodes.points.xyz) << threads << " threads";
  }
}

// The check certifies a boundary vertex or face without a tree query when its corners lie on
// the facet their nodes record (the distance to one facet bounds the distance to the surface,
// and is convex over a face). Its figures must be those of the tree queries alone: the
// largest face distance against 7 samples per face by SurfaceQuery::distance. The icosphere
// of 320 facets at h = 0.12 has faces on one facet (certified); that of 5,120 facets at
// h = 0.2 has faces across several, off the curved surface (queried).
TEST(VolumeMesh, CheckFacetCertificateGivesTheTreeQueriesFigures) {
  for (const auto& [levels, size] : {std::pair{2, 0.12}, std::pair{4, 0.2}}) {
    const PreparedSurface s = prepare_surface(test::icosphere(levels), "icosphere");
    const SurfaceQuery q(s.mesh);
    const SizingField h = uniform_size(s, size);
    const VolumeMesh vm = mesh_volume({s, q, h}, place_nodes({s, q, h}, detect_sharp_edges(s.mesh, 30)));
    const MeshCheck c = check_volume_mesh(vm, {s, q, h});  // (level 4's volume is off: chords)
    EXPECT_EQ(c.offsurface_vertices, 0u) << failures(c);
    static constexpr double kBary[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.5, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5},
                                           {2.0 / 3, 1.0 / 6, 1.0 / 6}, {1.0 / 6, 2.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 2.0 / 3}};
    double worst = 0;
    std::size_t on_one_facet = 0;
    for (std::size_t k = 0; k < vm.boundary.size(); k += 3) {
      const double* p[3];
      for (int i = 0; i < 3; ++i) p[i] = vm.nodes.points.p(vm.boundary[k + i]);
      double cen[3], face = 0;
      for (int d = 0; d < 3; ++d) cen[d] = (p[0][d] + p[1][d] + p[2][d]) / 3;
      for (const auto& w : kBary) {
        double x[3];
        for (int d = 0; d < 3; ++d) x[d] = w[0] * p[0][d] + w[1] * p[1][d] + w[2] * p[2][d];
        face = std::max(face, q.distance(x));
      }
      worst = std::max(worst, face / h(cen));
      const std::uint32_t f0 = vm.nodes.facet[vm.boundary[k]];
      on_one_facet += f0 == vm.nodes.facet[vm.boundary[k + 1]] && f0 == vm.nodes.facet[vm.boundary[k + 2]];
    }
    EXPECT_NEAR(c.max_hausdorff, worst, 1e-12) << levels;
    if (levels == 2) {
      EXPECT_GT(on_one_facet, 0u);
    }
    if (levels == 4) {
      EXPECT_GT(worst, 1e-3);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The checker on broken meshes: each defect must be reported.
class CheckNegative : public ::testing::Test {
 protected:
  void SetUp() override {
    vx = Voxels::block(1, 1, 1, 1.0);
    s = voxel_surface(vx);
    q = std::make_unique<SurfaceQuery>(s.mesh);
    h = uniform_size(s, 0.25);
    vm = mesh_volume({s, *q, h}, voxel_nodes(vx, s, *q, 4));
    ASSERT_TRUE(check_volume_mesh(vm, {s, *q, h}).ok());
  }
  static bool mentions(const MeshCheck& c, const std::string& what) {
    for (auto& f : c.failures)
      if (f.find(what) != std::string::npos) return true;
    return false;
  }
  Voxels vx;
  PreparedSurface s;
  std::unique_ptr<SurfaceQuery> q;
  SizingField h;
  VolumeMesh vm;
};

// Removing an interior tet (all of its vertices interior) opens a hole: its four faces
// become boundary faces off the surface, and the volume drops by its volume.
TEST_F(CheckNegative, MissingTet) {
  std::size_t victim = vm.num_tets();
  for (std::size_t t = 0; t < vm.num_tets() && victim == vm.num_tets(); ++t) {
    bool all_interior = true;
    for (int i = 0; i < 4; ++i) all_interior &= vm.nodes.kind[vm.tets[4 * t + i]] == NodeKind::interior;
    if (all_interior) victim = t;
  }
  ASSERT_LT(victim, vm.num_tets());
  vm.tets.erase(vm.tets.begin() + 4 * std::ptrdiff_t(victim), vm.tets.begin() + 4 * std::ptrdiff_t(victim) + 4);
  vm.tet_region.erase(vm.tet_region.begin() + std::ptrdiff_t(victim));
  const MeshCheck c = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_GE(c.offsurface_vertices, 4u);  // the victim's four interior vertices
  EXPECT_GE(c.offsurface_faces, 4u);
  EXPECT_TRUE(mentions(c, "boundary list")) << failures(c);
  EXPECT_TRUE(mentions(c, "off the surface")) << failures(c);
}

// Removing a tet with a face on the surface leaves a notch: the check names the face(s).
TEST_F(CheckNegative, MissingBoundaryTetIsAnOpenBoundaryAtTheSurface) {
  const std::size_t victim = vm.boundary_tet[0];
  vm.tets.erase(vm.tets.begin() + 4 * std::ptrdiff_t(victim), vm.tets.begin() + 4 * std::ptrdiff_t(victim) + 4);
  vm.tet_region.erase(vm.tet_region.begin() + std::ptrdiff_t(victim));
  const MeshCheck c = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_GT(c.offsurface_faces + c.offsurface_vertices, 0u) << failures(c);
}

// An extra tet outside the cube (sharing a boundary face, apex 0.3 out): outside centroid,
// an off-surface vertex, wrong volume.
TEST_F(CheckNegative, ExtraOutsideTet) {
  const std::uint32_t* f = &vm.boundary[0];
  const double *a = vm.nodes.points.p(f[0]), *b = vm.nodes.points.p(f[1]), *c0 = vm.nodes.points.p(f[2]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c0[0] - a[0], c0[1] - a[1], c0[2] - a[2]};
  double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  double apex[3];
  for (int k = 0; k < 3; ++k) apex[k] = (a[k] + b[k] + c0[k]) / 3 + 0.3 * n[k] / len;
  vm.nodes.push_back(apex, NodeKind::surface, 0, 0.25f);
  const std::uint32_t id = std::uint32_t(vm.nodes.points.size() - 1);
  // Outward face (f0,f1,f2) with the apex on the side its normal points to: positive.
  vm.tets.insert(vm.tets.end(), {f[0], f[1], f[2], id});
  vm.tet_region.push_back(0);
  ASSERT_GT(pred::orient3d(vm.nodes.points.p(f[0]), vm.nodes.points.p(f[1]), vm.nodes.points.p(f[2]), apex), 0);
  const MeshCheck c = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.outside_tets, 1u);
  EXPECT_EQ(c.nonpositive_tets, 0u);
  EXPECT_GE(c.offsurface_vertices, 1u);
  EXPECT_TRUE(mentions(c, "not strictly inside")) << failures(c);
  EXPECT_TRUE(mentions(c, "tet " + std::to_string(vm.num_tets() - 1))) << failures(c);
  // The boundary faces are halves of the 0.25 x 0.25 surface squares (area 1/32), so the extra
  // tet adds (1/32) * 0.3 / 3 = 0.003125 to the unit cube's volume (below the 0.5% tolerance:
  // the centroid test is what catches it).
  EXPECT_NEAR(c.volume_error, 0.003125, 1e-12);
}

// A surface node pushed 0.02 off the cube, keeping the facet it records: its facet no longer
// certifies it, so the tree measures it, and the faces at it are measured too.
TEST_F(CheckNegative, SurfaceNodeOffItsFacetIsMeasured) {
  std::uint32_t v = 0;
  while (v < vm.nodes.points.size() && vm.nodes.kind[v] != NodeKind::surface) ++v;
  ASSERT_LT(v, vm.nodes.points.size());
  double* p = vm.nodes.points.xyz.data() + 3 * std::size_t(v);
  int axis = 0;  // the cube face it lies on: the coordinate at 0 or 1
  for (int k = 0; k < 3; ++k)
    if (p[k] == 0 || p[k] == 1) axis = k;
  p[axis] += p[axis] == 0 ? -0.02 : 0.02;  // outward
  const MeshCheck c = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.offsurface_vertices, 1u);
  EXPECT_TRUE(mentions(c, "(distance 0.02")) << failures(c);
  EXPECT_NEAR(c.max_hausdorff, 0.02 / 0.25 * 2.0 / 3.0, 1e-12) << failures(c);  // its faces' samples
}

// Swapping two vertices of one tet inverts it.
TEST_F(CheckNegative, InvertedTet) {
  std::swap(vm.tets[4 * 5 + 0], vm.tets[4 * 5 + 1]);
  const MeshCheck c = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.nonpositive_tets, 1u);
  EXPECT_TRUE(mentions(c, "not positively oriented (exact orient3d <= 0), e.g. tet 5")) << failures(c);
}

// A tet whose volume is positive only at rounding level (the gear box had 23 such surface
// slivers before they were classified outside) is a zero-volume element: reported.
TEST_F(CheckNegative, ZeroVolumeTetAtRoundingLevel) {
  const std::uint32_t* v = &vm.tets[4 * 5];
  // Move the 4th vertex of tet 5 onto the plane of the other three, plus 1e-14 of the
  // normal: exactly positive for orient3d, volume-length ~1e-14.
  double a[3], b[3], c[3];  // copies: push_back below may move the coordinates
  for (int k = 0; k < 3; ++k) {
    a[k] = vm.nodes.points.p(v[0])[k];
    b[k] = vm.nodes.points.p(v[1])[k];
    c[k] = vm.nodes.points.p(v[2])[k];
  }
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const double p[3] = {(a[0] + b[0] + c[0]) / 3 + 1e-14 * n[0] / nn * 8,
                       (a[1] + b[1] + c[1]) / 3 + 1e-14 * n[1] / nn * 8,
                       (a[2] + b[2] + c[2]) / 3 + 1e-14 * n[2] / nn * 8};
  vm.nodes.push_back(p, NodeKind::interior, kNoFacet, 1.0f);
  vm.tets[4 * 5 + 3] = std::uint32_t(vm.nodes.size_count() - 1);
  ASSERT_GT(pred::orient3d(a, b, c, p), 0);
  const MeshCheck c2 = check_volume_mesh(vm, {s, *q, h});
  EXPECT_FALSE(c2.ok());
  EXPECT_EQ(c2.flat_tets, 1u);
  EXPECT_TRUE(mentions(c2, "zero volume at rounding level")) << failures(c2);
}

/// Unit cubes at the given integer offsets, each split into the 6 Kuhn tets (0, e_a, e_a+e_b, 1),
/// shared corners merged: a mesh built by hand for the topology figures of the checker.
VolumeMesh kuhn_cubes(const std::vector<std::array<int, 3>>& offsets) {
  VolumeMesh vm;
  std::map<std::array<int, 3>, std::uint32_t> ids;
  auto id = [&](int x, int y, int z) {
    auto [it, fresh] = ids.try_emplace({x, y, z}, std::uint32_t(ids.size()));
    if (fresh) {
      const double p[3] = {double(x), double(y), double(z)};
      vm.nodes.push_back(p, NodeKind::surface, 0, 1.0f);
    }
    return it->second;
  };
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& o : offsets)
    for (auto& pm : perms) {
      int p[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1, 1, 1}};
      p[1][pm[0]] = 1;
      p[2][pm[0]] = 1, p[2][pm[1]] = 1;
      std::uint32_t v[4];
      for (int i = 0; i < 4; ++i) v[i] = id(o[0] + p[i][0], o[1] + p[i][1], o[2] + p[i][2]);
      if (pred::orient3d(vm.nodes.points.p(v[0]), vm.nodes.points.p(v[1]), vm.nodes.points.p(v[2]),
                         vm.nodes.points.p(v[3])) < 0)
        std::swap(v[2], v[3]);
      vm.tets.insert(vm.tets.end(), v, v + 4);
      vm.tet_region.push_back(0);
    }
  return vm;
}

// Two cubes sharing only the edge x = y = 1: that edge is in 4 boundary faces (2 per cube:
// each cube's two faces through it, x = 1 and y = 1, each triangulated with a triangle on the
// edge), so exactly one boundary edge is not in exactly two faces.
TEST(CheckVolumeMesh, NonManifoldEdgeIsCounted) {
  const VolumeMesh vm = kuhn_cubes({{0, 0, 0}, {1, 1, 0}});
  const PreparedSurface s = voxel_surface(Voxels::block(2, 2, 1, 1.0));
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 1.0);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.nonpositive_tets, 0u);
  EXPECT_EQ(c.open_edges, 1u) << failures(c);
  EXPECT_NEAR(c.mesh_volume, 2.0, 1e-12);
  EXPECT_EQ(c.boundary_faces, 24u);  // 2 x 6 squares x 2 triangles
}

// Two cubes sharing only the corner (1,1,1): every edge is in two faces, but the faces around
// that vertex form two fans.
TEST(CheckVolumeMesh, NonManifoldVertexIsCounted) {
  const VolumeMesh vm = kuhn_cubes({{0, 0, 0}, {1, 1, 1}});
  const PreparedSurface s = voxel_surface(Voxels::block(2, 2, 2, 1.0));
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 1.0);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.open_edges, 0u) << failures(c);
  EXPECT_EQ(c.nonmanifold_vertices, 1u) << failures(c);
  bool named = false;
  for (auto& f : c.failures) named |= f.find("(1, 1, 1) (2 fans)") != std::string::npos;
  EXPECT_TRUE(named) << failures(c);
}

// Eight cubes along the diagonal (i, i, 0) share seven edges, each in 4 boundary faces; eight
// along (i, i, i) share seven corners, each with 2 fans. The checker counts all seven and names
// the first five in the order of one sort of them all: edges by their ends' node ids, vertices
// by id. (Both walks were sorts of every (vertex, face) or edge on one core; they now group
// by vertex on all threads, 2026-12.)
TEST(CheckVolumeMesh, OpenEdgesAndFansAreAllCountedAndNamedInIdOrder) {
  auto node_id = [](const VolumeMesh& vm, int x, int y, int z) {
    for (std::uint32_t v = 0; v < vm.nodes.points.size(); ++v) {
      const double* p = vm.nodes.points.p(v);
      if (p[0] == x && p[1] == y && p[2] == z) return v;
    }
    ADD_FAILURE() << "no node at " << x << " " << y << " " << z;
    return std::uint32_t(0);
  };
  auto at = [](int x, int y, int z) {
    return "(" + std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(z) + ")";
  };
  // Eight cubes at (i, i, dz * i), checked against the block of voxels holding them.
  auto checked_chain = [](int dz, VolumeMesh& vm) {
    std::vector<std::array<int, 3>> offsets;
    for (int i = 0; i < 8; ++i) offsets.push_back({i, i, dz * i});
    vm = kuhn_cubes(offsets);
    const PreparedSurface s = voxel_surface(Voxels::block(8, 8, dz ? 8 : 1, 1.0));
    const SurfaceQuery q(s.mesh);
    const SizingField h = uniform_size(s, 1.0);
    return check_volume_mesh(vm, {s, q, h});
  };
  {
    VolumeMesh vm;
    const MeshCheck c = checked_chain(0, vm);
    EXPECT_EQ(c.open_edges, 7u) << failures(c);
    EXPECT_EQ(c.nonmanifold_vertices, 0u) << failures(c);
    std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::string>> edges;
    for (int i = 1; i < 8; ++i) {
      std::uint32_t a = node_id(vm, i, i, 0), b = node_id(vm, i, i, 1);
      std::string text = " " + at(i, i, 0) + "-" + at(i, i, 1);
      if (a > b) std::swap(a, b), text = " " + at(i, i, 1) + "-" + at(i, i, 0);
      edges.push_back({{a, b}, text + " in 4 face(s)"});
    }
    std::sort(edges.begin(), edges.end());
    std::string want = "7 boundary edge(s) not in exactly two boundary faces, e.g.";
    for (std::size_t k = 0; k < 5; ++k) want += edges[k].second;
    EXPECT_NE(failures(c).find(want + "\n"), std::string::npos) << want << "\n" << failures(c);
  }
  {
    VolumeMesh vm;
    const MeshCheck c = checked_chain(1, vm);
    EXPECT_EQ(c.open_edges, 0u) << failures(c);
    EXPECT_EQ(c.nonmanifold_vertices, 7u) << failures(c);
    std::vector<std::pair<std::uint32_t, std::string>> corners;
    for (int i = 1; i < 8; ++i) {
      const std::uint32_t v = node_id(vm, i, i, i);
      corners.push_back({v, " " + std::to_string(v) + " at " + at(i, i, i) + " (2 fans)"});
    }
    std::sort(corners.begin(), corners.end());
    std::string want = "7 non-manifold boundary vertex(es), e.g.";
    for (std::size_t k = 0; k < 5; ++k) want += corners[k].second;
    EXPECT_NE(failures(c).find(want + "\n"), std::string::npos) << want << "\n" << failures(c);
  }
}

// A tet given twice (the face records of the check were made 16 bytes in 2026-11; this pins
// what they must still find): the first Kuhn tet's two faces inside the cube are then in
// three tets, and its two faces on the cube's boundary in two tets that see them the same way.
TEST(CheckVolumeMesh, DuplicatedTetGivesOverfullAndSameSideFaces) {
  VolumeMesh vm = kuhn_cubes({{0, 0, 0}});
  vm.tets.insert(vm.tets.end(), vm.tets.begin(), vm.tets.begin() + 4);
  vm.tet_region.push_back(0);
  const PreparedSurface s = voxel_surface(Voxels::block(1, 1, 1, 1.0));
  const SurfaceQuery q(s.mesh);
  const SizingField h = uniform_size(s, 1.0);
  const MeshCheck c = check_volume_mesh(vm, {s, q, h});
  EXPECT_FALSE(c.ok());
  EXPECT_NE(failures(c).find("2 face(s) shared by more than two tets"), std::string::npos) << failures(c);
  EXPECT_NE(failures(c).find(" in 3 tets"), std::string::npos) << failures(c);
  EXPECT_NE(failures(c).find("2 face(s) whose two tets lie on the same side"), std::string::npos) << failures(c);
  EXPECT_NE(failures(c).find("tets 0/6"), std::string::npos) << failures(c);
  EXPECT_EQ(c.boundary_faces, 10u);  // the cube's 12, less the duplicated tet's two
  EXPECT_EQ(c.nonpositive_tets, 0u);
}

}  // namespace
}  // namespace kdmesh
