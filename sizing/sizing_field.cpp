// kdmesh — the sizing field h(x): validation of the zones, and fast evaluation
// (one BVH over every segment-like zone piece, plus closed-form boxes, balls and plane sections).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/sizing_field.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <sstream>

#include "core/error.h"
#include "sizing/curvature_sizes.h"
#include "sizing/features.h"
#include "sizing/plane_section.h"
#include "sizing/segment_bvh.h"
#include "sizing/segment_cells.h"

namespace kdmesh {
namespace {

const char* kind_name(SizingZone::Kind k) {
  switch (k) {
    case SizingZone::Kind::sharp_edges: return "sharp_edges";
    case SizingZone::Kind::polyline: return "polyline";
    case SizingZone::Kind::segment: return "segment";
    case SizingZone::Kind::plane: return "plane";
    case SizingZone::Kind::point: return "point";
    case SizingZone::Kind::box: return "box";
    case SizingZone::Kind::ball: return "ball";
  }
  return "unknown";
}

[[noreturn]] void zone_error(std::size_t i, const SizingZone& z, const std::string& msg) {
  std::ostringstream os;
  os << "sizing zone " << i << " '" << z.name << "' (" << kind_name(z.kind) << "): " << msg;
  throw UsageError(os.str());
}

struct PlaneZone {
  double origin[3], normal[3], u[3], v[3];
  double size;
  SectionLocator locator;
};

struct BoxZone {
  double lo[3], hi[3];
  double size;
};

struct BallZone {
  double c[3];
  double r;
  double size;
};

}  // namespace

struct SizingField::Impl {
  SizingOptions options;  // min_size resolved (never 0)
  double g = 0;
  double h_min = 0, h_max = 0;
  SegmentBvh segments;  // sharp edges, polylines, segments, points, plane-section boundaries
  std::vector<PlaneZone> planes;
  std::vector<BoxZone> boxes;
  std::vector<BallZone> balls;
  SizingAutoStats auto_stats;

  /// h at x (reach 0), or a lower bound of h over the ball of radius reach around x: every
  /// term is size + g * distance, and a point within reach of x is at most reach closer.
  double eval(const double* x, double reach = 0, double start = HUGE_VAL) const {
    const double best = segments.min_value(x, g, others(x, reach, start), reach);
    return std::max(h_min, std::min(h_max, best));
  }

  /// The least of h_max, `start` and the boxes', balls' and plane sections' terms (at x, or
  /// over the ball of radius reach): eval's value before the segments.
  double others(const double* x, double reach, double start) const {
    double best = std::min(h_max, start);
    for (const BoxZone& b : boxes) {
      if (!(b.size < best)) continue;
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double e = std::max({b.lo[k] - x[k], 0.0, x[k] - b.hi[k]});
        d2 += e * e;
      }
      best = std::min(best, b.size + g * std::max(0.0, std::sqrt(d2) - reach));
    }
    for (const BallZone& b : balls) {
      if (!(b.size < best)) continue;
      const double dx = x[0] - b.c[0], dy = x[1] - b.c[1], dz = x[2] - b.c[2];
      const double d = std::max(0.0, std::sqrt(dx * dx + dy * dy + dz * dz) - b.r - reach);
      best = std::min(best, b.size + g * d);
    }
    // Plane sections: the interior term only (size + g|dz| when x projects into the region);
    // outside, the distance is to the boundary curve, whose segments are in the BVH. A lower
    // bound over a ball takes the term wherever the plane is in reach (the ball may reach
    // the region even when x does not project into it).
    for (const PlaneZone& p : planes) {
      const double r[3] = {x[0] - p.origin[0], x[1] - p.origin[1], x[2] - p.origin[2]};
      const double dz = r[0] * p.normal[0] + r[1] * p.normal[1] + r[2] * p.normal[2];
      const double value = p.size + g * std::max(0.0, std::fabs(dz) - reach);
      if (!(value < best)) continue;
      const double pu = r[0] * p.u[0] + r[1] * p.u[1] + r[2] * p.u[2];
      const double pv = r[0] * p.v[0] + r[1] * p.v[1] + r[2] * p.v[2];
      if (reach > 0 || p.locator.contains(pu, pv)) best = value;
    }
    return best;
  }

