// kdmesh — the automatic curvature terms of the sizing field: measured scale by scale on a
// hierarchy of cubic cells, so that the roughness of a scan (facet normals wobbling at the
// facets' own scale) does not pass for curvature at the scale of the mesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/curvature_sizes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <vector>

#include "sizing/surface_edges.h"

namespace kdmesh {
namespace {

/// The size that a radius of curvature r asks for (h_max when neither term is on), and the
/// floor `across` of the chordal term (the facets' own spacing; 0 at the cell levels).
struct SizeRule {
  double angle = 0, chord = 0, h_max = 0, h_min = 0;
  double operator()(double r, double across) const {
    double h = h_max;
    if (angle > 0) h = std::min(h, angle * r);
    // Below the facets' own spacing the input is flat between its edges: a smaller size
    // follows the facets no better (the creases are the feature edges' business).
    if (chord > 0) h = std::min(h, std::max(std::sqrt(12 * r * chord), across));
    return std::max(h, h_min);
  }
};

struct Cell {
  double an[3] = {0, 0, 0};  // sum of area x unit normal
  double ac[3] = {0, 0, 0};  // sum of area x centroid
  double area = 0;
};

using Key = std::array<std::int64_t, 3>;
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return std::size_t(k[0] * 73856093) ^ std::size_t(k[1] * 19349663) ^ std::size_t(k[2] * 83492791);
  }
};

}  // namespace

