// kdmesh — tests of node placement (corners, feature edges, surface, interior) and of the
// size fidelity measure.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "mesher/placement/edge_sampling.h"
#include "mesher/placement/interior_fill.h"
#include "mesher/placement/node_placement.h"
#include "mesher/quality/size_fidelity.h"
#include "mesher/placement/spacing_grid.h"
#include "mesher/placement/surface_sampling.h"

namespace kdmesh {
namespace {

struct Model {
  PreparedSurface surface;
  FeatureEdges features;
};

void finish(Model& m) {
  PreparedSurface& s = m.surface;
  s.tri_shell.assign(s.mesh.num_tris(), 0);
  s.shell_body = {0};
  s.shell_parent = {kNoFacet};
  s.num_bodies = 1;
  for (int a = 0; a < 3; ++a) {
    s.bbox_min[a] = INFINITY;
    s.bbox_max[a] = -INFINITY;
  }
  for (std::size_t i = 0; i < s.mesh.points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      s.bbox_min[a] = std::min(s.bbox_min[a], s.mesh.points.p(std::uint32_t(i))[a]);
      s.bbox_max[a] = std::max(s.bbox_max[a], s.mesh.points.p(std::uint32_t(i))[a]);
    }
  s.shell_volume = {s.volume};
}

/// Box [0,lx] x [0,ly] x [0,lz]: 12 outward facets; its 12 edges are features, its 8
/// vertices corners (vertex i = (lx*(i&1), ly*(i>>1&1), lz*(i>>2&1))).
Model box(double lx, double ly, double lz) {
  Model m;
  for (int i = 0; i < 8; ++i)
    m.surface.mesh.points.push_back(lx * (i & 1), ly * (i >> 1 & 1), lz * (i >> 2 & 1));
  m.surface.mesh.tris = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                         2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  m.features.edges = {0, 1, 0, 2, 0, 4, 1, 3, 1, 5, 2, 3, 2, 6, 3, 7, 4, 5, 4, 6, 5, 7, 6, 7};
  m.features.corners = {0, 1, 2, 3, 4, 5, 6, 7};
  m.surface.volume = lx * ly * lz;
  finish(m);
  return m;
}

/// n-gon prism of circumradius r and height H (axis z from 0 to H); the two rims are
/// corner-free feature loops (rim i: points i*n .. i*n+n-1), the centres are 2n and 2n+1.
Model cylinder(double r, double H, std::uint32_t n) {
  Model m;
  auto& P = m.surface.mesh.points;
  for (int k = 0; k < 2; ++k)
    for (std::uint32_t i = 0; i < n; ++i) {
      const double t = 2 * std::numbers::pi * i / n;
      P.push_back(r * std::cos(t), r * std::sin(t), k * H);
    }
  P.push_back(0, 0, 0);
  P.push_back(0, 0, H);
  const std::uint32_t cb = 2 * n, ct = 2 * n + 1;
  auto& T = m.surface.mesh.tris;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    T.insert(T.end(), {i, j, n + j, i, n + j, n + i, cb, j, i, ct, n + i, n + j});
    for (const std::uint32_t o : {0u, n}) {
      m.features.edges.push_back(std::min(o + i, o + j));
      m.features.edges.push_back(std::max(o + i, o + j));
    }
  }
  // Sorted, as FeatureEdges asks.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
  for (std::size_t k = 0; k < m.features.edges.size(); k += 2)
    e.emplace_back(m.features.edges[k], m.features.edges[k + 1]);
  std::sort(e.begin(), e.end());
  m.features.edges.clear();
  for (const auto& [a, b] : e) m.features.edges.insert(m.features.edges.end(), {a, b});
  m.surface.volume = 0.5 * n * r * r * std::sin(2 * std::numbers::pi / n) * H;
  finish(m);
  return m;
}

SizingField uniform(const Model& m, double h) {
  SizingOptions o;
  o.max_size = h;
  return build_sizing_field(m.surface.mesh, o);
}

/// h_max far away, `size` at the point `at`, gradation 0.3.
SizingField point_zone_field(const SurfaceMesh& s, double max_size, double size,
                             const std::array<double, 3>& at) {
  SizingOptions o;
  o.max_size = max_size;
  o.gradation = 0.3;
  SizingZone z;
  z.kind = SizingZone::Kind::point;
  z.size = size;
  z.coords = {at[0], at[1], at[2]};
  o.zones.push_back(z);
  return build_sizing_field(s, o);
}

double dist(const double* a, const double* b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

/// The smallest distance between two nodes, by brute force over all pairs.
double closest_pair(const NodeSet& ns) {
  double d = INFINITY;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i)
    for (std::uint32_t j = i + 1; j < ns.size_count(); ++j) d = std::min(d, dist(ns.points.p(i), ns.points.p(j)));
  return d;
}

/// Distance of p to the plane of facet f, and its barycentric coordinates in f (from
/// sub-triangle areas projected on the facet normal).
void facet_coords(const SurfaceMesh& s, std::uint32_t f, const double* p, double* plane_dist,
                  double* bary) {
  const std::uint32_t* t = s.tri(f);
  const double* v[3] = {s.points.p(t[0]), s.points.p(t[1]), s.points.p(t[2])};
  auto cross = [](const double* a, const double* b, const double* c, double* n) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
  };
  double n[3];
  cross(v[0], v[1], v[2], n);
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  *plane_dist = std::fabs((p[0] - v[0][0]) * n[0] + (p[1] - v[0][1]) * n[1] +
                          (p[2] - v[0][2]) * n[2]) / std::sqrt(nn);
  for (int i = 0; i < 3; ++i) {
    double m[3];
    cross(p, v[(i + 1) % 3], v[(i + 2) % 3], m);
    bary[i] = (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) / nn;
  }
}

std::size_t count(const NodeSet& ns, NodeKind k) {
  return std::size_t(std::count(ns.kind.begin(), ns.kind.end(), k));
}

// ---- surface nodes lie on their facet ----

void expect_surface_nodes_on_facets(const Model& m, const NodeSet& ns, double extent) {
  const SurfaceMesh& s = m.surface.mesh;
  std::size_t checked = 0;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i) {
    if (ns.kind[i] == NodeKind::interior) {
      EXPECT_EQ(ns.facet[i], kNoFacet) << "interior node " << i;
      continue;
    }
    ASSERT_LT(ns.facet[i], s.num_tris()) << "node " << i;
    double d, b[3];
    facet_coords(s, ns.facet[i], ns.points.p(i), &d, b);
    EXPECT_LE(d, 1e-12 * extent) << "node " << i << " is off the plane of facet " << ns.facet[i];
    for (int k = 0; k < 3; ++k)
      EXPECT_GE(b[k], -1e-12) << "node " << i << " is outside facet " << ns.facet[i];
    EXPECT_NEAR(b[0] + b[1] + b[2], 1.0, 1e-12);
    ++checked;
  }
  EXPECT_GT(checked, 0u);
}

TEST(NodePlacement, BoxSurfaceNodesLieOnTheirFacet) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, 0.1)}, m.features);
  expect_surface_nodes_on_facets(m, ns, 1.3);
}

TEST(NodePlacement, CylinderSurfaceNodesLieOnTheirFacet) {
  const Model m = cylinder(0.5, 1, 48);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, 0.08)}, m.features);
  expect_surface_nodes_on_facets(m, ns, 1);
  // The rims are feature loops: edge nodes exist and lie on z = 0 or z = 1 at radius <= r.
  std::size_t rim = 0;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i)
    if (ns.kind[i] == NodeKind::edge) {
      ++rim;
      const double* p = ns.points.p(i);
      EXPECT_TRUE(p[2] == 0 || p[2] == 1) << "edge node " << i << " z = " << p[2];
      EXPECT_LE(std::hypot(p[0], p[1]), 0.5 + 1e-12);
    }
  // Each rim: perimeter 48 * 2 r sin(pi/48) = 3.1394 long, h = 0.08: round(39.24) = 39
  // pieces, so 39 nodes per loop (the loop start is an edge node, no corners).
  EXPECT_EQ(rim, 2u * 39u);
}