  /// Cells over the surface's box where h is h_max throughout, found on first use: a lower
  /// bound of h over the cell's ball (eval with a reach) that is h_max proves it, and h at a
  /// point of such a cell is then h_max exactly, as eval would compute it, at the cost of a
  /// table lookup. Away from zones most evaluations fall there (pinion.ply at one size: 98% of
  /// its edges' midpoints). One byte per cell, at most ~128^3 cells: 0 not yet known, 1 h_max
  /// throughout, 2 not, 3 not and h at its centre known. Written by whichever thread first
  /// asks (the same value by any).
  /// In a cell that is not clear, the segments' term comes from the cell's candidate lists
  /// (SegmentCells, the same value as the BVH's search). Where the cell has none (its first 64
  /// queries, or their memory spent), h(centre) + g |x - centre| bounds h(x) from above (h is
  /// g-Lipschitz), and the BVH's search starts from it rather than from h_max: it prunes at
  /// once what cannot come below it. The search's minimum is the same (the bound is above it,
  /// with a margin far above the rounding of either).
  struct ClearCells {
    double lo[3] = {0, 0, 0}, inv = 0, radius = 0;
    int n[3] = {0, 0, 0};
    std::unique_ptr<std::uint8_t[]> state;
    std::unique_ptr<double[]> centre_h;  // h at the centre of a cell whose state is 3
  };
  mutable ClearCells clear;
  std::unique_ptr<SegmentCells> lists;  // over the clear cells' grid, when there are segments

