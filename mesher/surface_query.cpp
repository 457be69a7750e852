// kdmesh — SurfaceQuery: CGAL AABB tree adapter (CGAL types stay in this file and mesher/ray_parity).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface_query.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "mesher/ray_parity.h"

namespace kdmesh {

namespace {
using K = ray_parity::K;
using Triangles = ray_parity::Triangles;
using Primitive = ray_parity::Primitive;
using Tree = ray_parity::Tree;
}  // namespace

/// Facet bounding boxes binned on a uniform grid: which facets a small box may touch, with
/// exact comparisons only (cell indices are a monotone function of a coordinate, so a facet
/// box and a query box that overlap share a cell).
class BoxGrid {
 public:
  void build(const Triangles& tris) {
    for (int k = 0; k < 3; ++k) lo_[k] = hi_[k] = tris[0].vertex(0)[k];
    boxes_.resize(tris.size());
    for (std::size_t f = 0; f < tris.size(); ++f) {
      std::array<double, 6>& b = boxes_[f];
      for (int k = 0; k < 3; ++k) {
        b[k] = std::min({tris[f].vertex(0)[k], tris[f].vertex(1)[k], tris[f].vertex(2)[k]});
        b[3 + k] = std::max({tris[f].vertex(0)[k], tris[f].vertex(1)[k], tris[f].vertex(2)[k]});
        lo_[k] = std::min(lo_[k], b[k]);
        hi_[k] = std::max(hi_[k], b[3 + k]);
      }
    }
    // About 4 cells per facet, cubic cells, at most 128 per axis.
    const double ext[3] = {hi_[0] - lo_[0], hi_[1] - lo_[1], hi_[2] - lo_[2]};
    const double vol = std::max(ext[0], 1e-300) * std::max(ext[1], 1e-300) * std::max(ext[2], 1e-300);
    const double cell = std::cbrt(vol / (4.0 * double(tris.size())));
    for (int k = 0; k < 3; ++k) {
      n_[k] = int(std::clamp(ext[k] / cell, 1.0, 128.0));
      inv_[k] = ext[k] > 0 ? double(n_[k]) / ext[k] : 0;
    }
    std::vector<std::uint32_t> count(std::size_t(n_[0]) * n_[1] * n_[2] + 1, 0);
    auto each_cell = [&](const double* b, auto&& f) {
      int a[3], z[3];
      for (int k = 0; k < 3; ++k) a[k] = index(k, b[k]), z[k] = index(k, b[3 + k]);
      for (int i = a[0]; i <= z[0]; ++i)
        for (int j = a[1]; j <= z[1]; ++j)
          for (int l = a[2]; l <= z[2]; ++l) f((std::size_t(l) * n_[1] + j) * n_[0] + i);
    };
    for (const auto& b : boxes_) each_cell(b.data(), [&](std::size_t c) { ++count[c + 1]; });
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    start_ = count;
    items_.resize(count.back());
    for (std::uint32_t f = 0; f < boxes_.size(); ++f)
      each_cell(boxes_[f].data(), [&](std::size_t c) { items_[count[c]++] = f; });
  }
  /// False when no facet's (closed) box meets the closed box [a, b] (per axis a <= b).
  bool may_touch(const double* a, const double* b) const {
    int ia[3], ib[3];
    for (int k = 0; k < 3; ++k) {
      if (b[k] < lo_[k] || a[k] > hi_[k]) return false;
      ia[k] = index(k, a[k]), ib[k] = index(k, b[k]);
    }
    for (int i = ia[0]; i <= ib[0]; ++i)
      for (int j = ia[1]; j <= ib[1]; ++j)
        for (int l = ia[2]; l <= ib[2]; ++l) {
          const std::size_t c = (std::size_t(l) * n_[1] + j) * n_[0] + i;
          for (std::uint32_t x = start_[c]; x < start_[c + 1]; ++x) {
            const std::array<double, 6>& f = boxes_[items_[x]];
            if (f[0] <= b[0] && a[0] <= f[3] && f[1] <= b[1] && a[1] <= f[4] && f[2] <= b[2] &&
                a[2] <= f[5])
              return true;
          }
        }
    return false;
  }