void add_curvature_sizes(const SurfaceMesh& surface, const SizingOptions& options, double min_size,
                         WeightedSegments& out, SizingAutoStats& stats) {
  SizeRule rule;
  rule.angle = options.curvature_angle_deg / 180.0 * std::numbers::pi;
  rule.chord = options.chordal_deviation;
  rule.h_max = options.max_size;
  rule.h_min = min_size;
  if (!(rule.angle > 0) && !(rule.chord > 0)) return;
  const double feature = options.feature_angle_deg > 0
                             ? options.feature_angle_deg / 180.0 * std::numbers::pi
                             : std::numeric_limits<double>::infinity();
  const std::size_t nf = surface.num_tris();
  auto emit = [&](const double* a, const double* b, double h, double r) {
    if (!(h < rule.h_max)) return;
    out.push_back(a, b, h);
    if (stats.curvature_places++ == 0 || h < stats.min_curvature_size) stats.min_curvature_size = h;
    if (stats.curvature_places == 1 || r < stats.min_radius) stats.min_radius = r;
  };

  // Per facet: area, unit normal, centroid.
  std::vector<double> area(nf), nrm(3 * nf), cen(3 * nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* t = surface.tri(f);
    const double *a = surface.points.p(t[0]), *b = surface.points.p(t[1]), *c = surface.points.p(t[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    area[f] = len / 2;
    for (int k = 0; k < 3; ++k) {
      nrm[3 * f + k] = len > 0 ? n[k] / len : 0;
      cen[3 * f + k] = (a[k] + b[k] + c[k]) / 3;
    }
  }
  if (nf == 0) return;
  // The finest level: twice the typical facet (the median of sqrt(2 area)); below it a cell
  // holds too few facets to average their normals.
  std::vector<double> sizes(area);
  std::nth_element(sizes.begin(), sizes.begin() + std::ptrdiff_t(nf / 2), sizes.end());
  const double typical = std::sqrt(2 * sizes[nf / 2]);

  // Levels: cells of edge s = h_max, h_max / 2, ... At a level, a cell whose facets agree on a
  // normal (within 25 deg) and that has such neighbours is measured: r = the least over its
  // 26 neighbours of (distance between the cells' area centroids) / (angle between their mean
  // normals). Where the size that r asks for is at least s, the surface is smooth enough at
  // this scale: a point of that size goes to `out` and the cell's facets are done. The rest
  // (features, thin walls, strong curvature, facets larger than the cells) goes one level
  // finer; what is left below the facets' scale is measured per surface edge.
  std::vector<std::uint8_t> active(nf, 1);
  const double cos_agree = std::cos(25.0 / 180.0 * std::numbers::pi);
  const double finest = std::max(min_size, 2 * typical);
  std::unordered_map<Key, Cell, KeyHash> cells;
  std::vector<std::pair<Key, std::uint32_t>> member;  // (cell, facet) of the active facets
  for (double s = rule.h_max; s >= finest && s > 0; s /= 2) {
    cells.clear();
    member.clear();
    for (std::size_t f = 0; f < nf; ++f) {
      if (!active[f]) continue;
      Key k;
      for (int q = 0; q < 3; ++q) k[q] = std::int64_t(std::floor(cen[3 * f + q] / s));
      Cell& c = cells[k];
      for (int q = 0; q < 3; ++q) c.an[q] += area[f] * nrm[3 * f + q], c.ac[q] += area[f] * cen[3 * f + q];
      c.area += area[f];
      member.push_back({k, std::uint32_t(f)});
    }
    auto mean_normal = [&](const Cell& c, double* n) {
      const double l = std::sqrt(c.an[0] * c.an[0] + c.an[1] * c.an[1] + c.an[2] * c.an[2]);
      if (!(c.area > 0) || !(l >= cos_agree * c.area)) return false;  // no agreed normal
      for (int q = 0; q < 3; ++q) n[q] = c.an[q] / l;
      return true;
    };
    std::unordered_map<Key, double, KeyHash> resolved;  // cell -> its size, when resolved
    for (const auto& [k, c] : cells) {
      double n[3];
      if (!mean_normal(c, n)) continue;
      const double x[3] = {c.ac[0] / c.area, c.ac[1] / c.area, c.ac[2] / c.area};
      double r = std::numeric_limits<double>::infinity();
      bool neighbours = false;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (!dx && !dy && !dz) continue;
            const auto it = cells.find({k[0] + dx, k[1] + dy, k[2] + dz});
            double m[3];
            if (it == cells.end() || !mean_normal(it->second, m)) continue;
            neighbours = true;
            const Cell& o = it->second;
            const double d[3] = {o.ac[0] / o.area - x[0], o.ac[1] / o.area - x[1], o.ac[2] / o.area - x[2]};
            const double dist = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const double cr[3] = {n[1] * m[2] - n[2] * m[1], n[2] * m[0] - n[0] * m[2], n[0] * m[1] - n[1] * m[0]};
            const double ang = std::atan2(std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]),
                                          n[0] * m[0] + n[1] * m[1] + n[2] * m[2]);
            if (ang > 0) r = std::min(r, dist / ang);
          }
      if (!neighbours) continue;
      const double h = rule(r, 0);
      if (!(h >= s)) continue;
      resolved[k] = h;
      emit(x, x, h, r);
    }
    for (const auto& [k, f] : member)
      if (resolved.count(k)) active[f] = 0;
  }

  // Below the cells: per surface edge with an active facet, r = d / deviation, d the distance
  // across the edge (perpendicular to it) between the centroids of its two facets (exact on a
  // sphere of equilateral facets, 2/3 of the true radius on a cylinder of long strips).
  for (const SurfaceEdge& e : surface_edges(surface)) {
    if (!e.manifold() || !(e.deviation > 0) || !(e.deviation < feature)) continue;
    if (!active[e.f0] && !active[e.f1]) continue;
    const double* a = surface.points.p(e.lo);
    const double* b = surface.points.p(e.hi);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    if (!(uu > 0)) continue;
    double w[3];
    for (int k = 0; k < 3; ++k) w[k] = cen[3 * e.f1 + k] - cen[3 * e.f0 + k];
    const double along = (w[0] * u[0] + w[1] * u[1] + w[2] * u[2]) / uu;
    for (int k = 0; k < 3; ++k) w[k] -= along * u[k];
    const double across = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double r = across / e.deviation;
    if (!(r > 0) || !std::isfinite(r)) continue;
    emit(a, b, rule(r, across), r);
  }
}

}  // namespace kdmesh