// ---- interior nodes: strictly inside, clear of the surface ----

void expect_interior_clear(const Model& m, const NodeSet& ns, const SizingField& h,
                           double clearance) {
  const SurfaceQuery q(m.surface.mesh);
  std::size_t n = 0;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i) {
    if (ns.kind[i] != NodeKind::interior) continue;
    ++n;
    const double* p = ns.points.p(i);
    EXPECT_EQ(q.side(p), 1) << "interior node " << i;
    EXPECT_GE(q.distance(p), clearance * h(p)) << "interior node " << i;
  }
  EXPECT_GT(n, 0u);
}

TEST(NodePlacement, BoxInteriorNodesInsideAndClear) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const SizingField h = uniform(m, 0.1);
  const NodeSet ns = place_nodes({m.surface, q, h}, m.features);
  expect_interior_clear(m, ns, h, PlacementOptions{}.interior_clearance);
}

TEST(NodePlacement, CylinderInteriorNodesInsideAndClearWithOtherClearance) {
  const Model m = cylinder(0.5, 1, 48);
  const SurfaceQuery q(m.surface.mesh);
  const SizingField h = uniform(m, 0.08);
  PlacementOptions o;
  o.interior_clearance = 1.3;
  const NodeSet ns = place_nodes({m.surface, q, h}, m.features, o);
  expect_interior_clear(m, ns, h, 1.3);
}

/// The lattice nodes of fill_interior in a box (no boundary layer) and the nearest-neighbour
/// vectors of those well inside it.
struct LatticeSample {
  NodeSet nodes;
  std::vector<std::array<double, 3>> neighbour_vectors;
};

LatticeSample fill_box_lattice(bool rotate, double h) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const SizingField field = uniform(m, h);
  InteriorFillOptions o;
  o.rotate_lattice = rotate;
  o.layer_tries = 0;
  const double glo[3] = {-1, -1, -1};
  SpacingGrid grid(glo, h / 4);
  LatticeSample r;
  fill_interior(m.surface.mesh, m.surface.bbox_min, m.surface.bbox_max, q, field, o, grid, r.nodes);
  const double a = o.kappa * h;  // one level: h is uniform
  for (std::uint32_t i = 0; i < r.nodes.size_count(); ++i) {
    const double* p = r.nodes.points.p(i);
    if (q.distance(p) < 2 * a) continue;
    for (std::uint32_t j = 0; j < r.nodes.size_count(); ++j) {
      const double* s = r.nodes.points.p(j);
      if (j != i && dist(p, s) < 0.9 * a)  // the 8 body-diagonal neighbours, a sqrt3/2 away
        r.neighbour_vectors.push_back({s[0] - p[0], s[1] - p[1], s[2] - p[2]});
    }
  }
  return r;
}

/// The smallest angle (deg) between any of the vectors and a coordinate plane.
double least_angle_to_axis_planes(const std::vector<std::array<double, 3>>& vs) {
  double least = 90;
  for (const auto& v : vs) {
    const double n = std::hypot(v[0], v[1], v[2]);
    for (const double c : v) least = std::min(least, std::asin(std::abs(c) / n) * 180 / std::numbers::pi);
  }
  return least;
}

// Regression, handle.ply (issue 18): an axis-aligned lattice put rows of interior nodes in
// one plane with rows of surface nodes on the axis-aligned creases of a faceted scan, and the
// quality pass could not undo the sheets of slivers between them (7.7 deg at diag/80). The
// lattice is turned now, and exactly: every node is q M U for an integer vector U of one
// parity (M = kLatticeAxes, q = kappa h / 14 rounded to 16 bits), so the lattice's own ties
// stay exact (a rotation in floating point made the gear box drop 7,610 nodes as flat).
TEST(InteriorFill, LatticeIsTurnedOffTheAxesAndExact) {
  const double h = 0.1;
  const LatticeSample turned = fill_box_lattice(true, h);
  ASSERT_GT(turned.neighbour_vectors.size(), 100u);
  // The BCC neighbours lie along the turned <111> directions, all >= 4.7 deg off every
  // coordinate plane (the axis-aligned lattice's lie 35.3 deg off; its <100> rows on them).
  EXPECT_GT(least_angle_to_axis_planes(turned.neighbour_vectors), 4.7);
  const double kM[3][3] = {{6, 3, 2}, {2, -6, 3}, {3, -2, -6}};
  int e = 0;
  const double mantissa = std::frexp(InteriorFillOptions{}.kappa * h / 14, &e);
  const double q = std::ldexp(std::nearbyint(std::ldexp(mantissa, 16)), e - 16);
  for (std::uint32_t i = 0; i < turned.nodes.size_count(); ++i) {
    const double* p = turned.nodes.points.p(i);
    double u[3];
    for (int ax = 0; ax < 3; ++ax)  // U = M^T p / (49 q), exact for an exact lattice point
      u[ax] = (kM[0][ax] * p[0] + kM[1][ax] * p[1] + kM[2][ax] * p[2]) / (49 * q);
    for (int ax = 0; ax < 3; ++ax) {
      ASSERT_NEAR(u[ax], std::nearbyint(u[ax]), 1e-6) << "node " << i;
      const std::int64_t U[3] = {std::llround(u[0]), std::llround(u[1]), std::llround(u[2])};
      ASSERT_EQ(U[0] & 1, U[ax] & 1) << "node " << i << ": mixed parity";
      // ... and its coordinates are exactly q M U.
      const double exact = q * double(std::int64_t(kM[ax][0]) * U[0] +
                                      std::int64_t(kM[ax][1]) * U[1] + std::int64_t(kM[ax][2]) * U[2]);
      ASSERT_EQ(p[ax], exact) << "node " << i << " axis " << ax;
    }
  }
  // With the option off, the rows are the coordinate axes' <111> diagonals again.
  const LatticeSample aligned = fill_box_lattice(false, h);
  EXPECT_NEAR(least_angle_to_axis_planes(aligned.neighbour_vectors), 35.26, 0.01);
}