  void init_clear_cells(const PointSet& points) {
    if (points.size() == 0 || !(h_min < h_max)) return;
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = points.p(0)[k];
    for (std::uint32_t i = 1; i < points.size(); ++i)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], points.p(i)[k]), hi[k] = std::max(hi[k], points.p(i)[k]);
    double extent = 0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, hi[k] - lo[k]);
    if (!std::isfinite(extent)) return;
    const double cell = std::max(h_max, extent / 128);
    if (!(cell > 0)) return;
    for (int k = 0; k < 3; ++k) {
      clear.lo[k] = lo[k];
      clear.n[k] = int(std::floor((hi[k] - lo[k]) / cell)) + 1;
    }
    clear.inv = 1 / cell;
    clear.radius = 0.5 * std::sqrt(3.0) * cell;
    clear.state.reset(new std::uint8_t[std::size_t(clear.n[0]) * clear.n[1] * clear.n[2]]());
    clear.centre_h.reset(new double[std::size_t(clear.n[0]) * clear.n[1] * clear.n[2]]);
    if (segments.size() > 0 && options.list_memory > 0) {
      // The lists' balls get value()'s margin for its largest scale (a centre's and lo's
      // coordinates' magnitudes, the centres lying within a cell of the box).
      double scale = 0;
      for (int k = 0; k < 3; ++k)
        scale += std::fabs(lo[k]) + std::max(std::fabs(lo[k]), std::fabs(hi[k]) + cell);
      lists = std::make_unique<SegmentCells>(&segments, g, h_max, cell, clear.n, 1e-12 * scale,
                                             options.list_memory);
    }
  }

  /// The centre's coordinate on axis k of the cells of index f there. Every caller computes it
  /// here: a cell's state is found from its centre, so all must get the same bits.
  double centre_at(int k, double f) const { return clear.lo[k] + (f + 0.5) / clear.inv; }
  /// The magnitude of the coordinates a cell's figures are rounded at (its centre's, lo's).
  double cell_scale(const double* centre) const {
    return std::fabs(centre[0]) + std::fabs(centre[1]) + std::fabs(centre[2]) + std::fabs(clear.lo[0]) +
           std::fabs(clear.lo[1]) + std::fabs(clear.lo[2]);
  }
  /// Cell c's state where it is not known yet: 1 (clear) or 2, stored.
  std::uint8_t find_state(std::size_t c, const double* centre) const {
    // The ball around the centre holds the cell (and x, whatever the rounding of its cell
    // index: the margins are far above it).
    const double reach = clear.radius * (1 + 1e-6) + 1e-12 * cell_scale(centre);
    const std::uint8_t known = eval(centre, reach) < h_max ? 2 : 1;
    std::atomic_ref<std::uint8_t>(clear.state[c]).store(known, std::memory_order_relaxed);
    return known;
  }

  /// True when the cells that the box around the ball (x, r) meets, at most four per axis (the
  /// estimate's balls span up to 4 h), are all clear. Every zone's term is then at least h_max
  /// over each cell's ball (by the clear test's margin of 1e-6 of the radius, far above the
  /// rounding of a term), and the balls hold the ball (x, r): they reach 0.37 of a cell past
  /// their cells' faces, far beyond the rounding of a cell index. So eval(x, r) is h_max
  /// exactly, without the search.
  bool ball_clear(const double* x, double r) const {
    if (!clear.state) return false;
    std::size_t first[3];
    int span[3];
    for (int k = 0; k < 3; ++k) {
      const double a = std::floor((x[k] - r - clear.lo[k]) * clear.inv);
      const double b = std::floor((x[k] + r - clear.lo[k]) * clear.inv);
      if (!(a >= 0 && b < clear.n[k] && b - a <= 3)) return false;  // off the box, large, or NaN
      first[k] = std::size_t(a);
      span[k] = int(b - a);
    }
    for (int i = 0; i <= span[2]; ++i)
      for (int j = 0; j <= span[1]; ++j)
        for (int l = 0; l <= span[0]; ++l) {
          const std::size_t f[3] = {first[0] + std::size_t(l), first[1] + std::size_t(j),
                                    first[2] + std::size_t(i)};
          const std::size_t c = (f[2] * std::size_t(clear.n[1]) + f[1]) * std::size_t(clear.n[0]) + f[0];
          std::uint8_t known = std::atomic_ref<std::uint8_t>(clear.state[c]).load(std::memory_order_acquire);
          if (known == 0) {
            double centre[3];
            for (int k = 0; k < 3; ++k) centre[k] = centre_at(k, double(f[k]));
            known = find_state(c, centre);
          }
          if (known != 1) return false;
        }
    return true;
  }

  double value(const double* x) const {
    if (!clear.state) return eval(x);
    std::size_t c = 0;
    double centre[3];
    for (int k = 2; k >= 0; --k) {
      const double f = std::floor((x[k] - clear.lo[k]) * clear.inv);
      if (!(f >= 0 && f < clear.n[k])) return eval(x);  // off the box (or NaN)
      c = c * std::size_t(clear.n[k]) + std::size_t(f);
      centre[k] = centre_at(k, f);
    }
    std::atomic_ref<std::uint8_t> st(clear.state[c]);
    std::uint8_t known = st.load(std::memory_order_acquire);
    if (known == 1) return h_max;  // (most evaluations away from zones)
    const double scale = cell_scale(centre);
    if (known == 0) known = find_state(c, centre);
    if (known == 1) return h_max;
    double best = others(x, 0, HUGE_VAL);  // h_max and every zone's term but the segments'
    if (lists && lists->min_value(c, centre, x, best)) return std::max(h_min, std::min(h_max, best));
    // (A thread that sees 3 sees the centre's value stored before it; several threads may
    // store it, all the same value.)
    std::atomic_ref<double> ch(clear.centre_h[c]);
    double hc;
    if (known == 2) {
      hc = eval(centre);
      ch.store(hc, std::memory_order_relaxed);
      st.store(3, std::memory_order_release);
    } else {
      hc = ch.load(std::memory_order_relaxed);
    }
    const double dx = x[0] - centre[0], dy = x[1] - centre[1], dz = x[2] - centre[2];
    const double ub = (hc + g * std::sqrt(dx * dx + dy * dy + dz * dz)) * (1 + 1e-12) + 1e-12 * g * scale;
    // (eval(x, 0, ub) without the other zones again: their least is the same from any start)
    return std::max(h_min, std::min(h_max, segments.min_value(x, g, std::min(best, ub))));
  }
};

namespace {
[[noreturn]] void empty_field() {
  throw UsageError("sizing: the SizingField is empty (default-constructed; use build_sizing_field)");
}
}  // namespace

double SizingField::operator()(const double* x) const {
  if (!impl_) empty_field();
  return impl_->value(x);
}
double SizingField::lower_bound(const double* x, double radius) const {
  if (!impl_) empty_field();
  // At radius 0, h(x) by the zones' own search, without the cells' tables and lists: the
  // value operator() finds through them, bit for bit (the tests compare the two). Otherwise
  // h(x) as operator() finds it, at a fraction of the search's cost.
  if (!(radius > 0)) return impl_->eval(x);
  return lower_bound(x, radius, impl_->value(x));
}
double SizingField::lower_bound(const double* x, double radius, double h_at_x) const {
  if (!impl_) empty_field();
  if (!(radius > 0)) return h_at_x;
  // Away from every zone: eval(x, radius) is h_max (ball_clear), found from the cells' table.
  if (impl_->ball_clear(x, radius)) return std::max(impl_->h_max, h_at_x - impl_->g * radius);
  // Both are lower bounds: the terms with shortened distances, and h(x) - g r (h is
  // g-Lipschitz). The first is the tighter far from zones, the second beside a plane zone,
  // whose in-region term the first takes wherever the plane is in reach.
  return std::max(impl_->eval(x, radius), h_at_x - impl_->g * radius);
}
double SizingField::max_size() const {
  if (!impl_) empty_field();
  return impl_->h_max;
}
double SizingField::min_size() const {
  if (!impl_) empty_field();
  return impl_->h_min;
}
const SizingOptions& SizingField::options() const {
  if (!impl_) empty_field();
  return impl_->options;
}
const SizingAutoStats& SizingField::auto_stats() const {
  if (!impl_) empty_field();
  return impl_->auto_stats;
}

