// Test support: small FeMesh fixtures (a two-region unit cube with boundary, interface and
// feature-edge entities and groups of every dimension), shared by the io/ format tests.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "core/fe_mesh.h"

namespace kdmesh::test {

/// Entity ids of the cube mesh (deliberately not 0..k-1 everywhere, so that the +1 / -1 tag
/// conversions are exercised).
constexpr std::uint32_t kLeftVolume = 0, kRightVolume = 7;
constexpr std::uint32_t kSide0 = 20;  // xmin 20, xmax 21, ymin 22, ymax 23, zmin 24, zmax 25
constexpr std::uint32_t kInterface = 30;
inline const char* const kSideNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};

inline double det3(const double* a, const double* b, const double* c, const double* d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

inline std::array<std::uint32_t, 3> sorted3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::array<std::uint32_t, 3> k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// Adds the mid-edge nodes of an order-1 mesh (one per distinct edge, at its midpoint) and
/// makes it order 2 in FeMesh's node order.
inline void make_quadratic(FeMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
  auto node = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    const auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const double* p = m.points.p(a);
    const double* q = m.points.p(b);
    const auto id = std::uint32_t(m.points.size());
    m.points.push_back((p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2);
    mid.emplace(key, id);
    return id;
  };
  static const int kTetEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  std::vector<std::uint32_t> tets, faces, edges;
  for (std::size_t t = 0; t < m.tets.size() / 4; ++t) {
    const std::uint32_t* c = &m.tets[4 * t];
    tets.insert(tets.end(), c, c + 4);
    for (const auto& e : kTetEdges) tets.push_back(node(c[e[0]], c[e[1]]));
  }
  for (std::size_t f = 0; f < m.faces.size() / 3; ++f) {
    const std::uint32_t* c = &m.faces[3 * f];
    faces.insert(faces.end(), c, c + 3);
    for (int i = 0; i < 3; ++i) faces.push_back(node(c[i], c[(i + 1) % 3]));
  }
  for (std::size_t e = 0; e < m.edges.size() / 2; ++e) {
    const std::uint32_t* c = &m.edges[2 * e];
    edges.insert(edges.end(), c, c + 2);
    edges.push_back(node(c[0], c[1]));
  }
  m.tets = tets;
  m.faces = faces;
  m.edges = edges;
  m.order = 2;
}

/// The id of grid point (i, j, k) of kuhn_cube(n).
inline std::uint32_t cube_vid(int n, int i, int j, int k) {
  return std::uint32_t(i + (n + 1) * (j + (n + 1) * k));
}

/// The unit cube's (n+1)^3 grid points (point i + (n+1)(j + (n+1)k) at (i, j, k) / n) and its
/// n^3 subcubes each cut into the 6 positive Kuhn tets along its main diagonal (neighbouring
/// subcubes share their face diagonals: a conforming mesh); tets 6c .. 6c+5 fill subcube
/// c = i + n(j + n k); tet_entity 0; no faces, edges or groups.
inline FeMesh kuhn_cube(int n) {
  FeMesh m;
  auto vid = [n](int i, int j, int k) { return cube_vid(n, i, j, k); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.points.push_back(double(i) / n, double(j) / n, double(k) / n);
  static const int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : kPerm) {
          int c[3] = {i, j, k};
          std::uint32_t v[4];
          v[0] = vid(c[0], c[1], c[2]);
          for (int s = 0; s < 2; ++s) {
            ++c[p[s]];
            v[s + 1] = vid(c[0], c[1], c[2]);
          }
          v[3] = vid(i + 1, j + 1, k + 1);
          if (det3(m.points.p(v[0]), m.points.p(v[1]), m.points.p(v[2]), m.points.p(v[3])) < 0)
            std::swap(v[1], v[2]);
          m.tets.insert(m.tets.end(), v, v + 4);
          m.tet_entity.push_back(0);
        }
  return m;
}

/// Appends the 12 edges of the cube of kuhn_cube(n), n segments each, with entity
/// curve0 + 4 * axis + 2 * s + t (the edge along `axis` at the other two coordinates s, t).
inline void add_cube_edges(FeMesh& m, int n, std::uint32_t curve0) {
  auto vid = [n](int i, int j, int k) { return cube_vid(n, i, j, k); };
  for (int axis = 0; axis < 3; ++axis)
    for (int s = 0; s < 2; ++s)
      for (int t = 0; t < 2; ++t)
        for (int step = 0; step < n; ++step) {
          int c[3];
          c[axis] = step;
          c[(axis + 1) % 3] = s * n;
          c[(axis + 2) % 3] = t * n;
          const std::uint32_t a = vid(c[0], c[1], c[2]);
          ++c[axis];
          m.edges.insert(m.edges.end(), {a, vid(c[0], c[1], c[2])});
          m.edge_entity.push_back(curve0 + std::uint32_t(4 * axis + 2 * s + t));
        }
}

/// The unit cube cut into n^3 subcubes (n even), each split into the 6 Kuhn tets along its
/// main diagonal (so neighbouring subcubes share their face diagonals: a conforming mesh).
///  - volumes: entity kLeftVolume for x < 1/2, kRightVolume for x > 1/2;
///  - faces: the boundary triangles, one entity per cube side (kSide0 + 2 * axis + side), plus
///    the interface x = 1/2 (kInterface), oriented +x (out of the left volume);
///  - edges: the 12 cube edges, n segments each, curve 4 * axis + 2 * s + t;
///  - groups: dim 3 "solid" {both}, "right_half" {kRightVolume}; dim 2 one per side, "sides"
///    {all six}, "interface"; dim 1 "x_edges" (curves along x), "other_edges".
/// Every face is oriented with its normal (c1-c0)x(c2-c0) pointing out of the volume it bounds.
inline FeMesh cube_mesh(int n, int order) {
  FeMesh m = kuhn_cube(n);
  for (std::size_t t = 0; t < m.tet_entity.size(); ++t)
    m.tet_entity[t] = 2 * ((t / 6) % std::size_t(n)) < std::size_t(n) ? kLeftVolume : kRightVolume;

  // Faces: boundary (once in the tets) and the interface x = 1/2 (twice, taken from the left).
  // The outward listing of the face opposite corner i of a positive tet (c0 c1 c2 c3).
  static const int kOutward[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<std::uint32_t, 3>, int> count;
  for (std::size_t t = 0; t < m.tet_entity.size(); ++t)
    for (const auto& f : kOutward)
      ++count[sorted3(m.tets[4 * t + f[0]], m.tets[4 * t + f[1]], m.tets[4 * t + f[2]])];
  for (std::size_t t = 0; t < m.tet_entity.size(); ++t)
    for (const auto& f : kOutward) {
      const std::uint32_t a = m.tets[4 * t + f[0]], b = m.tets[4 * t + f[1]],
                          c = m.tets[4 * t + f[2]];
      const double* pa = m.points.p(a);
      const double* pb = m.points.p(b);
      const double* pc = m.points.p(c);
      std::uint32_t entity = 0;
      if (count[sorted3(a, b, c)] == 1) {
        for (int axis = 0; axis < 3; ++axis)
          for (int side = 0; side < 2; ++side)
            if (pa[axis] == side && pb[axis] == side && pc[axis] == side)
              entity = kSide0 + std::uint32_t(2 * axis + side);
      } else if (pa[0] == 0.5 && pb[0] == 0.5 && pc[0] == 0.5 &&
                 m.tet_entity[t] == kLeftVolume) {
        entity = kInterface;
      } else {
        continue;
      }
      m.faces.insert(m.faces.end(), {a, b, c});
      m.face_entity.push_back(entity);
    }

  add_cube_edges(m, n, 0);

  m.groups.push_back({"solid", 3, {kLeftVolume, kRightVolume}});
  m.groups.push_back({"right_half", 3, {kRightVolume}});
  for (int s = 0; s < 6; ++s) m.groups.push_back({kSideNames[s], 2, {kSide0 + std::uint32_t(s)}});
  m.groups.push_back({"sides", 2, {kSide0, kSide0 + 1, kSide0 + 2, kSide0 + 3, kSide0 + 4, kSide0 + 5}});
  m.groups.push_back({"interface", 2, {kInterface}});
  m.groups.push_back({"x_edges", 1, {0, 1, 2, 3}});
  m.groups.push_back({"other_edges", 1, {4, 5, 6, 7, 8, 9, 10, 11}});
  if (order == 2) make_quadratic(m);
  return m;
}

}  // namespace kdmesh::test