// The lattice's candidates are every lattice point inside the box and clear of its faces, of
// its own level: brute force over a range of U wider than the box, level by level, with the
// level rule of InteriorFillOptions::rho (round(log_rho(h_max / h(p))), clamped). Each block
// enumerates only the U whose image box over the block's corners holds them (the range of i
// rounded inwards; rounded outwards, the gear box tried 792M points for 23M in their blocks),
// and takes a size inside its level's range narrowed by 1e-9 as that level without the
// logarithm. A range cut too far would lose points at the blocks' borders, which the octree
// puts all through the box; a wrong level range would move points between levels.
TEST(InteriorFill, CandidatesAreEveryLatticePointOfItsLevelInsideAndClear) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const SizingField fields[3] = {uniform(m, 0.1), uniform(m, 0.043),
                                 point_zone_field(m.surface.mesh, 0.12, 0.035, {0.3, 0.7, 0.2})};
  const double smallest[3] = {0.1, 0.043, 0.035};  // the least size each field takes
  for (const SizingField& field : fields) {
    const std::size_t f = std::size_t(&field - fields);
    for (const bool rotate : {true, false}) {
      InteriorFillOptions o;
      o.rotate_lattice = rotate;
      o.layer_tries = 0;
      const double glo[3] = {-1, -1, -1};
      SpacingGrid grid(glo, field.min_size() / 4);
      grid.set_lipschitz(field.options().gradation);
      NodeSet ns;
      const InteriorFillStats st =
          fill_interior(m.surface.mesh, m.surface.bbox_min, m.surface.bbox_max, q, field, o, grid, ns);
      const double hmax = field.max_size(), hmin = std::min(field.min_size(), hmax);
      const int max_level = int(std::lround(std::log(hmax / hmin) / std::log(o.rho))) + 1;
      auto level_of = [&](double h) {
        return std::clamp(int(std::lround(std::log(hmax / h) / std::log(o.rho))), 0, max_level);
      };
      // Level k's lattice: q M U, U all even or all odd, q = kappa h_max rho^-k / 14 rounded to
      // 16 bits (the test above).
      const std::int64_t kM[3][3] = {{6, 3, 2}, {2, -6, 3}, {3, -2, -6}};
      const std::int64_t kI[3][3] = {{7, 0, 0}, {0, 7, 0}, {0, 0, 7}};
      const std::int64_t(&M)[3][3] = rotate ? kM : kI;
      const double hi[3] = {1, 1.3, 0.7};
      std::size_t expected = 0;
      std::set<int> levels;
      // (Levels of sizes the field never takes have no points: min_size() is a lower bound.)
      for (int k = level_of(hmax); k <= level_of(smallest[f]); ++k) {
        int e = 0;
        const double mantissa = std::frexp(o.kappa * hmax * std::pow(o.rho, -double(k)) / 14, &e);
        const double qs = std::ldexp(std::nearbyint(std::ldexp(mantissa, 16)), e - 16);
        const std::int64_t r = std::int64_t(1.8 / qs / 7) + 4;  // |U_i| <= |p| / (7 q), |p| < 1.78
        for (std::int64_t a = -r; a <= r; ++a)
          for (std::int64_t b = -r; b <= r; ++b)
            for (std::int64_t c = -r; c <= r; ++c) {
              if ((a & 1) != (b & 1) || (a & 1) != (c & 1)) continue;
              double p[3];
              bool in = true;
              for (int ax = 0; ax < 3 && in; ++ax) {
                p[ax] = qs * double(M[ax][0] * a + M[ax][1] * b + M[ax][2] * c);
                in = p[ax] > 0 && p[ax] < hi[ax];
              }
              if (!in) continue;
              const double h = field(p);
              if (level_of(h) == k && q.distance(p) >= o.clearance * h) ++expected, levels.insert(k);
            }
      }
      EXPECT_GT(expected, 500u) << "field " << f;
      if (f == 2) {
        EXPECT_GE(levels.size(), 3u);  // the graded field's points: 3 levels or more
      }
      EXPECT_EQ(st.candidates, expected) << "field " << f << " rotate " << rotate;
    }
  }
}

// ---- corners and feature edges ----

TEST(NodePlacement, BoxCornersArePresentAsCornerNodes) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, 0.1)}, m.features);
  ASSERT_EQ(count(ns, NodeKind::corner), 8u);
  std::set<std::vector<double>> corners, expected;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i)
    if (ns.kind[i] == NodeKind::corner) {
      const double* p = ns.points.p(i);
      corners.insert({p[0], p[1], p[2]});
    }
  for (int i = 0; i < 8; ++i) expected.insert({1.0 * (i & 1), 1.3 * (i >> 1 & 1), 0.7 * (i >> 2 & 1)});
  EXPECT_EQ(corners, expected);
}

TEST(NodePlacement, UniformEdgeSpacingIsLengthOverRoundedCount) {
  // With h uniform, the integral of ds/h along an edge of length L is I = L/h, the edge is
  // cut into n = round(L/h) pieces of equal I/n, i.e. equal length L/n. Box 1 x 1.3 x 0.7,
  // h = 0.12: x edges 1/0.12 = 8.33 -> 8 pieces of 0.125; y edges 1.3/0.12 = 10.83 -> 11 of
  // 0.11818...; z edges 0.7/0.12 = 5.83 -> 6 of 0.11666...
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, 0.12)}, m.features);
  const double L[3] = {1, 1.3, 0.7};
  const int pieces[3] = {8, 11, 6};
  EXPECT_EQ(count(ns, NodeKind::edge), std::size_t(4 * (7 + 10 + 5)));
  for (int axis = 0; axis < 3; ++axis) {
    // The edge along `axis` through the origin: the other two coordinates are 0.
    std::vector<double> t = {0, L[axis]};  // its two corners
    for (std::uint32_t i = 0; i < ns.size_count(); ++i) {
      if (ns.kind[i] != NodeKind::edge) continue;
      const double* p = ns.points.p(i);
      if (p[(axis + 1) % 3] == 0 && p[(axis + 2) % 3] == 0) t.push_back(p[axis]);
    }
    std::sort(t.begin(), t.end());
    ASSERT_EQ(t.size(), std::size_t(pieces[axis] + 1)) << "axis " << axis;
    for (std::size_t k = 1; k < t.size(); ++k)
      EXPECT_NEAR(t[k] - t[k - 1], L[axis] / pieces[axis], 1e-12) << "axis " << axis;
  }
}

TEST(NodePlacement, ClosedLoopStartsAtItsSmallestPoint) {
  const Model m = cylinder(0.5, 1, 12);
  const std::vector<FeaturePolyline> lines = chain_feature_edges(m.surface.mesh, m.features);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_TRUE(lines[0].closed);
  EXPECT_TRUE(lines[1].closed);
  EXPECT_EQ(lines[0].points.front(), 0u);
  EXPECT_EQ(lines[0].points.back(), 0u);
  EXPECT_EQ(lines[1].points.front(), 12u);
  EXPECT_EQ(lines[0].points.size(), 13u);  // 12 edges, the start repeated at the end
}

TEST(NodePlacement, FeatureEdgeOutsideTheSurfaceIsAUsageError) {
  Model m = box(1, 1, 1);
  m.features.edges.push_back(7);
  m.features.edges.push_back(99);
  EXPECT_THROW(chain_feature_edges(m.surface.mesh, m.features), UsageError);
}

// ---- spacing and counts ----

// Two feature curves that leave a corner at a small angle got nodes a fraction of h apart (the
// first node of each at h from the corner): homer.ply, femur.ply and lever.stl kept tets under
// 5 deg on such pairs, 0.01-0.06 h long. An edge node closer than beta (h_p + h_q) / 2 to a
// node already placed is left out; the other curve keeps its nodes where the two are apart.
TEST(NodePlacement, RegressionHomerFeatureCurvesAtASmallAngleKeepTheirNodesApart) {
  Model m;
  // Corner C = 0; the curves C-A and C-B, 5.7 deg apart, on a flat sheet with D and E.
  for (const auto& p : std::vector<std::array<double, 3>>{{0, 0, 0}, {10, 0.5, 0}, {10, -0.5, 0}, {0, 5, 0}, {0, -5, 0}})
    m.surface.mesh.points.push_back(p[0], p[1], p[2]);
  m.surface.mesh.tris = {0, 2, 1, 0, 1, 3, 0, 4, 2};
  m.features.edges = {0, 1, 0, 2};
  m.features.corners = {0, 1, 2};
  finish(m);
  const double h = 1;
  const SizingField sizing = uniform(m, h);
  const double lo[3] = {-20, -20, -20};
  auto place = [&](double beta) {
    SpacingGrid grid(lo, h);
    NodeSet nodes;
    place_edge_nodes(m.surface.mesh, m.features, sizing, beta, grid, nodes);
    EXPECT_EQ(grid.size(), nodes.size_count());
    return nodes;
  };
  const NodeSet all = place(0), thinned = place(0.3);
  EXPECT_LT(closest_pair(all), 0.11 * h);  // 2 h sin(2.86 deg) = 0.1 h at the first nodes
  EXPECT_GE(closest_pair(thinned), 0.3 * h);
  // Both curves keep nodes where they are apart: at x > 6 they are more than 0.6 h apart.
  int far_a = 0, far_b = 0;
  for (std::uint32_t i = 0; i < thinned.size_count(); ++i) {
    const double* p = thinned.points.p(i);
    if (thinned.kind[i] != NodeKind::edge || p[0] <= 6) continue;
    (p[1] > 0 ? far_a : far_b) += 1;
  }
  EXPECT_GE(far_a, 3);
  EXPECT_GE(far_b, 3);
  EXPECT_LT(thinned.size_count(), all.size_count());
}