namespace {
/// The options' own numbers (the zones are checked as they are built): UsageError naming the
/// option.
void check_options(const SizingOptions& options) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!(options.max_size > 0) || !finite(options.max_size))
    throw UsageError("sizing: max_size must be finite and > 0 (got " +
                     std::to_string(options.max_size) + ")");
  if (!(options.min_size >= 0) || !finite(options.min_size))
    throw UsageError("sizing: min_size must be finite and >= 0 (got " +
                     std::to_string(options.min_size) + ")");
  if (options.min_size > options.max_size)
    throw UsageError("sizing: min_size " + std::to_string(options.min_size) +
                     " is larger than max_size " + std::to_string(options.max_size));
  if (!(options.gradation > 0) || !finite(options.gradation))
    throw UsageError("sizing: gradation must be finite and > 0 (got " +
                     std::to_string(options.gradation) + ")");
  if (!(options.curvature_angle_deg >= 0 && options.curvature_angle_deg < 180))
    throw UsageError("sizing: curvature_angle_deg must be in [0, 180) degrees (got " +
                     std::to_string(options.curvature_angle_deg) + ")");
  if (!(options.chordal_deviation >= 0) || !finite(options.chordal_deviation))
    throw UsageError("sizing: chordal_deviation must be finite and >= 0 (got " +
                     std::to_string(options.chordal_deviation) + ")");
  if (!(options.feature_angle_deg >= 0 && options.feature_angle_deg < 180))
    throw UsageError("sizing: feature_angle_deg must be in [0, 180) degrees (got " +
                     std::to_string(options.feature_angle_deg) + ")");
}
}  // namespace

