// kdmesh — node and memory estimate of a meshing job.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/resource_estimate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/parallel_for.h"
#include "mesher/point_values.h"

namespace kdmesh {

namespace {

double triangle_area(const double* a, const double* b, const double* c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

double dist2(const double* a, const double* b) {
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

/// Upper bound of h within distance `radius` of a point where it is `hc` (h is g-Lipschitz
/// and at most h_max): what the lower bounds of the cap use.
double h_upper(const SizingField& h, double hc, double radius) {
  return std::min(h.max_size(), hc + h.options().gradation * radius);
}

struct Tri {
  double p[3][3];
  double c[3];
  double hc;
  double lower;  ///< lower bound of its node count
};

Tri make_tri(const double* a, const double* b, const double* c, const SizingField& h, ResourceEstimate& e) {
  Tri t;
  for (int i = 0; i < 3; ++i) {
    t.p[0][i] = a[i], t.p[1][i] = b[i], t.p[2][i] = c[i];
    t.c[i] = (a[i] + b[i] + c[i]) / 3;
  }
  t.hc = h(t.c);
  ++e.samples;
  const double radius = std::sqrt(std::max({dist2(t.c, a), dist2(t.c, b), dist2(t.c, c)}));
  const double hu = h_upper(h, t.hc, radius);
  t.lower = triangle_area(a, b, c) / (kSurfaceDensity * hu * hu);
  return t;
}

/// Work shared by the threads of one integration: the contributions of the parts finished so
/// far (a lower bound of the total, for the cap) and whether a part stopped at the cap.
struct CapWatch {
  double cap;
  std::atomic<double> finished{0};
  std::atomic<bool> capped{false};
  /// Stops a part whose own finished sum and pending lower bounds, with the other finished
  /// parts', pass the cap: then the total passes it too.
  bool over(double done, double pending) {
    if (capped.load(std::memory_order_relaxed)) return true;
    if (finished.load(std::memory_order_relaxed) + done + pending <= cap) return false;
    capped.store(true, std::memory_order_relaxed);
    return true;
  }
};

/// Integral of 1 / (kSurfaceDensity h^2) over the surface: each facet is split in four while h,
/// sampled at its centroid and corners, varies by more than 15% and its longest edge exceeds
/// 2 h. Facets on all cores, summed in facet order (the same figures on any thread count).
/// Stops once finished parts and the lower bounds of pending ones pass `cap`.
void integrate_surface(const SurfaceMesh& m, const SizingField& h, ResourceEstimate& e, double cap) {
  const std::size_t nf = m.num_tris();
  std::vector<double> nodes(nf, 0.0);
  std::vector<std::uint64_t> samples(nf, 0);
  CapWatch watch{cap};
  parallel_for(nf, [&](std::size_t fb, std::size_t fe, unsigned) {
    std::vector<Tri> stack;
    ResourceEstimate local;
    PointValues corners;  // h at the facet's corners: each split's midpoints serve several triangles
    for (std::size_t f = fb; f < fe && !watch.capped.load(std::memory_order_relaxed); ++f) {
      local = {};
      corners.clear();
      stack.assign(1, make_tri(m.points.p(m.tri(f)[0]), m.points.p(m.tri(f)[1]), m.points.p(m.tri(f)[2]), h, local));
      double pending = stack.back().lower;
      while (!stack.empty()) {
        if (watch.over(local.surface_nodes, pending)) return;
        const Tri x = stack.back();
        stack.pop_back();
        pending -= x.lower;
        double hlo = x.hc, hhi = x.hc;
        for (const double* p : x.p) {
          const double hp = corners.at(p, [&](const double* x) { return h(x); }, local.samples);
          hlo = std::min(hlo, hp);
          hhi = std::max(hhi, hp);
        }
        const double longest2 =
            std::max({dist2(x.p[0], x.p[1]), dist2(x.p[1], x.p[2]), dist2(x.p[2], x.p[0])});
        if (hhi <= 1.15 * hlo || longest2 <= 4 * hlo * hlo) {
          local.surface_nodes += triangle_area(x.p[0], x.p[1], x.p[2]) / (kSurfaceDensity * x.hc * x.hc);
          continue;
        }
        double mid[3][3];
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < 3; ++i) mid[k][i] = 0.5 * (x.p[k][i] + x.p[(k + 1) % 3][i]);
        for (const Tri& y : {make_tri(x.p[0], mid[0], mid[2], h, local), make_tri(mid[0], x.p[1], mid[1], h, local),
                             make_tri(mid[2], mid[1], x.p[2], h, local), make_tri(mid[0], mid[1], mid[2], h, local)}) {
          stack.push_back(y);
          pending += y.lower;
        }
      }
      nodes[f] = local.surface_nodes;
      samples[f] = local.samples;
      watch.finished.fetch_add(local.surface_nodes, std::memory_order_relaxed);
    }
  }, 16);
  for (std::size_t f = 0; f < nf; ++f) e.surface_nodes += nodes[f], e.samples += samples[f];
  if (watch.capped || e.surface_nodes > cap) e.surface_nodes = cap, e.capped = true;
}

struct Cell {
  double c[3];
  double r;        ///< half edge
  double hc;       ///< h at the centre
  double sd;       ///< signed surface distance of the centre (> 0 inside)
  double lower;    ///< lower bound of its node count (0 unless wholly inside)
};

/// A cell centred at c with half edge r. `parent_sd` is a lower bound of the centre's |signed
/// distance| with its sign when the parent cell lay wholly on one side (then the child does
/// too, and the surface is not queried), NaN otherwise.
Cell make_cell(const double* c, double r, double parent_sd, const SurfaceQuery& q, const SizingField& h,
               ResourceEstimate& e) {
  Cell x{{c[0], c[1], c[2]}, r, h(x.c), parent_sd, 0};
  const double rho = r * std::sqrt(3.0);
  ++e.samples;
  if (std::isnan(parent_sd)) {
    // Only a cell the surface crosses needs its centre's distance. One farther from the
    // surface than its half diagonal rho lies wholly on one side, and every figure of it and
    // of its children is that of |sd| = rho (they test sd against +-rho and pass their
    // children sd -+ rho / 2, their own half diagonals; the fraction inside is 0 or 1). On
    // thin-walled parts most cells are near the surface: the distance queries were 0.3 of the
    // estimate's 1.2 CPU-s on occt_sh2.stl.
    const double d = q.within(x.c, rho) ? q.distance(x.c) : rho;
    x.sd = q.side(x.c) > 0 ? d : -d;
    e.samples += 2;
  }
  if (x.sd >= rho) {
    const double hu = h_upper(h, x.hc, rho);
    x.lower = 8 * r * r * r / (kVolumeDensity * hu * hu * hu);
  }
  return x;
}

/// Takes cell x of the octree: adds its share to `done` when it is final (or nothing when it
/// lies wholly outside), else appends its 8 children to `out`, their lower bounds to `pending`.
void take_cell(const Cell& x, const SurfaceQuery& q, const SizingField& h, ResourceEstimate& e,
               std::vector<Cell>& out, double& done, double& pending) {
  const double rho = x.r * std::sqrt(3.0);
  if (x.sd <= -rho) return;  // wholly outside
  // Bounds of h over the cell, from its centre: the cell lies in the ball of radius rho
  // around it, where h is at least the field with every zone's distance shortened by rho
  // (SizingField::lower_bound, given h(c): one query) and at most h(c) + g rho (h is
  // g-Lipschitz). The 8 corners sampled instead took 9 queries in all (the paper gear box's
  // estimate: 4.3-5.2 s, most of it these queries, on two cores; 2.7-2.8 s with two).
  const double hlo = std::min(x.hc, h.lower_bound(x.c, rho, x.hc));
  const double hhi = h_upper(h, x.hc, rho);
  ++e.samples;
  const bool crossed = x.sd < rho;
  const bool uniform = hhi <= 1.15 * hlo;
  if ((uniform && (!crossed || rho <= 4 * hlo)) || rho <= 1.5 * hlo) {
    const double fraction = std::clamp(0.5 + x.sd / (2 * x.r), 0.0, 1.0);
    done += fraction * 8 * x.r * x.r * x.r / (kVolumeDensity * x.hc * x.hc * x.hc);
    return;
  }
  const double r = 0.5 * x.r;
  // A child centre is rho / 2 from ours: a parent wholly on one side bounds the children's
  // signed distances by |sd| - rho / 2 >= their own half diagonal rho / 2.
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  const double child_sd = crossed ? unknown : x.sd > 0 ? x.sd - 0.5 * rho : x.sd + 0.5 * rho;
  for (int k = 0; k < 8; ++k) {
    const double c[3] = {x.c[0] + ((k & 1) ? r : -r), x.c[1] + ((k & 2) ? r : -r), x.c[2] + ((k & 4) ? r : -r)};
    out.push_back(make_cell(c, r, child_sd, q, h, e));
    pending += out.back().lower;
  }
}

/// Integral of 1 / (kVolumeDensity h^3) over the solid, on an adaptive octree of its bounding
/// cube. A cell is final when h, bounded from its centre (take_cell), varies by at most 15%
/// and the cell is wholly inside or outside (surface distance from the centre >= its half
/// diagonal) or no larger than 4 h, or when it is no larger than 1.5 h (half diagonals). A
/// final cell the surface crosses counts the fraction clamp(1/2 + sd / (2r)) of its volume,
/// sd the centre's signed distance (exact for a plane parallel to a cell face).
/// The top levels are taken breadth first until there are kParts cells; their subtrees then
/// run depth first on all cores, summed in the order of the cells (the same figures on any
/// thread count; one thread took 8 s of the paper gear box's 160). Stops like
/// integrate_surface once past `cap`.
void integrate_volume(const PreparedSurface& s, const SurfaceQuery& q, const SizingField& h,
                      ResourceEstimate& e, double cap) {
  constexpr std::size_t kParts = 512;
  double edge = 0, centre[3];
  for (int i = 0; i < 3; ++i) {
    edge = std::max(edge, s.bbox_max[i] - s.bbox_min[i]);
    centre[i] = 0.5 * (s.bbox_min[i] + s.bbox_max[i]);
  }
  if (!(edge > 0)) return;
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  std::vector<Cell> top{make_cell(centre, 0.5 * edge * 1.0001, unknown, q, h, e)};
  double done = 0, pending = top.back().lower;
  while (!top.empty() && top.size() < kParts) {
    if (done + pending > cap) {
      e.interior_nodes = cap, e.capped = true;
      return;
    }
    std::vector<Cell> next;
    pending = 0;
    for (const Cell& x : top) take_cell(x, q, h, e, next, done, pending);
    top.swap(next);
  }
  std::vector<double> part(top.size(), 0.0);
  std::vector<std::uint64_t> samples(top.size(), 0);
  CapWatch watch{cap};
  watch.finished = done;
  parallel_for(top.size(), [&](std::size_t b, std::size_t end, unsigned) {
    std::vector<Cell> stack;
    for (std::size_t i = b; i < end && !watch.capped.load(std::memory_order_relaxed); ++i) {
      ResourceEstimate local;
      double sum = 0, waiting = top[i].lower;
      stack.assign(1, top[i]);
      while (!stack.empty()) {
        if (watch.over(sum, waiting)) return;
        const Cell x = stack.back();
        stack.pop_back();
        waiting -= x.lower;
        take_cell(x, q, h, local, stack, sum, waiting);
      }
      part[i] = sum;
      samples[i] = local.samples;
      watch.finished.fetch_add(sum, std::memory_order_relaxed);
    }
  }, 1);
  double total = done;
  for (std::size_t i = 0; i < top.size(); ++i) total += part[i], e.samples += samples[i];
  if (watch.capped || total > cap) total = cap, e.capped = true;
  e.interior_nodes = total;
}

}  // namespace

ResourceEstimate estimate_resources(const Domain& domain, double node_cap) {
  const PreparedSurface& surface = domain.surface;
  const SurfaceQuery& query = domain.query;
  const SizingField& sizing = domain.sizing;
  ResourceEstimate e;
  integrate_surface(surface.mesh, sizing, e, node_cap);
  if (!e.capped) integrate_volume(surface, query, sizing, e, node_cap - e.surface_nodes);
  e.nodes = e.surface_nodes + e.interior_nodes;
  e.peak_bytes = kBaseBytes + kBytesPerNode * e.nodes + kBytesPerFacet * double(surface.mesh.num_tris());
  return e;
}

}  // namespace kdmesh