// SpacingGrid::conflicts against brute force, with and without the Lipschitz bound: nodes
// whose sizes follow a graded field h(x) = h0 + g |x - c| (stored as floats, as a NodeSet
// keeps them; sizes over seven grid levels), placed by dart throwing at beta 0.75 as the
// interior fill does, then queried at random points with the field's size there, at betas
// from 0.3 to 1. The bound skips whole levels of larger and smaller nodes and shortens the
// reach; a bound that cut too much would miss conflicts near the level borders.
TEST(SpacingGrid, ConflictsEqualBruteForceOnAGradedField) {
  const double lo[3] = {-1, -1, -1}, c[3] = {0.2, 0.3, 0.1};
  const double h0 = 0.01;
  for (const double g : {0.3, 0.9}) {  // g beta / 2 up to 0.45
    auto size_at = [&](const double* x) {
      const double d = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                                 (x[2] - c[2]) * (x[2] - c[2]));
      return double(float(h0 + g * d));
    };
    std::vector<std::array<double, 4>> stored;
    auto brute = [&](const double* p, double h, double beta) {
      for (const auto& n : stored) {
        const double dx = n[0] - p[0], dy = n[1] - p[1], dz = n[2] - p[2];
        const double lim = beta * (h + n[3]) / 2;
        if (dx * dx + dy * dy + dz * dz < lim * lim) return true;
      }
      return false;
    };
    Rng rng(7);
    SpacingGrid plain(lo, h0), bounded(lo, h0);
    bounded.set_lipschitz(g);
    for (int i = 0; i < 20000; ++i) {
      std::array<double, 4> n;
      for (int k = 0; k < 3; ++k) n[k] = rng.uniform(-0.5, 0.5);
      n[3] = size_at(n.data());
      if (brute(n.data(), n[3], 0.75)) continue;
      plain.insert(n.data(), n[3]);
      bounded.insert(n.data(), n[3]);
      stored.push_back(n);
    }
    int hits = 0, misses = 0;
    for (const double beta : {0.3, 0.7, 0.75, 1.0}) {
      for (int i = 0; i < 3000; ++i) {
        double p[3];
        for (double& x : p) x = rng.uniform(-0.6, 0.6);
        const double h = size_at(p);
        const bool expected = brute(p, h, beta);
        ASSERT_EQ(plain.conflicts(p, h, beta), expected) << "g " << g << " beta " << beta << " query " << i;
        ASSERT_EQ(bounded.conflicts(p, h, beta), expected) << "g " << g << " beta " << beta << " query " << i;
        (expected ? hits : misses) += 1;
      }
    }
    // Both answers are common, so both were compared.
    EXPECT_GT(hits, 2000) << "g " << g << ", " << misses << " misses, " << stored.size() << " nodes";
    EXPECT_GT(misses, 2000) << "g " << g << ", " << hits << " hits, " << stored.size() << " nodes";
  }
  // The farthest conflict the bound allows: a query at the centre c of the radial field
  // h = h0 + g |x - c| (h = h0 there) and one node at distance d, whose size h0 + g d is as
  // large as the Lipschitz bound lets it be. They conflict iff d < beta (2 h0 + g d) / 2, i.e.
  // d < d* = beta h0 / (1 - g beta / 2). Nodes at d* (1 -+ 1e-6) along the axes from random
  // centres (so the cell borders fall differently around them).
  Rng rng(11);
  for (const double g : {0.3, 0.9})
    for (const double beta : {0.7, 1.0}) {
      const double dstar = beta * h0 / (1 - g * beta / 2);
      for (int i = 0; i < 400; ++i) {
        // Along an axis, where a cell border can fall between the true and a cut reach.
        double p[3];
        for (double& x : p) x = rng.uniform(-0.5, 0.5);
        for (const double f : {1 - 1e-6, 1 + 1e-6}) {
          const double d = f * dstar;
          double q[3] = {p[0], p[1], p[2]};
          q[i % 3] += i % 2 ? d : -d;
          SpacingGrid grid(lo, h0);
          grid.set_lipschitz(g);
          grid.insert(q, h0 + g * d);
          EXPECT_EQ(grid.conflicts(p, h0, beta), f < 1) << "g " << g << " beta " << beta << " i " << i;
        }
      }
    }
}

// Cells beyond the hash table's range (2^19 per axis and level) share the edge cells' keys:
// nodes and queries up to 2^22 cells beyond the corner, and below it (negative cell indices,
// where the index's floor by truncation must round down), still get brute force's answers.
// The graded-field test above never leaves the table's range.
TEST(SpacingGrid, CellsBeyondTheTableRangeStillFindEveryConflict) {
  const double lo[3] = {0, 0, 0};
  const double h = 1;
  SpacingGrid grid(lo, h);  // cells 4 across: the table's range ends near 2^21
  std::vector<std::array<double, 3>> stored;
  Rng rng(5);
  auto random_point = [&](double* x) {
    for (int k = 0; k < 3; ++k) {
      // Spread along x over [-2^23, 2^24], near the other two axes' table edges.
      x[k] = k == 0 ? rng.uniform(-8388608.0, 16777216.0) : rng.uniform(-3.0, 3.0) + (k == 1 ? 2097152.0 : -2.0);
    }
  };
  auto brute = [&](const double* p, double beta) {
    for (const auto& n : stored) {
      const double dx = n[0] - p[0], dy = n[1] - p[1], dz = n[2] - p[2];
      const double lim = beta * (h + h) / 2;
      if (dx * dx + dy * dy + dz * dz < lim * lim) return true;
    }
    return false;
  };
  for (int i = 0; i < 3000; ++i) {
    double x[3];
    random_point(x);
    if (i % 2) x[0] = stored.empty() ? x[0] : stored.back()[0] + rng.uniform(-1.5, 1.5);  // near pairs
    if (brute(x, 0.5)) continue;
    grid.insert(x, h);
    stored.push_back({x[0], x[1], x[2]});
  }
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    double p[3];
    random_point(p);
    if (i % 2) {
      const auto& n = stored[std::size_t(i) % stored.size()];
      for (int k = 0; k < 3; ++k) p[k] = n[k] + rng.uniform(-1.2, 1.2);
    }
    const bool expected = brute(p, 1.0);
    ASSERT_EQ(grid.conflicts(p, h, 1.0), expected) << "query " << i;
    hits += expected;
  }
  EXPECT_GT(hits, 300);
  EXPECT_LT(hits, 2700);
}

// Issue 19: the surface sweep split a facet into 4 similar pieces down to the local size, so
// a long thin facet cost (length / h)^2: a 64-sided cylinder 100 long at size 0.3 spent 6
// minutes placing nodes and 2 s meshing them. The sweep now cuts a thin piece across into
// strips: a cylinder 4 times longer costs 3.6 times the points (15.9 times before; 7 with
// longest-edge bisection, whose thin pieces split into 3 per halving), and the points stay a
// bounded multiple of the nodes: a triangular pattern of spacing step = beta h / 2 is
// 4.6 / (beta h)^2 points per unit area, nodes beta h apart about 0.65 / (beta h)^2, plus a
// row and a point more per piece (16.5 points per node here; 14,300 before, growing with the
// length).
TEST(NodePlacement, RegressionLongThinFacetsSweepInLinearWork) {
  auto sweep = [](double H) {
    const Model m = cylinder(1.0, H, 64);
    const SizingField f = uniform(m, 0.1);
    const double lo[3] = {-2, -2, -1};
    SpacingGrid grid(lo, 0.1);
    NodeSet nodes;
    const SurfaceSamplingStats st = place_surface_nodes(m.surface.mesh, f, SurfaceSamplingOptions{}, grid, nodes);
    return std::pair{st, nodes.size_count()};
  };
  const auto [a, na] = sweep(10);
  const auto [b, nb] = sweep(40);
  EXPECT_GT(nb, 3.5 * double(na));
  EXPECT_LT(double(b.sweep_points) / double(a.sweep_points), 4.4) << a.sweep_points << " " << b.sweep_points << " pieces " << a.sweep_pieces << " " << b.sweep_pieces;
  EXPECT_LT(double(b.sweep_points), 20.0 * double(nb)) << b.sweep_points << " points for " << nb << " nodes";
}

