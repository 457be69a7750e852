// kdmesh — nodes on feature corners and along feature edges.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/placement/edge_sampling.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "core/error.h"

namespace kdmesh {

namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

/// Smallest facet id incident to each surface edge (a, b).
std::unordered_map<std::uint64_t, std::uint32_t> edge_facets(const SurfaceMesh& s) {
  std::unordered_map<std::uint64_t, std::uint32_t> m;
  m.reserve(s.tris.size());
  for (std::size_t f = s.num_tris(); f-- > 0;) {
    const std::uint32_t* t = s.tri(f);
    for (int i = 0; i < 3; ++i) m[edge_key(t[i], t[(i + 1) % 3])] = std::uint32_t(f);
  }
  return m;
}

}  // namespace

std::vector<FeaturePolyline> chain_feature_edges(const SurfaceMesh& surface,
                                                 const FeatureEdges& features) {
  const std::size_t np = surface.points.size();
  const std::size_t ne = features.num_edges();
  // Adjacency in CSR form: for each point, the incident feature edge ids.
  std::vector<std::uint32_t> start(np + 1, 0), inc(2 * ne);
  for (std::size_t e = 0; e < ne; ++e)
    for (int k = 0; k < 2; ++k) {
      const std::uint32_t v = features.edges[2 * e + k];
      if (v >= np)
        throw UsageError("feature edge " + std::to_string(e) + " refers to point " +
                         std::to_string(v) + ", but the surface has " + std::to_string(np) +
                         " points");
      ++start[v + 1];
    }
  for (std::size_t v = 0; v < np; ++v) start[v + 1] += start[v];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t e = 0; e < ne; ++e)
      for (int k = 0; k < 2; ++k) inc[fill[features.edges[2 * e + k]]++] = std::uint32_t(e);
  }
  std::vector<char> corner(np, 0);
  for (const std::uint32_t c : features.corners)
    if (c < np) corner[c] = 1;
  for (std::size_t v = 0; v < np; ++v)
    if (start[v + 1] - start[v] != 0 && start[v + 1] - start[v] != 2) corner[v] = 1;

  std::vector<char> used(ne, 0);
  std::vector<FeaturePolyline> out;
  auto walk = [&](std::uint32_t v, std::uint32_t e) {
    FeaturePolyline pl;
    pl.points.push_back(v);
    for (;;) {
      used[e] = 1;
      const std::uint32_t a = features.edges[2 * e], b = features.edges[2 * e + 1];
      v = a == v ? b : a;
      pl.points.push_back(v);
      if (corner[v] || v == pl.points.front()) break;
      std::uint32_t next = std::uint32_t(-1);
      for (std::uint32_t k = start[v]; k < start[v + 1]; ++k)
        if (!used[inc[k]]) next = inc[k];
      if (next == std::uint32_t(-1)) break;
      e = next;
    }
    pl.closed = !corner[pl.points.front()] && pl.points.back() == pl.points.front();
    out.push_back(std::move(pl));
  };
  // Open polylines from corners, in point order; then corner-free loops from their
  // smallest point (the first unused point in id order is the smallest of its loop).
  for (std::uint32_t v = 0; v < np; ++v)
    if (corner[v])
      for (std::uint32_t k = start[v]; k < start[v + 1]; ++k)
        if (!used[inc[k]]) walk(v, inc[k]);
  for (std::uint32_t v = 0; v < np; ++v)
    for (std::uint32_t k = start[v]; k < start[v + 1]; ++k)
      if (!used[inc[k]]) {
        // Of the two loop edges at v, start along the one towards the smaller neighbour.
        std::uint32_t best = inc[k];
        for (std::uint32_t m = start[v]; m < start[v + 1]; ++m) {
          const std::uint32_t e = inc[m];
          if (used[e]) continue;
          auto other = [&](std::uint32_t x) {
            return features.edges[2 * x] == v ? features.edges[2 * x + 1] : features.edges[2 * x];
          };
          if (other(e) < other(best)) best = e;
        }
        walk(v, best);
      }
  return out;
}