 private:
  int index(int k, double x) const {
    return std::clamp(int(std::floor((x - lo_[k]) * inv_[k])), 0, n_[k] - 1);
  }
  double lo_[3], hi_[3], inv_[3];
  int n_[3];
  std::vector<std::array<double, 6>> boxes_;
  std::vector<std::uint32_t> start_, items_;
};

struct SurfaceQuery::Impl {
  Triangles triangles;
  Tree tree;
  BoxGrid boxes;
  double magnitude = 0;  // largest |coordinate| of the surface
};

SurfaceQuery::SurfaceQuery(const SurfaceMesh& surface) : impl_(std::make_unique<Impl>()) {
  if (surface.num_tris() == 0) throw GeometryError("surface query: the surface has no facets");
  auto P = [&](std::uint32_t v) {
    const double* p = surface.points.p(v);
    return K::Point_3(p[0], p[1], p[2]);
  };
  impl_->triangles.reserve(surface.num_tris());
  for (std::size_t f = 0; f < surface.num_tris(); ++f) {
    const std::uint32_t* t = surface.tri(f);
    impl_->triangles.emplace_back(P(t[0]), P(t[1]), P(t[2]));
  }
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
  impl_->boxes.build(impl_->triangles);
  for (const double x : surface.points.xyz) impl_->magnitude = std::max(impl_->magnitude, std::fabs(x));
}

SurfaceQuery::~SurfaceQuery() = default;

int SurfaceQuery::side(const double* p) const {
  // Parity of a segment's crossings, exact at any magnitude: mesher/ray_parity.h.
  return ray_parity::side(impl_->tree, p);
}

double SurfaceQuery::closest(const double* p, double* out, std::uint32_t* facet) const {
  const K::Point_3 q(p[0], p[1], p[2]);
  const auto [c, id] = impl_->tree.closest_point_and_primitive(q);
  out[0] = c.x();
  out[1] = c.y();
  out[2] = c.z();
  if (facet) *facet = std::uint32_t(id - impl_->triangles.cbegin());
  return std::sqrt(CGAL::squared_distance(q, c));
}

bool SurfaceQuery::box_may_touch(const double* a, const double* b) const {
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = std::min(a[k], b[k]), hi[k] = std::max(a[k], b[k]);
  return impl_->boxes.may_touch(lo, hi);
}

double SurfaceQuery::ray_distance(const double* origin, const double* dir, std::uint32_t skip,
                                  std::uint32_t* hit_facet) const {
  if (hit_facet) *hit_facet = kNoFacet;
  const K::Point_3 o(origin[0], origin[1], origin[2]);
  // The ray stores o + d, and CGAL's ray-triangle code rebuilds the direction at a facet
  // vertex a as a + ((o + d) - o): each sum is rounded to ulp(|x|) = 2^(e-52) of the
  // coordinates, so a direction of fixed length (the callers' unit normals) loses all its bits
  // from |x| = 2^53 (a degenerate ray: CGAL assertion) and is bent well before. Scaled by a
  // power of two (exact, undone on t below) to at least the coordinates' magnitude, d keeps
  // its direction to a relative 2^-52 at every scale.
  const double dmax = std::max({std::fabs(dir[0]), std::fabs(dir[1]), std::fabs(dir[2])});
  if (!(dmax > 0) || !std::isfinite(dmax)) return std::numeric_limits<double>::infinity();
  const double reach = std::max({impl_->magnitude, std::fabs(origin[0]), std::fabs(origin[1]), std::fabs(origin[2])});
  const int shift = reach > 0 ? std::ilogb(reach) + 1 - std::ilogb(dmax) : 0;
  const K::Vector_3 d(std::ldexp(dir[0], shift), std::ldexp(dir[1], shift), std::ldexp(dir[2], shift));
  const double dd = d.squared_length();
  if (!(dd > 0) || !std::isfinite(dd)) return std::numeric_limits<double>::infinity();
  const auto begin = impl_->triangles.cbegin();
  const auto hit = impl_->tree.first_intersection(
      K::Ray_3(o, d), [&](const Primitive::Id& id) { return std::uint32_t(id - begin) == skip; });
  if (!hit) return std::numeric_limits<double>::infinity();
  double t = std::numeric_limits<double>::infinity();
  if (hit_facet) *hit_facet = std::uint32_t(hit->second - begin);
  if (const K::Point_3* p = boost::get<K::Point_3>(&hit->first)) {
    t = std::sqrt(CGAL::squared_distance(o, *p) / dd);
  } else if (const K::Segment_3* sgm = boost::get<K::Segment_3>(&hit->first)) {
    t = std::sqrt(std::min(CGAL::squared_distance(o, sgm->source()), CGAL::squared_distance(o, sgm->target())) / dd);
  }
  return std::ldexp(t, shift);  // in units of |dir|
}

double SurfaceQuery::distance(const double* p) const {
  const K::Point_3 q(p[0], p[1], p[2]);
  return std::sqrt(impl_->tree.squared_distance(q));
}

}  // namespace kdmesh