// The gear box (test_cli_calculix) lost a feature edge: a surface node inside the diametral
// ball of the segment between two consecutive edge nodes kept that segment out of the Delaunay
// tetrahedralization, recovery added Steiner points beside it, and the boundary groups found
// the curve not followed. The spacing alone does not keep nodes out of those balls: with
// beta = 0.7 < 1/sqrt(2), a shell of each ball near the segment's midpoint is farther than
// beta h from both ends. The surface sampling now keeps out of them. Checked here by brute
// force over the consecutive feature nodes of a box's edges, at sizes that do and do not
// divide its sides.
TEST(NodePlacement, RegressionGearboxSurfaceNodeInsideAFeatureSegmentsBall) {
  const Model m = box(1.0, 0.8, 0.6);
  int inside_unprotected = 0;
  for (const double h : {0.3, 0.23, 0.17, 0.13}) {
    const SizingField f = uniform(m, h);
    for (const bool protect : {false, true}) {
      const double lo[3] = {-1, -1, -1};
      SpacingGrid grid(lo, h / 4), balls(lo, h / 4);
      NodeSet nodes;
      place_edge_nodes(m.surface.mesh, m.features, f, 0.3, grid, nodes, &balls);
      SurfaceSamplingOptions so;
      so.beta = 0.7;
      place_surface_nodes(m.surface.mesh, f, so, grid, nodes, {}, protect ? &balls : nullptr);
      std::vector<std::uint32_t> feat, surf;
      for (std::uint32_t i = 0; i < nodes.size_count(); ++i)
        (nodes.kind[i] == NodeKind::surface ? surf : feat).push_back(i);
      int inside = 0;
      for (const std::uint32_t a : feat)
        for (const std::uint32_t b : feat) {
          const double *pa = nodes.points.p(a), *pb = nodes.points.p(b);
          const double L = dist(pa, pb);
          if (a >= b || L > 2 * h) continue;
          // Consecutive on one box edge: two coordinates shared, and no feature node between.
          const double side[3] = {1.0, 0.8, 0.6};
          int shared = 0;
          for (int k = 0; k < 3; ++k) shared += pa[k] == pb[k] && (pa[k] == 0 || pa[k] == side[k]);
          bool between = false;
          for (const std::uint32_t c : feat)
            between |= c != a && c != b && std::fabs(dist(pa, nodes.points.p(c)) + dist(nodes.points.p(c), pb) - L) < 1e-12;
          if (shared != 2 || between) continue;
          const double mid[3] = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
          for (const std::uint32_t q : surf) inside += dist(nodes.points.p(q), mid) < L / 2;
        }
      if (protect) {
        EXPECT_EQ(inside, 0) << "h " << h;
      } else {
        inside_unprotected += inside;
      }
    }
  }
  EXPECT_GT(inside_unprotected, 0);  // the defect is there without the balls
}

TEST(NodePlacement, NoTwoNodesCloserThanTheGuaranteedBound) {
  // Guarantee: a surface or interior node keeps >= 0.7 (h_p + h_q) / 2 from every node placed
  // before it (the surface rule; interior nodes use 0.75). Feature nodes keep only 0.3 from
  // other curves' nodes and corners; on this box their spacing is L/round(L/h) >= 0.7 / 0.75 h (see the edge test above), so all
  // pairs keep >= 0.7 h (h uniform). Brute force over all pairs.
  for (const bool cyl : {false, true}) {
    const Model m = cyl ? cylinder(0.5, 1, 48) : box(1, 1.3, 0.7);
    const double h = cyl ? 0.09 : 0.12;
    const SurfaceQuery q(m.surface.mesh);
    const NodeSet ns = place_nodes({m.surface, q, uniform(m, h)}, m.features);
    EXPECT_GE(closest_pair(ns), 0.7 * h * (1 - 1e-12)) << (cyl ? "cylinder" : "box");
  }
}

TEST(NodePlacement, NodeCountsFollowVolumeAndAreaOverCellSize) {
  // Box 1 x 1.3 x 0.7, h = 0.05, clearance c = 0.8.
  // Interior: a BCC lattice of cube edge a = 1.083 h holds 2 nodes per a^3. Every node is
  // >= c h from the faces, every cell of the shrunk box [c h + a, L - c h - a] is fully
  // filled, so  2 prod(L_i - 2 c h - 2 a) / a^3  <=  N_lattice, and N_lattice <=
  // 2 prod(L_i - 2 c h + 2 a) / a^3 (cells meeting [c h, L - c h]). The boundary layer adds
  // nodes in the gap; it can at most fill the band [c h, c h + a] with spacing 0.75 h,
  // i.e. <= area * a / (0.75 h)^3 * sqrt(2) (densest packing of balls of radius 0.375 h).
  // Surface: Poisson-disk nodes with spacing >= 0.7 h: discs of radius 0.35 h around them
  // are disjoint and within 0.35 h of the surface: N_s <= (area + perimeter... ) bounded by
  // (A + 0.35 h * E + pi (0.35 h)^2 * 8) / (pi (0.35 h)^2) with E the total edge length;
  // and every surface point is within 0.7 h + sweep step (0.35 h) of a node, so
  // N_s >= A / (pi (1.05 h)^2).
  const double L[3] = {1, 1.3, 0.7}, h = 0.05, c = 0.8, a = 1.083 * h;
  const Model m = box(L[0], L[1], L[2]);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, h)}, m.features);
  double lo = 2, hi = 2;
  for (const double l : L) {
    lo *= (l - 2 * c * h - 2 * a) / a;
    hi *= (l - 2 * c * h + 2 * a) / a;
  }
  const double area = 2 * (L[0] * L[1] + L[1] * L[2] + L[0] * L[2]);
  const double E = 4 * (L[0] + L[1] + L[2]);
  hi += area * a / std::pow(0.75 * h, 3) * std::sqrt(2.0);
  const double n_int = double(count(ns, NodeKind::interior));
  EXPECT_GE(n_int, lo);
  EXPECT_LE(n_int, hi);
  const double disc = std::numbers::pi * 0.35 * h * 0.35 * h;
  const double n_surf = double(ns.size_count()) - n_int;
  EXPECT_LE(n_surf, (area + 0.35 * h * E + 8 * disc) / disc);
  EXPECT_GE(n_surf, area / (std::numbers::pi * 1.05 * h * 1.05 * h));
  // Sizes recorded per node are the field's.
  for (std::uint32_t i = 0; i < ns.size_count(); ++i) ASSERT_EQ(ns.size[i], float(h));
}

// ---- determinism ----

bool same(const NodeSet& a, const NodeSet& b) {
  return a.points.xyz.size() == b.points.xyz.size() &&
         std::memcmp(a.points.xyz.data(), b.points.xyz.data(), a.points.xyz.size() * sizeof(double)) == 0 &&
         a.kind == b.kind && a.facet == b.facet &&
         std::memcmp(a.size.data(), b.size.data(), a.size.size() * sizeof(float)) == 0;
}

