// kdmesh — cells of a surface with internal walls (mesher/surface/surface_cells.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface/surface_cells.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <numeric>
#include <utility>

#include "mesher/surface/surface_prepare.h"

namespace kdmesh {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

K::Point_3 point(const SurfaceMesh& m, std::uint32_t v) {
  const double* p = m.points.p(v);
  return {p[0], p[1], p[2]};
}

/// A facet at an edge (a, b), a < b: its id, its apex, and +1 if it runs a -> b (its normal
/// then points the way a turn counter-clockwise about a -> b goes), -1 if b -> a.
struct AtEdge {
  std::uint32_t facet, apex;
  int dir;
};

std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<AtEdge>> edge_facets(const SurfaceMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<AtEdge>> edges;
  for (std::uint32_t f = 0; f < m.num_tris(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t a = m.tri(f)[j], b = m.tri(f)[(j + 1) % 3], c = m.tri(f)[(j + 2) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({f, c, a < b ? 1 : -1});
    }
  return edges;
}

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

bool has_nonmanifold_edges(const SurfaceMesh& mesh) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
  e.reserve(3 * mesh.num_tris());
  for (std::size_t f = 0; f < mesh.num_tris(); ++f)
    for (int j = 0; j < 3; ++j) e.push_back(std::minmax(mesh.tri(f)[j], mesh.tri(f)[(j + 1) % 3]));
  std::sort(e.begin(), e.end());
  for (std::size_t i = 0; i + 2 < e.size(); ++i)
    if (e[i] == e[i + 2]) return true;
  return false;
}

std::vector<SurfaceMesh> split_cells(const SurfaceMesh& input, const std::string& source) {
  for (std::uint32_t v : input.tris)
    if (v >= input.points.size()) throw SurfaceError(source + ": a facet names point " + std::to_string(v), {});
  // Two facets on the same corners facing opposite ways are one wall written twice (two parts
  // touching, exported into one file): one copy stays. Facing the same way, they are duplicates.
  SurfaceMesh m;
  m.points = input.points;
  std::vector<std::uint32_t> orig;  // m's facet -> the input's (messages)
  {
    std::map<std::array<std::uint32_t, 3>, std::uint32_t> first;  // sorted corners -> facet
    for (std::uint32_t f = 0; f < input.num_tris(); ++f) {
      const std::uint32_t* t = input.tri(f);
      std::array<std::uint32_t, 3> key{t[0], t[1], t[2]};
      std::sort(key.begin(), key.end());
      const auto [it, fresh] = first.emplace(key, f);
      if (fresh) {
        m.tris.insert(m.tris.end(), t, t + 3);
        orig.push_back(f);
        continue;
      }
      const std::uint32_t* u = input.tri(it->second);
      const int r = u[1] == t[0] ? 1 : u[2] == t[0] ? 2 : 0;  // u rotated to start where t starts
      if (u[(r + 1) % 3] == t[1])
        throw SurfaceError(source + ": facets " + std::to_string(it->second) + " and " + std::to_string(f) +
                               " are duplicates (the same corners, facing the same way)",
                           {it->second, f}, SurfaceError::Defect::duplicates);
    }
  }
  const std::size_t nf = m.num_tris();
  // Side s of facet f (0: the side its normal points to, 1: the other) is half-facet 2 f + s.
  UnionFind uf(2 * nf);
  for (auto& entry : edge_facets(m)) {  // not a structured binding: the lambdas below use `list`
    const auto& edge = entry.first;
    auto& list = entry.second;
    const K::Point_3 a = point(m, edge.first), b = point(m, edge.second);
    if (list.size() == 1)
      throw SurfaceError(source + ": facet " + std::to_string(orig[list[0].facet]) + " has an open edge", {orig[list[0].facet]});
    // Counter-clockwise about a -> b from the first facet's half-plane: the half-turn (0, pi)
    // is the side its normal as run a -> b points to; within a half, orientation decides.
    const K::Point_3 c0 = point(m, list[0].apex);
    auto half = [&](const AtEdge& x) {
      if (x.facet == list[0].facet) return 0;
      const CGAL::Orientation o = CGAL::orientation(a, b, c0, point(m, x.apex));
      if (o == CGAL::POSITIVE) return 1;
      if (o == CGAL::NEGATIVE) return 3;
      if (CGAL::coplanar_orientation(a, b, c0, point(m, x.apex)) == CGAL::POSITIVE)
        throw SurfaceError(source + ": facets " + std::to_string(orig[list[0].facet]) + " and " + std::to_string(orig[x.facet]) +
                               " overlap along their common edge",
                           {orig[list[0].facet], orig[x.facet]});
      return 2;  // the opposite half-plane
    };
    std::vector<std::pair<int, AtEdge>> sorted;
    for (const AtEdge& x : list) sorted.push_back({half(x), x});
    std::sort(sorted.begin(), sorted.end(), [&](const auto& x, const auto& y) {
      if (x.first != y.first) return x.first < y.first;
      if (x.second.facet == y.second.facet) return false;
      return CGAL::orientation(a, b, point(m, x.second.apex), point(m, y.second.apex)) == CGAL::POSITIVE;
    });
    for (std::size_t i = 0; i + 1 < sorted.size(); ++i)
      if (sorted[i].first == sorted[i + 1].first && (sorted[i].first == 1 || sorted[i].first == 3) &&
          CGAL::orientation(a, b, point(m, sorted[i].second.apex), point(m, sorted[i + 1].second.apex)) == CGAL::ZERO)
        throw SurfaceError(source + ": facets " + std::to_string(orig[sorted[i].second.facet]) + " and " +
                               std::to_string(orig[sorted[i + 1].second.facet]) + " overlap along their common edge",
                           {orig[sorted[i].second.facet], orig[sorted[i + 1].second.facet]});
    // The space between consecutive facets f, g (counter-clockwise) is on f's counter-clockwise
    // side and g's clockwise side. The counter-clockwise side of a facet is its normal's side
    // when it runs a -> b.
    const std::size_t k = sorted.size();
    for (std::size_t i = 0; i < k; ++i) {
      const AtEdge& f = sorted[i].second;
      const AtEdge& g = sorted[(i + 1) % k].second;
      const std::uint32_t f_ccw = 2 * f.facet + (f.dir > 0 ? 0 : 1);
      const std::uint32_t g_cw = 2 * g.facet + (g.dir > 0 ? 1 : 0);
      uf.join(f_ccw, g_cw);
    }
  }
  // Classes of sides: each bounds one region. Outward orientation: a cell on the normal's side
  // (side 0) sees the facet reversed.
  std::map<std::uint32_t, std::vector<std::uint32_t>> classes;  // root -> half-facets, by id
  for (std::uint32_t h = 0; h < 2 * nf; ++h) classes[uf.find(h)].push_back(h);
  for (std::uint32_t f = 0; f < nf; ++f)
    if (uf.find(2 * f) == uf.find(2 * f + 1))
      throw SurfaceError(source + ": facet " + std::to_string(orig[f]) +
                             " has the same region on both sides (a wall that divides nothing)",
                         {orig[f]});
  std::vector<SurfaceMesh> cells;
  std::size_t unbounded = 0;
  for (const auto& [root, sides] : classes) {
    SurfaceMesh cell;
    std::map<std::uint32_t, std::uint32_t> id;
    double volume6 = 0;
    for (std::uint32_t h : sides) {
      const std::uint32_t* t = m.tri(h / 2);
      const std::uint32_t v[3] = {t[0], h % 2 == 0 ? t[2] : t[1], h % 2 == 0 ? t[1] : t[2]};
      const double *p = m.points.p(v[0]), *q = m.points.p(v[1]), *r = m.points.p(v[2]);
      volume6 += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                 p[2] * (q[0] * r[1] - q[1] * r[0]);
      for (std::uint32_t x : v) {
        auto [it, fresh] = id.emplace(x, std::uint32_t(cell.points.size()));
        if (fresh) cell.points.push_back(m.points.p(x)[0], m.points.p(x)[1], m.points.p(x)[2]);
        cell.tris.push_back(it->second);
      }
    }
    if (volume6 > 0) cells.push_back(std::move(cell));
    else ++unbounded;
  }
  // One unbounded region per connected piece of the surface; more: a cell inside a cell.
  UnionFind pieces(m.points.size());
  for (std::size_t f = 0; f < nf; ++f) pieces.join(m.tri(f)[0], m.tri(f)[1]), pieces.join(m.tri(f)[0], m.tri(f)[2]);
  std::size_t npieces = 0;
  std::vector<std::uint8_t> used(m.points.size(), 0);
  for (std::uint32_t v : m.tris) used[v] = 1;
  for (std::uint32_t v = 0; v < m.points.size(); ++v) npieces += used[v] && pieces.find(v) == v;
  if (unbounded != npieces)
    throw SurfaceError(source + ": the surface with internal walls has a cell inside another cell or a void (" +
                           std::to_string(cells.size()) + " cells, " + std::to_string(unbounded) +
                           " unbounded sides for " + std::to_string(npieces) +
                           " pieces); such parts must be separate bodies",
                       {});
  return cells;
}

}  // namespace kdmesh
