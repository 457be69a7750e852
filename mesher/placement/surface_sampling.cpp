// kdmesh — Poisson-disk nodes on surface facets.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/placement/surface_sampling.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "core/rng.h"
#include "mesher/surface/crease_points.h"

namespace kdmesh {

namespace {

/// Cuts of a facet in the sweep: a backstop only. A piece is cut while its diameter exceeds
/// its sampling step >= beta h_min / 2 >= beta 2^-23 x the extent (numeric_ranges.h), and two
/// cuts through the longer sides at least nearly halve the diameter, so a facet no larger than
/// the extent stops far above this depth.
constexpr int kMaxSweepDepth = 200;
/// Rows of the sweep's triangular pattern: sqrt(3)/2 of the spacing along a row.
constexpr double kRowSpacing = 0.8660254037844386;

/// Strictly inside the diametral ball of a feature-curve segment (place_edge_nodes'
/// segment_balls: midpoints stored with h = the segment's length, so the test radius
/// 1 x (0 + length) / 2 is the ball's).
bool in_feature_ball(const SpacingGrid* balls, const double* p) { return balls && balls->conflicts(p, 0, 1); }

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
                        const SurfaceSamplingOptions& options, SpacingGrid& grid, NodeSet& nodes,
                        const SpacingGrid* feature_balls) {
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
    if (grid.conflicts(p, h, options.beta) || in_feature_ball(feature_balls, p)) return;
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

/// The sweep of facet abc (in its plane frame: a at the origin, b = (bx, 0), c = (cx, cy)),
/// after the darts: it fills what they and the neighbouring facets' nodes left, calling
/// visit(v, w) at points of barycentric coordinates (1 - v - w, v, w).
///
/// Pieces are convex quadrilaterals (a triangle repeats its apex); the first is the facet,
/// its apex opposite its shortest edge. A piece is cut through the midpoints of its longer
/// pair of opposite sides, recursively, while it is larger than its sampling step and either
/// large against the local size (diameter D > 8 r at its corners' mean) or where the size
/// varies (its lower bound h_lo over the piece, SizingField::lower_bound, under h_c / 2). A
/// final piece is swept in rows sqrt(3)/2 step apart, points step apart along each, odd rows
/// shifted by half a spacing (sides and corners included), step = r_lo / 2, r_lo = beta
/// max(h_min, h_lo): a triangular pattern, every point of a rectangle within step / sqrt(3)
/// of one. Each point becomes a node or conflicts with one, so that no surface point is left
/// farther than about beta h + r / 2 from a node. (A square pattern at step left a cube at
/// h = 0.25 needing 117 Steiner points to recover its boundary.)
///
/// A long thin facet is cut across into strips, so the work is proportional to the facet's
/// area / r^2 plus its length / r. Splitting into 4 similar triangles (until 2026-11) made it
/// the length squared: 6 minutes on the walls of a 64-sided cylinder 100 long at size 0.3,
/// issue 19; bisecting the longest edge still made it length^1.58 (a thin triangle bisects
/// into 3 of half the length per halving). A uniform grid at the facet's smallest r cost
/// O(area / r_min^2): minutes on a long housing wall refined at one end.
template <class Visit>
void sweep_facet(const double* a, const double* b, const double* c, double bx, double cx, double cy,
                 const SizingField& sizing, double beta, SurfaceSamplingStats& stats, Visit&& visit) {
  const double hfloor = std::max(sizing.min_size(), 1e-300);
  struct Piece {
    double v[4], w[4];  // barycentric (v, w) of the corners in the facet: a zero stays exact,
    int depth;          // so that nodes on the facet's edges ab and ac lie exactly on them
  };
  const double fv[3] = {0, 1, 0}, fw[3] = {0, 0, 1};  // a, b, c
  const double opp[3] = {(bx - cx) * (bx - cx) + cy * cy, cx * cx + cy * cy, bx * bx};  // squared edges opposite a, b, c
  const int apex = opp[0] <= opp[1] && opp[0] <= opp[2] ? 0 : (opp[1] <= opp[2] ? 1 : 2);
  const int c2 = (apex + 1) % 3, c3 = (apex + 2) % 3;
  std::vector<Piece> pieces{{{fv[apex], fv[apex], fv[c2], fv[c3]}, {fw[apex], fw[apex], fw[c2], fw[c3]}, 0}};
  while (!pieces.empty()) {
    const Piece q = pieces.back();
    pieces.pop_back();
    double X[4], Y[4];  // frame coordinates
    for (int k = 0; k < 4; ++k) {
      X[k] = q.v[k] * bx + q.w[k] * cx;
      Y[k] = q.w[k] * cy;
    }
    auto dist = [&](int i, int j) { return std::hypot(X[j] - X[i], Y[j] - Y[i]); };
    const double D = std::max({dist(0, 1), dist(1, 2), dist(2, 3), dist(3, 0), dist(0, 2), dist(1, 3)});
    const double vc = (q.v[0] + q.v[1] + q.v[2] + q.v[3]) / 4, wc = (q.w[0] + q.w[1] + q.w[2] + q.w[3]) / 4;
    double pc[3];
    for (int k = 0; k < 3; ++k) pc[k] = a[k] + vc * (b[k] - a[k]) + wc * (c[k] - a[k]);
    const double hc = sizing(pc);
    const double h_lo = sizing.lower_bound(pc, D, hc);  // the piece lies within D of pc
    const double step = 0.5 * beta * std::max(hfloor, h_lo);
    if (q.depth < kMaxSweepDepth && D > step && (D > 8 * beta * hc || h_lo < 0.5 * hc)) {
      Piece p0 = q, p1 = q;
      p0.depth = p1.depth = q.depth + 1;
      if (dist(1, 2) + dist(3, 0) >= dist(0, 1) + dist(2, 3)) {  // cut sides 12 and 30
        const double m12v = (q.v[1] + q.v[2]) / 2, m12w = (q.w[1] + q.w[2]) / 2;
        const double m30v = (q.v[3] + q.v[0]) / 2, m30w = (q.w[3] + q.w[0]) / 2;
        p0.v[2] = m12v, p0.w[2] = m12w, p0.v[3] = m30v, p0.w[3] = m30w;  // (0, 1, m12, m30)
        p1.v[0] = m30v, p1.w[0] = m30w, p1.v[1] = m12v, p1.w[1] = m12w;  // (m30, m12, 2, 3)
      } else {  // cut sides 01 and 23
        const double m01v = (q.v[0] + q.v[1]) / 2, m01w = (q.w[0] + q.w[1]) / 2;
        const double m23v = (q.v[2] + q.v[3]) / 2, m23w = (q.w[2] + q.w[3]) / 2;
        p0.v[1] = m01v, p0.w[1] = m01w, p0.v[2] = m23v, p0.w[2] = m23w;  // (0, m01, m23, 3)
        p1.v[0] = m01v, p1.w[0] = m01w, p1.v[3] = m23v, p1.w[3] = m23w;  // (m01, 1, 2, m23)
      }
      pieces.push_back(p1);
      pieces.push_back(p0);  // swept first
      continue;
    }
    ++stats.sweep_pieces;
    // Rows: bilinear, from side (i0, i1) to side (i3, i2), in the direction of fewer points.
    auto rows_and_points = [&](double across, double along, std::int64_t& nr, std::int64_t& np) {
      nr = std::clamp<std::int64_t>(std::int64_t(std::ceil(across / (kRowSpacing * step))), 1, 4096);
      np = std::clamp<std::int64_t>(std::int64_t(std::ceil(along / step)), 1, 4096);
    };
    std::int64_t nr_a, np_a, nr_b, np_b;  // rows from side 01 to side 32, or from side 12 to side 03
    rows_and_points(std::max(dist(0, 3), dist(1, 2)), std::max(dist(0, 1), dist(3, 2)), nr_a, np_a);
    rows_and_points(std::max(dist(1, 0), dist(2, 3)), std::max(dist(1, 2), dist(0, 3)), nr_b, np_b);
    const bool first = (nr_a + 1) * (np_a + 1) <= (nr_b + 1) * (np_b + 1);
    const int i0 = first ? 0 : 1, i1 = first ? 1 : 2, i2 = first ? 2 : 3, i3 = first ? 3 : 0;
    const std::int64_t nr = first ? nr_a : nr_b;
    for (std::int64_t i = 0; i <= nr; ++i) {
      const double t = double(i) / double(nr);
      const double sv = q.v[i0] + t * (q.v[i3] - q.v[i0]), sw = q.w[i0] + t * (q.w[i3] - q.w[i0]);
      const double ev = q.v[i1] + t * (q.v[i2] - q.v[i1]), ew = q.w[i1] + t * (q.w[i2] - q.w[i1]);
      const double row = std::hypot((ev - sv) * bx + (ew - sw) * cx, (ew - sw) * cy);
      const std::int64_t n = std::clamp<std::int64_t>(std::int64_t(std::ceil(row / step)), 0, 4096);
      // Odd rows take the midpoints between the even rows' points (a triangular pattern),
      // and their two ends.
      const bool odd = (i & 1) && n > 0;
      for (std::int64_t j = 0; j <= n + (odd ? 1 : 0); ++j) {
        const double s2 = n == 0 ? 0.0
                          : !odd ? double(j) / double(n)
                                 : (j == 0 ? 0.0 : j == n + 1 ? 1.0 : (double(j) - 0.5) / double(n));
        const double vv = sv + s2 * (ev - sv), ww = sw + s2 * (ew - sw);
        visit(vv, ww, h_lo);
        ++stats.sweep_points;
      }
    }
  }
}

}  // namespace

SurfaceSamplingStats place_surface_nodes(const SurfaceMesh& surface, const SizingField& sizing,
                                         const SurfaceSamplingOptions& options, SpacingGrid& grid,
                                         NodeSet& nodes, const std::function<void(double)>& progress,
                                         const SpacingGrid* feature_balls) {
  SurfaceSamplingStats stats;
  const std::size_t nf = surface.num_tris();
  const double grad = sizing.options().gradation;
  place_crease_nodes(surface, sizing, options, grid, nodes, feature_balls);
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
    // h_floor: a lower bound of h at the point (0: none). A conflict at a size below h is a
    // conflict at h (the spacing only grows with h), and most tries conflict: those found
    // at the bound need no field evaluation. The decisions are the same.
    auto try_bary = [&](double vv, double w, double x, double y, double h_floor) -> bool {
      const double uu = (1 - vv) - w;
      if (!(uu >= 0 && vv >= 0 && w >= 0)) return false;
      double p[3];
      // From a: a facet in a coordinate plane keeps that coordinate exactly (uu + vv + w is
      // not always exactly 1).
      for (int k = 0; k < 3; ++k) p[k] = a[k] + vv * (b[k] - a[k]) + w * (c[k] - a[k]);
      if (h_floor > 0 && grid.conflicts(p, h_floor, options.beta)) return false;
      const double h = sizing(p);
      if (grid.conflicts(p, h, options.beta) || in_feature_ball(feature_balls, p)) return false;
      grid.insert(p, h);
      nodes.push_back(p, NodeKind::surface, std::uint32_t(f), float(h));
      active.push_back(x);
      active.push_back(y);
      active.push_back(h);
      return true;
    };
    auto try_add = [&](double x, double y, double h_floor) -> bool {  // frame coordinates
      const double w = y / cy;
      return try_bary((x - w * cx) / bx, w, x, y, h_floor);
    };
    // A lower bound of h at a point within `dist` of a point where h >= h_known (h is
    // g-Lipschitz), lowered for the rounding of h and of the points' positions (the margins
    // are far above it).
    const double scale = std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]) + lu + std::fabs(cx) + std::fabs(cy);
    auto floor_at = [&](double h_known, double dist) {
      return h_known * (1 - 1e-9) - grad * (dist * (1 + 1e-6) + 1e-12 * scale);
    };
    auto advance = [&] {  // Bridson step around the accepted nodes (depth-first, newest first)
      while (!active.empty()) {
        const std::size_t k = active.size() - 3;
        const double x0 = active[k], y0 = active[k + 1], r = options.beta * active[k + 2];
        bool added = false;
        for (int tr = 0; tr < options.tries && !added; ++tr) {
          const double ang = rng.uniform(0, 2 * std::numbers::pi);
          const double rad = r * (1 + rng.uniform());
          // The try is rad from the active node, whose h is active[k + 2].
          added = try_add(x0 + rad * std::cos(ang), y0 + rad * std::sin(ang), floor_at(active[k + 2], rad));
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
      try_add(r1 * bx + r2 * cx, r2 * cy, 0.0);
      advance();
    }
    sweep_facet(a, b, c, bx, cx, cy, sizing, options.beta, stats, [&](double vv, double ww, double h_floor) {
      // h_floor: h's lower bound over the sweep's piece.
      try_bary(vv, ww, vv * bx + ww * cx, ww * cy, floor_at(h_floor, 0));
      advance();
    });
  }
  if (progress) progress(1.0);
  return stats;
}

}  // namespace kdmesh