TEST(NodePlacement, DeterministicForASeedAndDifferentAcrossSeeds) {
  const Model m = cylinder(0.5, 1, 48);
  const SurfaceQuery q(m.surface.mesh);
  const SizingField h = uniform(m, 0.08);
  PlacementOptions o;
  o.seed = 7;
  const NodeSet a = place_nodes({m.surface, q, h}, m.features, o);
  const NodeSet b = place_nodes({m.surface, q, h}, m.features, o);
  EXPECT_TRUE(same(a, b));
  o.seed = 8;
  const NodeSet c = place_nodes({m.surface, q, h}, m.features, o);
  EXPECT_FALSE(same(a, c));
}

/// A cylinder (radius 0.5, height 1, 48 sides) with a field of h_max `max_size` refined to
/// `size` at (0.5, 0, 0.5), and its feature and surface nodes placed as node placement does:
/// what the interior fill starts from.
struct SampledCylinder {
  SampledCylinder(double max_size, double size)
      : field(point_zone_field(m.surface.mesh, max_size, size, {0.5, 0, 0.5})), grid(kGridLo, field.min_size()) {
    grid.set_lipschitz(field.options().gradation);
    place_edge_nodes(m.surface.mesh, m.features, field, 0.3, grid, surface_nodes);
    SurfaceSamplingOptions so;
    so.beta = 0.7;
    place_surface_nodes(m.surface.mesh, field, so, grid, surface_nodes);
  }
  static constexpr double kGridLo[3] = {-2, -2, -2};
  const Model m = cylinder(0.5, 1, 48);
  const SurfaceQuery q{m.surface.mesh};
  const SizingField field;
  SpacingGrid grid;
  NodeSet surface_nodes;
};

// The lattice fill skips the field's evaluation at a point whose level the bounds of its
// block (h at the block's centre, h Lipschitz) show to be another than the one enumerated
// (2026-11-29: on the paper gear box 9.7M of 22.8M evaluations). It must give the very nodes
// of evaluating every point: graded fields over many levels, from a point zone and from a
// plane zone, with the lattice turned and not.
TEST(InteriorFill, LevelBoundsGiveTheNodesOfEvaluatingEveryPoint) {
  const Model m = box(1, 1.3, 0.7);
  const SurfaceQuery q(m.surface.mesh);
  SizingOptions po;
  po.max_size = 0.2;
  po.gradation = 0.3;
  SizingZone plane;
  plane.kind = SizingZone::Kind::plane;
  plane.size = 0.01;
  plane.coords = {0.4, 0.6, 0.35, 1, 0.3, 0.2};
  po.zones.push_back(plane);
  const SizingField fields[2] = {point_zone_field(m.surface.mesh, 0.1, 0.004, {0.3, 0.7, 0.2}),
                                 build_sizing_field(m.surface.mesh, po)};
  for (const SizingField& field : fields)
    for (const bool rotate : {true, false}) {
      std::vector<NodeSet> runs;
      std::vector<std::size_t> candidates;
      for (const bool bound : {true, false}) {
        InteriorFillOptions o;
        o.rotate_lattice = rotate;
        o.layer_tries = 0;
        o.bound_levels = bound;
        const double glo[3] = {-2, -2, -2};
        SpacingGrid grid(glo, field.min_size());
        grid.set_lipschitz(field.options().gradation);
        NodeSet ns;
        candidates.push_back(fill_interior(m.surface.mesh, m.surface.bbox_min, m.surface.bbox_max, q, field, o,
                                           grid, ns).candidates);
        runs.push_back(std::move(ns));
      }
      EXPECT_GT(runs[0].size_count(), &field == fields ? 1000u : 20000u);
      EXPECT_TRUE(same(runs[0], runs[1])) << "rotate " << rotate;
      EXPECT_EQ(candidates[0], candidates[1]) << "rotate " << rotate;
    }
}

// The boundary layer decides its tries in batches of 65,536: their conflict tests against
// the grid as it stood before the batch, their distance and side run on several threads, and
// each kept try is then tested against the nodes its batch kept before it. This must give
// exactly the nodes of deciding each try when it is drawn: the same on 1, 2 and 3 threads,
// and no layer node closer to an earlier node than the interior rule allows (brute force
// over all pairs; the batch test left out put nodes 0.0007 apart).
TEST(InteriorFill, BoundaryLayerInBatchesIsTheSameOnAnyThreadCountAndKeepsItsSpacing) {
  SampledCylinder c(0.03, 0.012);
  const auto& [m, q, field, grid, surface_nodes] = c;
  InteriorFillOptions o;
  o.beta = 0.75;
  const std::size_t tries = surface_nodes.size_count() * std::size_t(o.layer_tries);
  ASSERT_GT(tries, 3u * 65536u);  // several batches
  std::vector<NodeSet> runs;
  InteriorFillStats st;
  for (const unsigned threads : {1u, 2u, 3u}) {
    o.threads = threads;
    SpacingGrid g = grid;
    NodeSet ns = surface_nodes;
    const InteriorFillStats s = fill_interior(m.surface.mesh, m.surface.bbox_min, m.surface.bbox_max, q,
                                              field, o, g, ns);
    if (!runs.empty()) {
      EXPECT_TRUE(same(runs.front(), ns)) << threads << " threads";
      EXPECT_EQ(s.distance_queries, st.distance_queries) << threads << " threads";
      EXPECT_EQ(s.side_queries, st.side_queries) << threads << " threads";
    }
    st = s;
    runs.push_back(std::move(ns));
  }
  const NodeSet& ns = runs.front();
  ASSERT_GT(st.layer_nodes, 1000u);
  const std::size_t first_layer = ns.size_count() - st.layer_nodes;
  std::vector<double> h(ns.size_count());
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = field(ns.points.p(std::uint32_t(i)));
  double worst = INFINITY;  // least |p - q| / ((h_p + h_q) / 2) of a layer node p and an earlier q
  for (std::size_t i = first_layer; i < ns.size_count(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      worst = std::min(worst, dist(ns.points.p(std::uint32_t(i)), ns.points.p(std::uint32_t(j))) /
                                  ((h[i] + h[j]) / 2));
  EXPECT_GE(worst, 0.75 * (1 - 1e-9));
}

// Node placement generates the lattice's candidates (InteriorLattice::work) on a helper thread
// while it samples the surface, and the calling thread joins in afterwards. Any number of
// threads calling work() at any time gives fill_interior's nodes on one thread; finish()
// before every block is generated (never started, or stopped) is an error, not fewer nodes.
TEST(InteriorFill, LatticeGeneratedAheadOnAnyThreadsGivesTheSameNodes) {
  SampledCylinder c(0.05, 0.015);
  const auto& [m, q, field, grid, surface_nodes] = c;
  InteriorFillOptions o;
  o.beta = 0.75;
  o.threads = 1;
  SpacingGrid g1 = grid;
  NodeSet one = surface_nodes;
  const InteriorFillStats s1 = fill_interior(m.surface.mesh, m.surface.bbox_min, m.surface.bbox_max, q,
                                             field, o, g1, one);
  ASSERT_GT(s1.lattice_nodes, 1000u);
  o.threads = 2;
  InteriorLattice lattice(m.surface.bbox_min, m.surface.bbox_max, q, field, o);
  std::vector<std::thread> early;
  for (int i = 0; i < 3; ++i) early.emplace_back([&] { lattice.work(); });
  lattice.work_on(2);
  for (auto& t : early) t.join();
  SpacingGrid g2 = grid;
  NodeSet ahead = surface_nodes;
  const InteriorFillStats s2 = lattice.finish(m.surface.mesh, g2, ahead);
  EXPECT_TRUE(same(one, ahead));
  EXPECT_EQ(s2.candidates, s1.candidates);
  EXPECT_EQ(s2.lattice_nodes, s1.lattice_nodes);
  EXPECT_EQ(s2.distance_queries, s1.distance_queries);

  InteriorLattice never(m.surface.bbox_min, m.surface.bbox_max, q, field, o);
  SpacingGrid g3 = grid;
  NodeSet ns = surface_nodes;
  EXPECT_THROW(never.finish(m.surface.mesh, g3, ns), UsageError);
  InteriorLattice stopped(m.surface.bbox_min, m.surface.bbox_max, q, field, o);
  stopped.stop();
  stopped.work();
  EXPECT_THROW(stopped.finish(m.surface.mesh, g3, ns), UsageError);
  EXPECT_EQ(ns.size_count(), surface_nodes.size_count());  // nothing added
}

// ---- thin plate: no room inside ----

TEST(NodePlacement, PlateThinnerThanTheClearanceHasSurfaceNodesOnly) {
  // Thickness 0.1, h = 0.2: every inside point is <= 0.05 from the surface, less than
  // c h = 0.16, so no interior node may exist.
  const Model m = box(1, 1, 0.1);
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, uniform(m, 0.2)}, m.features);
  EXPECT_EQ(count(ns, NodeKind::interior), 0u);
  EXPECT_EQ(count(ns, NodeKind::corner), 8u);
  EXPECT_GT(count(ns, NodeKind::surface), 0u);
}