SizingField build_sizing_field(const SurfaceMesh& surface, const SizingOptions& options) {
  check_options(options);
  auto finite = [](double v) { return std::isfinite(v); };

  auto impl = std::make_shared<SizingField::Impl>();
  impl->options = options;
  if (impl->options.min_size == 0) impl->options.min_size = options.max_size / 1000;
  impl->g = options.gradation;
  impl->h_max = options.max_size;
  impl->h_min = impl->options.min_size;

  bool surface_checked = false;
  auto check_surface = [&](std::size_t i, const SizingZone& z) {
    if (surface_checked) return;
    const std::size_t bad = first_non_finite(surface.points);
    if (bad != surface.points.size())
      zone_error(i, z, "surface point " + std::to_string(bad) + " has a non-finite coordinate");
    surface_checked = true;
  };

  WeightedSegments segs;
  for (std::size_t i = 0; i < options.zones.size(); ++i) {
    const SizingZone& z = options.zones[i];
    const std::vector<double>& c = z.coords;
    if (!(z.size > 0) || !finite(z.size))
      zone_error(i, z, "size must be finite and > 0 (got " + std::to_string(z.size) + ")");
    for (std::size_t k = 0; k < c.size(); ++k)
      if (!finite(c[k])) zone_error(i, z, "coordinate " + std::to_string(k) + " is not finite");
    auto need = [&](std::size_t n, const char* what) {
      if (c.size() != n)
        zone_error(i, z, "expects " + std::to_string(n) + " coordinates (" + what + "), got " +
                             std::to_string(c.size()));
    };
    switch (z.kind) {
      case SizingZone::Kind::sharp_edges: {
        if (!c.empty()) zone_error(i, z, "takes no coordinates");
        if (!(z.angle_deg > 0 && z.angle_deg < 180))
          zone_error(i, z, "angle_deg must be in (0, 180) (got " + std::to_string(z.angle_deg) + ")");
        check_surface(i, z);
        const FeatureEdges fe = detect_sharp_edges(surface, z.angle_deg);
        for (std::size_t e = 0; e < fe.num_edges(); ++e)
          segs.push_back(surface.points.p(fe.edges[2 * e]), surface.points.p(fe.edges[2 * e + 1]),
                         z.size);
        break;
      }
      case SizingZone::Kind::polyline: {
        if (c.size() < 6 || c.size() % 3 != 0)
          zone_error(i, z, "expects 3*k coordinates with k >= 2 vertices, got " +
                               std::to_string(c.size()));
        for (std::size_t k = 0; k + 1 < c.size() / 3; ++k) {
          const double* a = c.data() + 3 * k;
          const double* b = a + 3;
          if (a[0] == b[0] && a[1] == b[1] && a[2] == b[2])
            zone_error(i, z, "piece " + std::to_string(k) + " (vertices " + std::to_string(k) +
                                 " and " + std::to_string(k + 1) + ") has zero length");
          segs.push_back(a, b, z.size);
        }
        break;
      }
      case SizingZone::Kind::segment: {
        need(6, "two end points");
        if (c[0] == c[3] && c[1] == c[4] && c[2] == c[5])
          zone_error(i, z, "the segment has zero length");
        segs.push_back(c.data(), c.data() + 3, z.size);
        break;
      }
      case SizingZone::Kind::point: {
        need(3, "a point");
        segs.push_back(c.data(), c.data(), z.size);
        break;
      }
      case SizingZone::Kind::plane: {
        need(6, "origin and normal");
        const double* n = c.data() + 3;
        const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (!(nn > 0) || !finite(nn)) zone_error(i, z, "the normal is zero (or overflows)");
        check_surface(i, z);
        const PlaneSection sec = cut_with_plane(surface, c.data(), n);
        if (sec.empty()) zone_error(i, z, "the plane misses the solid (no surface facet crosses it)");
        PlaneZone p;
        for (int k = 0; k < 3; ++k) {
          p.origin[k] = sec.origin[k];
          p.normal[k] = sec.normal[k];
          p.u[k] = sec.u[k];
          p.v[k] = sec.v[k];
        }
        p.size = z.size;
        p.locator = SectionLocator(sec);
        impl->planes.push_back(std::move(p));
        for (std::size_t s = 0; s < sec.num_segments(); ++s)
          segs.push_back(sec.xyz.data() + 3 * std::size_t(sec.segs[2 * s]),
                         sec.xyz.data() + 3 * std::size_t(sec.segs[2 * s + 1]), z.size);
        break;
      }
      case SizingZone::Kind::box: {
        need(6, "min and max corners");
        BoxZone b;
        for (int k = 0; k < 3; ++k) {
          b.lo[k] = c[k];
          b.hi[k] = c[3 + k];
          if (b.lo[k] > b.hi[k])
            zone_error(i, z, std::string("min ") + "xyz"[k] + " = " + std::to_string(b.lo[k]) +
                                 " is larger than max " + "xyz"[k] + " = " + std::to_string(b.hi[k]));
        }
        b.size = z.size;
        impl->boxes.push_back(b);
        break;
      }
      case SizingZone::Kind::ball: {
        need(4, "center and radius");
        if (!(c[3] > 0)) zone_error(i, z, "radius must be > 0 (got " + std::to_string(c[3]) + ")");
        impl->balls.push_back({{c[0], c[1], c[2]}, c[3], z.size});
        break;
      }
      default:
        zone_error(i, z, "unknown zone kind " + std::to_string(int(z.kind)));
    }
  }
  for (std::size_t k = 0; k < options.derived.size(); ++k) {
    const double w = options.derived.weight[k];
    const double* ab = options.derived.ab.data() + 6 * k;
    if (!(w > 0) || !finite(w) || !std::all_of(ab, ab + 6, finite))
      throw UsageError("sizing: derived segment " + std::to_string(k) + " has a non-finite or non-positive value");
    segs.push_back(ab, ab + 3, std::max(w, impl->h_min));
  }
  if (options.curvature_angle_deg > 0 || options.chordal_deviation > 0) {
    if (const std::size_t bad = first_non_finite(surface.points); bad != surface.points.size())
      throw UsageError("sizing: surface point " + std::to_string(bad) + " has a non-finite coordinate");
    add_curvature_sizes(surface, impl->options, impl->h_min, segs, impl->auto_stats);
  }
  impl->segments = SegmentBvh(segs);
  impl->init_clear_cells(surface.points);
  return SizingField(impl);
}

}  // namespace kdmesh