void place_edge_nodes(const SurfaceMesh& surface, const FeatureEdges& features,
                      const SizingField& sizing, double beta, SpacingGrid& grid, NodeSet& nodes,
                      SpacingGrid* segment_balls, bool skip_placed_corners) {
  const auto efacet = edge_facets(surface);
  auto facet_of_edge = [&](std::uint32_t a, std::uint32_t b) {
    const auto it = efacet.find(edge_key(a, b));
    if (it == efacet.end())
      throw GeometryError("feature edge (" + std::to_string(a) + ", " + std::to_string(b) +
                          ") is not an edge of the surface");
    return it->second;
  };
  // Corners: facet = smallest incident facet.
  std::vector<std::uint32_t> vfacet(surface.points.size(), kNoFacet);
  for (std::size_t f = surface.num_tris(); f-- > 0;)
    for (int i = 0; i < 3; ++i) vfacet[surface.tri(f)[i]] = std::uint32_t(f);
  const std::vector<FeaturePolyline> lines = chain_feature_edges(surface, features);
  std::vector<char> is_corner(surface.points.size(), 0);
  auto add_corner = [&](std::uint32_t c) {
    if (is_corner[c]) return;
    is_corner[c] = 1;
    if (vfacet[c] == kNoFacet)
      throw GeometryError("feature corner " + std::to_string(c) + " is on no surface facet");
    const double* p = surface.points.p(c);
    const float h = float(sizing(p));
    if (skip_placed_corners && grid.conflicts(p, h, 1e-9)) return;
    nodes.push_back(p, NodeKind::corner, vfacet[c], h);
    grid.insert(p, h);
  };
  for (const std::uint32_t c : features.corners)
    if (c < surface.points.size()) add_corner(c);
  for (const FeaturePolyline& pl : lines)
    if (!pl.closed) {
      add_corner(pl.points.front());
      add_corner(pl.points.back());
    }

  // Along each polyline: cumulative I(s) = integral ds/h, by the midpoint rule on pieces
  // short against h (<= h/8), then nodes at I = I_total * i / n.
  struct Piece {
    std::uint32_t seg;   // segment index in the polyline
    double t0, t1;       // parameter range on the segment
    double i0, i1;       // cumulative integral at t0, t1
  };
  std::vector<Piece> pieces;
  for (const FeaturePolyline& pl : lines) {
    pieces.clear();
    double total = 0;
    const std::size_t nseg = pl.points.size() - 1;
    for (std::size_t s = 0; s < nseg; ++s) {
      const double* a = surface.points.p(pl.points[s]);
      const double* b = surface.points.p(pl.points[s + 1]);
      const double len = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
      const double hmin_end = std::min(sizing(a), sizing(b));
      const std::size_t m = std::clamp<std::size_t>(std::size_t(std::ceil(8 * len / hmin_end)), 1,
                                                    std::size_t(1) << 20);
      for (std::size_t k = 0; k < m; ++k) {
        const double t0 = double(k) / double(m), t1 = double(k + 1) / double(m);
        const double tm = (t0 + t1) / 2;
        const double x[3] = {a[0] + tm * (b[0] - a[0]), a[1] + tm * (b[1] - a[1]),
                             a[2] + tm * (b[2] - a[2])};
        const double di = len * (t1 - t0) / sizing(x);
        pieces.push_back({std::uint32_t(s), t0, t1, total, total + di});
        total += di;
      }
    }
    const std::size_t n = std::max<std::size_t>(1, std::size_t(std::llround(total)));
    const std::size_t first = pl.closed ? 0 : 1;  // a loop's start is an edge node too
    std::size_t pc = 0;
    // The polyline's nodes in order (the corners at an open one's ends), for segment_balls.
    std::vector<double> kept;
    if (!pl.closed) kept.insert(kept.end(), surface.points.p(pl.points.front()), surface.points.p(pl.points.front()) + 3);
    for (std::size_t i = first; i < n; ++i) {
      const double target = total * double(i) / double(n);
      while (pc + 1 < pieces.size() && pieces[pc].i1 < target) ++pc;
      const Piece& q = pieces[pc];
      const double w = q.i1 > q.i0 ? std::clamp((target - q.i0) / (q.i1 - q.i0), 0.0, 1.0) : 0.0;
      const double t = q.t0 + w * (q.t1 - q.t0);
      const std::uint32_t va = pl.points[q.seg], vb = pl.points[q.seg + 1];
      const double* a = surface.points.p(va);
      const double* b = surface.points.p(vb);
      const double x[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                           a[2] + t * (b[2] - a[2])};
      const float h = float(sizing(x));
      if (beta > 0 && grid.conflicts(x, h, beta)) continue;
      nodes.push_back(x, NodeKind::edge, facet_of_edge(va, vb), h);
      grid.insert(x, h);
      kept.insert(kept.end(), x, x + 3);
    }
    if (!segment_balls) continue;
    const double* last = surface.points.p(pl.closed ? pl.points.front() : pl.points.back());
    if (pl.closed && kept.size() >= 3) last = kept.data();  // the loop closes at its first node
    const double end[3] = {last[0], last[1], last[2]};  // (kept may move as it grows)
    kept.insert(kept.end(), end, end + 3);
    for (std::size_t k = 3; k < kept.size(); k += 3) {
      const double* a = &kept[k - 3];
      const double* b = &kept[k];
      const double mid[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
      const double len = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
      if (len > 0) segment_balls->insert(mid, len);
    }
  }
}

}  // namespace kdmesh