// ---- options, progress ----

TEST(NodePlacement, BadClearanceIsAUsageError) {
  const Model m = box(1, 1, 1);
  const SurfaceQuery q(m.surface.mesh);
  PlacementOptions o;
  o.interior_clearance = -1;
  EXPECT_THROW(place_nodes({m.surface, q, uniform(m, 0.2)}, m.features, o), UsageError);
  o.interior_clearance = NAN;
  EXPECT_THROW(place_nodes({m.surface, q, uniform(m, 0.2)}, m.features, o), UsageError);
}

TEST(NodePlacement, ProgressReportsEveryStageUpToOne) {
  const Model m = box(1, 1, 1);
  const SurfaceQuery q(m.surface.mesh);
  PlacementOptions o;
  std::vector<std::string> stages;
  double last = -1;
  o.progress = [&](const std::string& s, double f) {
    if (stages.empty() || stages.back() != s) stages.push_back(s);
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    last = f;
  };
  place_nodes({m.surface, q, uniform(m, 0.2)}, m.features, o);
  EXPECT_EQ(stages, (std::vector<std::string>{"edges", "surface", "interior"}));
  EXPECT_EQ(last, 1.0);
}

// ---- graded field ----

/// Expected interior node count of a lattice fill of the box [0,L]^3 region `lo..hi`:
/// the integral of the BCC density 2 / (1.083 h)^3 over the points at distance >= c h from
/// the box faces (distance computed directly: min over axes of min(x, L - x)), midpoint rule
/// on an m^3 grid. Independent of the placement code except for the lattice constant.
double expected_lattice_nodes(const SizingField& h, double L, const double* lo, const double* hi,
                              double c, int m) {
  double sum = 0;
  const double d[3] = {(hi[0] - lo[0]) / m, (hi[1] - lo[1]) / m, (hi[2] - lo[2]) / m};
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k) {
        const double p[3] = {lo[0] + (i + 0.5) * d[0], lo[1] + (j + 0.5) * d[1],
                             lo[2] + (k + 0.5) * d[2]};
        double dist = INFINITY;
        for (const double x : p) dist = std::min({dist, x, L - x});
        const double hp = h(p);
        if (dist >= c * hp) sum += 2 / std::pow(1.083 * hp, 3);
      }
  return sum * d[0] * d[1] * d[2];
}

TEST(NodePlacement, GradedFieldDensityFollowsTheField) {
  // Box [0,2]^3, a point zone of size 0.01 at its centre, gradation 0.3, h_max 0.1: h grows
  // from 0.01 to 0.1 at distance 0.3. The interior lattice holds 2 nodes per (1.083 h)^3
  // (see the count test), up to the level rounding: a / (1.083 h) in [rho^-1/2, rho^1/2],
  // rho = sqrt(2), so the local density is within a factor rho^(3/2) = 1.68 either way;
  // level transitions drop a few nodes. So the interior count in the cube [0.8, 1.2]^3
  // around the zone and in the cube [1.4, 1.7]^3 (h = 0.1 throughout: its nearest point to
  // the centre has h = 0.01 + 0.3 * 0.69 > 0.1; it is >= 0.3 from the faces, beyond the
  // boundary layer) must each be within [0.5, 1.7] x the integral of that density, computed
  // independently below.
  const Model m = box(2, 2, 2);
  const SizingField h = point_zone_field(m.surface.mesh, 0.1, 0.01, {1, 1, 1});
  const SurfaceQuery q(m.surface.mesh);
  const NodeSet ns = place_nodes({m.surface, q, h}, m.features);
  const double c = PlacementOptions{}.interior_clearance;
  const double n0[3] = {0.8, 0.8, 0.8}, n1[3] = {1.2, 1.2, 1.2};
  const double f0[3] = {1.4, 1.4, 1.4}, f1[3] = {1.7, 1.7, 1.7};
  auto in = [](const double* p, const double* lo, const double* hi) {
    return p[0] >= lo[0] && p[0] < hi[0] && p[1] >= lo[1] && p[1] < hi[1] && p[2] >= lo[2] &&
           p[2] < hi[2];
  };
  std::size_t near = 0, far = 0;
  for (std::uint32_t i = 0; i < ns.size_count(); ++i) {
    const double* p = ns.points.p(i);
    ASSERT_EQ(ns.size[i], float(h(p)));
    if (ns.kind[i] != NodeKind::interior) continue;
    near += in(p, n0, n1);
    far += in(p, f0, f1);
  }
  const double e_near = expected_lattice_nodes(h, 2, n0, n1, c, 80);
  const double e_far = expected_lattice_nodes(h, 2, f0, f1, c, 40);
  EXPECT_GE(double(near), 0.5 * e_near);
  EXPECT_LE(double(near), 1.7 * e_near);
  EXPECT_GE(double(far), 0.5 * e_far);
  EXPECT_LE(double(far), 1.7 * e_far);
  // The zone matters: around it the field expects far more than h = 0.1 would, beyond the
  // tolerance above, so these bounds separate graded from uniform placement.
  const double e_near_uniform = expected_lattice_nodes(uniform(m, 0.1), 2, n0, n1, c, 80);
  EXPECT_GT(e_near, 1.7 / 0.5 * e_near_uniform);
  expect_interior_clear(m, ns, h, c);
  expect_surface_nodes_on_facets(m, ns, 2);
}

// ---- size fidelity ----

TEST(SizeFidelity, RightCornerTetByHand) {
  // Tet (0,0,0), (1,0,0), (0,1,0), (0,0,1), h = 1: edges 1, 1, 1, sqrt2, sqrt2, sqrt2.
  // Mean (3 + 3 sqrt2) / 6 = 1.20711; in [0.7, 1.4]: the three unit edges (sqrt2 = 1.414 is
  // long), so 0.5; min 1, max sqrt2.
  PointSet p;
  p.push_back(0, 0, 0);
  p.push_back(1, 0, 0);
  p.push_back(0, 1, 0);
  p.push_back(0, 0, 1);
  SurfaceMesh s;
  s.points = p;
  SizingOptions o;
  o.max_size = 1;
  const SizingField h = build_sizing_field(s, o);
  // Two copies of the tet (the second with permuted ids): edges are counted once.
  const SizeFidelity f = measure_size_fidelity(p, {0, 1, 2, 3, 3, 2, 0, 1}, h);
  EXPECT_EQ(f.edges, 6u);
  EXPECT_NEAR(f.mean_ratio, (3 + 3 * std::sqrt(2.0)) / 6, 1e-15);
  EXPECT_DOUBLE_EQ(f.in_range, 0.5);
  EXPECT_DOUBLE_EQ(f.long_fraction, 0.5);
  EXPECT_DOUBLE_EQ(f.short_fraction, 0.0);
  EXPECT_DOUBLE_EQ(f.min_ratio, 1.0);
  EXPECT_DOUBLE_EQ(f.max_ratio, std::sqrt(2.0));
  EXPECT_EQ(measure_size_fidelity(p, {}, h).edges, 0u);
  EXPECT_THROW(measure_size_fidelity(p, {0, 1, 2}, h), UsageError);
  EXPECT_THROW(measure_size_fidelity(p, {0, 1, 2, 4}, h), UsageError);
  // No zone: every edge is away from refinement, each measured against h_max = 1.
  EXPECT_EQ(f.away_edges, 6u);
  EXPECT_NEAR(f.away_mean_ratio, f.mean_ratio, 1e-15);
}

