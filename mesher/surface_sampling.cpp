// kdmesh — Poisson-disk nodes on surface facets.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface_sampling.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "core/rng.h"
#include "mesher/crease_points.h"

namespace kdmesh {

namespace {

std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t facet) {
  // Distinct streams per facet: splitmix-style mixing of (seed, facet).
  std::uint64_t z = seed * 0x9e3779b97f4a7c15ULL + (facet + 1) * 0xd1b54a32d192ed03ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// Creases first: nodes at the surface vertices on a crease (an edge whose two facets are
/// not coplanar, decided exactly), then along each crease at about h steps. Without them a
/// faceted curved surface (a polygonal cylinder) gets long Delaunay hull edges along its
/// creases wherever no node happens to lie on them.
void place_crease_nodes(const SurfaceMesh& surface, const SizingField& sizing,
                        const SurfaceSamplingOptions& options, SpacingGrid& grid, NodeSet& nodes) {
  struct Crease {
    std::uint32_t a, b, facet;  // a < b; facet: the lower id of the edge's two facets
  };
  std::vector<Crease> creases;
  const CreaseFinder finder(surface);
  for (std::size_t f = 0; f < surface.num_tris(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t g = finder.neighbour(f, j);
      if (!finder.is_crease(f, j) || g == kNoFacet || g < f) continue;
      const std::uint32_t a = surface.tri(f)[j], b = surface.tri(f)[(j + 1) % 3];
      creases.push_back({std::min(a, b), std::max(a, b), std::uint32_t(f)});
    }
  std::sort(creases.begin(), creases.end(), [](const Crease& x, const Crease& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  auto add = [&](const double* p, std::uint32_t facet) {
    const double h = sizing(p);
    if (grid.conflicts(p, h, options.beta)) return;
    grid.insert(p, h);
    nodes.push_back(p, NodeKind::surface, facet, float(h));
  };
  for (const Crease& c : creases) add(surface.points.p(c.a), c.facet);
  for (const Crease& c : creases) add(surface.points.p(c.b), c.facet);
  for (const Crease& c : creases) {
    const double* a = surface.points.p(c.a);
    const double* b = surface.points.p(c.b);
    const double mid[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
    const double len = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    const std::int64_t m = std::clamp<std::int64_t>(std::llround(len / sizing(mid)), 1, 1 << 20);
    for (std::int64_t i = 1; i < m; ++i) {
      const double t = double(i) / double(m);
      const double p[3] = {(1 - t) * a[0] + t * b[0], (1 - t) * a[1] + t * b[1],
                           (1 - t) * a[2] + t * b[2]};
      add(p, c.facet);
    }
  }
}

}  // namespace

void place_surface_nodes(const SurfaceMesh& surface, const SizingField& sizing,
                         const SurfaceSamplingOptions& options, SpacingGrid& grid, NodeSet& nodes,
                         const std::function<void(double)>& progress) {
  const std::size_t nf = surface.num_tris();
  place_crease_nodes(surface, sizing, options, grid, nodes);
  std::vector<double> active;  // (s, t) facet coordinates of the accepted nodes of this facet
  for (std::size_t f = 0; f < nf; ++f) {
    if (progress && (f & 1023) == 0) progress(double(f) / double(nf));
    const std::uint32_t* t = surface.tri(f);
    const double* a = surface.points.p(t[0]);
    const double* b = surface.points.p(t[1]);
    const double* c = surface.points.p(t[2]);
    // Orthonormal frame of the facet plane: e1 along ab, e2 in-plane perpendicular.
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double area2 = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(area2 > 0)) continue;  // degenerate facet: prepared surfaces have none
    // 2D coordinates of b and c in the frame (a at the origin).
    const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double e1[3] = {u[0] / lu, u[1] / lu, u[2] / lu};
    const double e2[3] = {(n[1] * e1[2] - n[2] * e1[1]) / area2,
                          (n[2] * e1[0] - n[0] * e1[2]) / area2,
                          (n[0] * e1[1] - n[1] * e1[0]) / area2};
    const double bx = lu, cx = v[0] * e1[0] + v[1] * e1[1] + v[2] * e1[2];
    const double cy = v[0] * e2[0] + v[1] * e2[1] + v[2] * e2[2];
    // Barycentric (v, w) of a 2D point (x, y): solve x = v bx + w cx, y = w cy.
    Rng rng(stream_seed(options.seed, f));
    active.clear();
    // Adds the point of barycentric coordinates (1 - v - w, v, w) unless it is off the facet
    // or conflicts; x, y are its frame coordinates (for the Bridson step).
    auto try_bary = [&](double vv, double w, double x, double y) -> bool {
      const double uu = (1 - vv) - w;
      if (!(uu >= 0 && vv >= 0 && w >= 0)) return false;
      double p[3];
      for (int k = 0; k < 3; ++k) p[k] = uu * a[k] + vv * b[k] + w * c[k];
      const double h = sizing(p);
      if (grid.conflicts(p, h, options.beta)) return false;
      grid.insert(p, h);
      nodes.push_back(p, NodeKind::surface, std::uint32_t(f), float(h));
      active.push_back(x);
      active.push_back(y);
      active.push_back(h);
      return true;
    };
    auto try_add = [&](double x, double y) -> bool {  // frame coordinates
      const double w = y / cy;
      return try_bary((x - w * cx) / bx, w, x, y);
    };
    auto advance = [&] {  // Bridson step around the accepted nodes (depth-first, newest first)
      while (!active.empty()) {
        const std::size_t k = active.size() - 3;
        const double x0 = active[k], y0 = active[k + 1], r = options.beta * active[k + 2];
        bool added = false;
        for (int tr = 0; tr < options.tries && !added; ++tr) {
          const double ang = rng.uniform(0, 2 * std::numbers::pi);
          const double rad = r * (1 + rng.uniform());
          added = try_add(x0 + rad * std::cos(ang), y0 + rad * std::sin(ang));
        }
        if (!added) active.resize(k);  // retire it (an addition pushed a new active node)
      }
    };
    // Darts: one per 2 r^2 of area (r at the centroid), plus a few, seed the Bridson step;
    // the sweep below then fills what they and the neighbouring facets left.
    const double g[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                         (a[2] + b[2] + c[2]) / 3};
    const double rc = options.beta * sizing(g);
    const double darts = std::min(1e7, std::ceil(0.25 * area2 / (rc * rc)) + 4);
    for (double d = 0; d < darts; ++d) {
      double r1 = rng.uniform(), r2 = rng.uniform();
      if (r1 + r2 > 1) {
        r1 = 1 - r1;
        r2 = 1 - r2;
      }
      try_add(r1 * bx + r2 * cx, r2 * cy);
      advance();
    }
    // Sweep, adaptively: the facet is split at its edge midpoints into 4 pieces, recursively,
    // until a piece is small against the local size: diameter D <= 8 r at its centroid and
    // g D <= h_c / 2 (h is g-Lipschitz, so h >= h_c - g D >= h_c / 2 over the piece). Each
    // piece's grid u a + v b + w c (its edges and corners included) then has steps <=
    // r_lo / 2, r_lo = beta max(h_min, h_c - g D) (g: the gradation), so that no surface point is left farther than
    // about beta h + r / 2 from a node, also where neighbouring facets' nodes cut this facet's
    // free area into pieces the darts missed. A uniform grid at the facet's smallest r instead
    // cost O(area / r_min^2): minutes on a long housing wall refined at one end.
    const double grad = sizing.options().gradation;
    const double hfloor = std::max(sizing.min_size(), 1e-300);
    struct Piece {
      double v[3], w[3];  // barycentric (v, w) of the piece's corners in the facet
      int depth;
    };
    std::vector<Piece> pieces{{{0, 1, 0}, {0, 0, 1}, 0}};
    while (!pieces.empty()) {
      const Piece q = pieces.back();
      pieces.pop_back();
      double X[3], Y[3];
      for (int k = 0; k < 3; ++k) {
        X[k] = q.v[k] * bx + q.w[k] * cx;
        Y[k] = q.w[k] * cy;
      }
      const double D = std::max({std::hypot(X[1] - X[0], Y[1] - Y[0]),
                                 std::hypot(X[2] - X[0], Y[2] - Y[0]),
                                 std::hypot(X[2] - X[1], Y[2] - Y[1])});
      const double vc = (q.v[0] + q.v[1] + q.v[2]) / 3, wc = (q.w[0] + q.w[1] + q.w[2]) / 3;
      double pc[3];
      for (int k = 0; k < 3; ++k) pc[k] = a[k] + vc * (b[k] - a[k]) + wc * (c[k] - a[k]);
      const double hc = sizing(pc);
      if (q.depth < 40 && (D > 8 * options.beta * hc || grad * D > 0.5 * hc)) {
        const double mv[3] = {(q.v[0] + q.v[1]) / 2, (q.v[1] + q.v[2]) / 2, (q.v[2] + q.v[0]) / 2};
        const double mw[3] = {(q.w[0] + q.w[1]) / 2, (q.w[1] + q.w[2]) / 2, (q.w[2] + q.w[0]) / 2};
        const int d = q.depth + 1;
        // Pushed in reverse so that they are swept corner 0, 1, 2, then the middle piece.
        pieces.push_back({{mv[0], mv[1], mv[2]}, {mw[0], mw[1], mw[2]}, d});
        pieces.push_back({{mv[2], mv[1], q.v[2]}, {mw[2], mw[1], q.w[2]}, d});
        pieces.push_back({{mv[0], q.v[1], mv[1]}, {mw[0], q.w[1], mw[1]}, d});
        pieces.push_back({{q.v[0], mv[0], mv[2]}, {q.w[0], mw[0], mw[2]}, d});
        continue;
      }
      const double step = 0.5 * options.beta * std::max(hfloor, hc - grad * D);
      const std::int64_t m = std::clamp<std::int64_t>(std::int64_t(std::ceil(D / step)), 1, 4096);
      for (std::int64_t i = 0; i <= m; ++i)
        for (std::int64_t j = 0; i + j <= m; ++j) {
          const double s1 = double(i) / double(m), s2 = double(j) / double(m);
          const double vv = q.v[0] + s1 * (q.v[1] - q.v[0]) + s2 * (q.v[2] - q.v[0]);
          const double ww = q.w[0] + s1 * (q.w[1] - q.w[0]) + s2 * (q.w[2] - q.w[0]);
          try_bary(vv, ww, vv * bx + ww * cx, ww * cy);
          advance();
        }
    }
  }
  if (progress) progress(1.0);
}

}  // namespace kdmesh