TEST(SizeFidelity, AwayFromRefinementCountsOnlyEdgesTheFieldLeavesAtTheUsersSize) {
  // h_max = 1, a point zone of size 0.1 at the origin, gradation 0.3: h(x) = min(1, 0.1 + 0.3 |x|)
  // is below 1 within |x| < 3. Two tets: one at the zone (every edge refined), one with all
  // four corners (and so every midpoint) farther than 3 from it: a right corner tet of legs 2,
  // edges 2 (three) and 2 sqrt2 (three), mean length 1 + sqrt2 = that over h_max = 1.
  PointSet p;
  for (const double o : {0.0, 10.0}) {
    const double l = o == 0 ? 1 : 2;
    p.push_back(o, o, o);
    p.push_back(o + l, o, o);
    p.push_back(o, o + l, o);
    p.push_back(o, o, o + l);
  }
  SurfaceMesh s;
  s.points = p;
  const SizingField h = point_zone_field(s, 1, 0.1, {0, 0, 0});
  const SizeFidelity f = measure_size_fidelity(p, {0, 1, 2, 3, 4, 5, 6, 7}, h);
  EXPECT_EQ(f.edges, 12u);
  EXPECT_EQ(f.away_edges, 6u);
  EXPECT_NEAR(f.away_mean_ratio, 1 + std::sqrt(2.0), 1e-12);
  EXPECT_GT(f.mean_ratio, 2);  // the refined tet's edges are long for h = 0.1 + ...
}

/// The size-fidelity figures by hand: every distinct edge, the field at its midpoint.
struct FidelityByHand {
  std::size_t edges = 0, in = 0, refined = 0;
  double sum = 0, lo = INFINITY, hi = 0;
};
FidelityByHand fidelity_by_hand(const PointSet& p, const std::vector<std::uint32_t>& tets,
                                const SizingField& h) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::size_t t = 0; t < tets.size(); t += 4)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.insert(std::minmax(tets[t + i], tets[t + j]));
  FidelityByHand f;
  f.edges = edges.size();
  for (const auto& [a, b] : edges) {
    const double *pa = p.p(a), *pb = p.p(b);
    const double m[3] = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
    const double r = std::hypot(pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]) / h(m);
    f.sum += r;
    f.lo = std::min(f.lo, r);
    f.hi = std::max(f.hi, r);
    f.in += r >= 0.7 && r <= 1.4;
    f.refined += h(m) < 1;
  }
  return f;
}

void expect_fidelity_by_hand(const SizeFidelity& f, const FidelityByHand& want) {
  ASSERT_EQ(f.edges, want.edges);
  EXPECT_GT(want.refined, 0u);
  const double mean = want.sum / double(want.edges);
  EXPECT_NEAR(f.mean_ratio, mean, 1e-12 * mean);
  EXPECT_EQ(f.min_ratio, want.lo);
  EXPECT_EQ(f.max_ratio, want.hi);
  EXPECT_DOUBLE_EQ(f.in_range, double(want.in) / double(want.edges));
}

// The edges whose midpoints the field refines are found even when neither end is near the
// refinement: the figures equal those of the field evaluated at every midpoint. measure_size_
// fidelity skips the midpoints of a vertex's edges when the field is h_max over a ball of half
// its longest edge; a ball of zero radius (the vertex alone) would skip the long edge below,
// whose ends are 5 from the point zone (h = 1 there) and whose midpoint is 0.5 from it.
TEST(SizeFidelity, EqualsTheFieldEvaluatedAtEveryMidpoint) {
  PointSet p;
  p.push_back(-5, 0.5, 0);   // the long edge (0, 1) passes the zone at the origin
  p.push_back(5, 0.5, 0);
  p.push_back(0, 8, 0);
  p.push_back(0, 6, 7);
  Rng rng(3);
  for (int i = 0; i < 200; ++i) p.push_back(rng.uniform(-9, 9), rng.uniform(-9, 9), rng.uniform(-9, 9));
  std::vector<std::uint32_t> tets = {0, 1, 2, 3};
  for (std::uint32_t i = 4; i + 3 < p.size(); i += 2) tets.insert(tets.end(), {i, i + 1, i + 2, i + 3});
  SurfaceMesh s;
  s.points = p;
  const SizingField h = point_zone_field(s, 1, 0.1, {0, 0, 0});
  const SizeFidelity f = measure_size_fidelity(p, tets, h);
  const FidelityByHand want = fidelity_by_hand(p, tets, h);
  expect_fidelity_by_hand(f, want);
  // The long edge: 10 long, h = 0.1 + 0.3 * 0.5 at its midpoint.
  EXPECT_DOUBLE_EQ(want.hi, 10 / 0.25);
}

// The reach of a vertex covers its edges to lower ids too. Vertex 1's edges to higher ids are
// short and 5 from the zone, where h = h_max over a ball of their half length; its edge to 0
// passes the zone; so do the edges of 2 and 3 to 0. Counting only the edges a vertex starts
// (the unique edges are stored from their lower end) leaves 1, 2 and 3 "clear", and the long
// edges' ratios about 10 instead of 36-40.
TEST(SizeFidelity, ReachCoversTheEdgesToLowerIds) {
  PointSet p;
  p.push_back(-5, 0.5, 0);
  p.push_back(5, 0.5, 0);
  p.push_back(5.2, 0.5, 0);
  p.push_back(5, 0.7, 0.1);
  SurfaceMesh s;
  s.points = p;
  const SizingField h = point_zone_field(s, 1, 0.1, {0, 0, 0});
  const std::vector<std::uint32_t> tets = {0, 1, 2, 3};
  const FidelityByHand want = fidelity_by_hand(p, tets, h);
  expect_fidelity_by_hand(measure_size_fidelity(p, tets, h), want);
  EXPECT_GT(want.hi, 40);  // edge (0, 2): 10.2 long, h = 0.1 + 0.3 * 0.51 at its midpoint
}

// A vertex in hundreds of tets: its edges' group holds more entries than the table of
// DistinctSorter (mesher/distinct_sorter.h) takes, and the others' groups fewer; the figures
// still equal the field's at every unique edge's midpoint.
TEST(SizeFidelity, AVertexInHundredsOfTetsCountsEachEdgeOnce) {
  PointSet p;
  p.push_back(0, 0, 0);
  Rng rng(5);
  for (int i = 0; i < 150; ++i) p.push_back(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3));
  std::vector<std::uint32_t> tets;
  for (std::uint32_t i = 1; i + 2 < p.size(); ++i) tets.insert(tets.end(), {0, i, i + 1, i + 2});
  for (std::uint32_t i = 1; i + 3 < p.size(); i += 3) tets.insert(tets.end(), {i + 3, i, 0, i + 1});
  SurfaceMesh s;
  s.points = p;
  const SizingField h = point_zone_field(s, 1, 0.1, {0.5, 0, 0});
  const FidelityByHand want = fidelity_by_hand(p, tets, h);
  ASSERT_EQ(want.edges, 150u + 149u + 148u + 49u);  // (0, i); (i, i+1); (i, i+2); (i, i+3)
  expect_fidelity_by_hand(measure_size_fidelity(p, tets, h), want);
}

}  // namespace
}  // namespace kdmesh
