// kdmesh — CGAL 5.5 as a reference: Delaunay_triangulation_3 and convex_hull_3 (Epick).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <numeric>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/Unique_hash_map.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>

#include "core/error.h"
#include "core/timer.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"

namespace kdmesh {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, K>;
using Cb = CGAL::Delaunay_triangulation_cell_base_3<K>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;  // sequential
using Dt = CGAL::Delaunay_triangulation_3<K, Tds>;

// ---- counting instantiation (CgalOptions::count only) ----
// Counters of the running counted triangulation (one at a time per thread).
struct Counts {
  std::uint64_t orient = 0, sphere = 0, removed_cells = 0;
};
thread_local Counts tl_counts;

/// Epick with counting Orientation_3 and Side_of_oriented_sphere_3: each call increments a
/// counter, then calls Epick's (statically filtered, exact) predicate. Every other type and
/// functor is Epick's. Triangulation_structural_filtering_traits is not specialised for this
/// class, so Triangulation_3::locate walks with these exact tests only (no inexact pre-walk).
struct CountingK : K {
  struct Orientation_3 {
    using result_type = K::Orientation_3::result_type;
    K::Orientation_3 base = K().orientation_3_object();
    template <class... Args>
    result_type operator()(const Args&... args) const {
      ++tl_counts.orient;
      return base(args...);
    }
  };
  struct Side_of_oriented_sphere_3 {
    using result_type = K::Side_of_oriented_sphere_3::result_type;
    K::Side_of_oriented_sphere_3 base = K().side_of_oriented_sphere_3_object();
    template <class... Args>
    result_type operator()(const Args&... args) const {
      ++tl_counts.sphere;
      return base(args...);
    }
  };
  Orientation_3 orientation_3_object() const { return {}; }
  Side_of_oriented_sphere_3 side_of_oriented_sphere_3_object() const { return {}; }
};

/// A Delaunay cell that counts its destructions: the triangulation removes exactly the cells in
/// conflict with each inserted point (Compact_container::erase destroys them).
template <class Gt, class Cb = CGAL::Delaunay_triangulation_cell_base_3<Gt>>
class CountingCell : public Cb {
 public:
  template <class Tds2>
  struct Rebind_TDS {
    using Cb2 = typename Cb::template Rebind_TDS<Tds2>::Other;
    using Other = CountingCell<Gt, Cb2>;
  };
  using Cb::Cb;
  CountingCell() = default;
  CountingCell(const CountingCell&) = default;
  CountingCell& operator=(const CountingCell&) = default;
  ~CountingCell() { ++tl_counts.removed_cells; }
};

using CountingVb = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, CountingK>;
using CountingTds = CGAL::Triangulation_data_structure_3<CountingVb, CountingCell<CountingK>>;
using CountingDt = CGAL::Delaunay_triangulation_3<CountingK, CountingTds>;

Point cgal_point(const PointSet& points, std::uint32_t i) {
  const double* p = points.p(i);
  return Point(p[0], p[1], p[2]);
}

void check_finite(const PointSet& points) {
  const std::size_t i = first_non_finite(points);
  if (i < points.size()) throw GeometryError("point " + std::to_string(i) + " has a non-finite coordinate");
}

/// Throws UsageError unless `order` is a permutation of the n point ids whose hints are
/// kNoHint or points inserted earlier.
void check_order(const Ordering& order, std::size_t n) {
  if (order.order.size() != n || order.hint.size() != n) {
    throw UsageError("CGAL: ordering '" + order.name + "' has " +
                     std::to_string(order.order.size()) + " ids and " +
                     std::to_string(order.hint.size()) + " hints for " + std::to_string(n) +
                     " points");
  }
  std::vector<bool> inserted(n, false);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t p = order.order[k], h = order.hint[k];
    if (p >= n || inserted[p]) {
      throw UsageError("CGAL: ordering '" + order.name + "' is not a permutation (rank " +
                       std::to_string(k) + ", id " + std::to_string(p) + ")");
    }
    if (h != kNoHint && (h >= n || !inserted[h])) {
      throw UsageError("CGAL: ordering '" + order.name + "': hint " + std::to_string(h) +
                       " of rank " + std::to_string(k) + " is not an earlier-inserted point");
    }
    inserted[p] = true;
  }
}

}  // namespace

namespace {

/// Inserts p into dt located from `start` (null: from the infinite cell), as dt.insert(p, start)
/// does. The counted triangulation does it in two steps to attribute the orientation tests.
template <class T>
typename T::Vertex_handle insert_one(T& dt, const typename T::Point& p,
                                     typename T::Cell_handle start, ReferenceResult& counts) {
  if constexpr (std::is_same_v<T, CountingDt>) {
    typename T::Locate_type lt;
    int li, lj;
    const std::uint64_t before = tl_counts.orient;
    const typename T::Cell_handle c = dt.locate(p, lt, li, lj, start);
    counts.locate_orient_tests += tl_counts.orient - before;
    return dt.insert(p, lt, c, li, lj);
  } else {
    (void)counts;
    return dt.insert(p, start);
  }
}

/// The whole adapter, for the plain (Dt) or the counting (CountingDt) instantiation.
template <class T>
ReferenceResult cgal_run(const PointSet& points, const Ordering* order) {
  using P = typename T::Point;
  const std::size_t n = points.size();
  const std::vector<std::uint32_t> canon = canonical_point_ids(points);
  constexpr bool counting = std::is_same_v<T, CountingDt>;

  T dt;
  ReferenceResult result;
  tl_counts = {};
  if (!order && !counting) {
    // CGAL's range insertion: spatial sort, then insertion along it. A duplicate keeps the
    // info of whichever copy CGAL inserted first; canonical ids make that irrelevant.
    std::vector<std::pair<P, std::uint32_t>> input;
    input.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) input.emplace_back(cgal_point(points, i), i);
    Stopwatch clock;
    dt.insert(input.begin(), input.end());
    result.seconds = clock.seconds();
  } else if (!order) {
    // The range insertion, counted: CGAL 5.5's sequential insert_with_info spelled out (same
    // spatial_sort call on the same traits' comparisons, each point located from the cell of
    // the previously inserted vertex, the first from the infinite cell).
    std::vector<P> pts;
    pts.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) pts.push_back(cgal_point(points, i));
    std::vector<std::size_t> indices(n);
    for (std::size_t i = 0; i < n; ++i) indices[i] = i;
    using Pmap = typename CGAL::Pointer_property_map<P>::type;
    using SortTraits = CGAL::Spatial_sort_traits_adapter_3<typename T::Geom_traits, Pmap>;
    Stopwatch clock;
    CGAL::spatial_sort<CGAL::Sequential_tag>(indices.begin(), indices.end(),
                                             SortTraits(CGAL::make_property_map(pts), dt.geom_traits()));
    typename T::Vertex_handle hint;
    for (const std::size_t i : indices) {
      const typename T::Cell_handle start =
          hint == typename T::Vertex_handle() ? dt.infinite_cell() : hint->cell();
      hint = insert_one(dt, pts[i], start, result);
      if (hint != typename T::Vertex_handle()) hint->info() = std::uint32_t(i);
    }
    result.seconds = clock.seconds();
  } else {
    // One point at a time, located from (a cell of) the vertex of its hint. Inserting an
    // existing point returns its vertex: that handle then serves as the duplicate's vertex.
    std::vector<P> pts;
    pts.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) pts.push_back(cgal_point(points, i));
    std::vector<typename T::Vertex_handle> vertex_of(n);
    Stopwatch clock;
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t p = order->order[k], h = order->hint[k];
      typename T::Cell_handle start;
      if (h != kNoHint && dt.dimension() == 3) start = vertex_of[h]->cell();
      const std::size_t before = dt.number_of_vertices();
      const typename T::Vertex_handle v = insert_one(dt, pts[p], start, result);
      if (dt.number_of_vertices() != before) v->info() = p;
      vertex_of[p] = v;
    }
    result.seconds = clock.seconds();
  }
  if constexpr (counting) {
    // Read before dt is destroyed: its remaining cells are not conflicts.
    result.counted = true;
    result.orient_tests = tl_counts.orient;
    result.sphere_tests = tl_counts.sphere;
    result.conflicts = tl_counts.removed_cells;
  }

  if (dt.dimension() < 3) {
    throw GeometryError("CGAL: all points are coplanar (triangulation of dimension " +
                        std::to_string(dt.dimension()) + "): no tetrahedralization");
  }
  // CGAL's cells are positively oriented: CGAL::orientation(v0, v1, v2, v3) == POSITIVE, the
  // sign of det[v1-v0, v2-v0, v3-v0] (POSITIVE on (0, e1, e2, e3)), i.e. kdmesh's convention.
  result.tets.reserve(4 * dt.number_of_finite_cells());
  for (const typename T::Cell_handle c : dt.finite_cell_handles()) {
    for (int j = 0; j < 4; ++j) result.tets.push_back(canon[c->vertex(j)->info()]);
  }
  result.num_vertices = dt.number_of_vertices();
  return result;
}

/// Stock CGAL (CgalOptions::plain): Delaunay_triangulation_3<Epick> on a Point_3 range, timed
/// alone; ids recovered afterwards through the points sorted by coordinates.
ReferenceResult cgal_plain_run(const PointSet& points) {
  using PlainDt = CGAL::Delaunay_triangulation_3<K>;
  const std::size_t n = points.size();
  std::vector<Point> pts;
  pts.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) pts.push_back(cgal_point(points, i));
  ReferenceResult result;
  PlainDt dt;
  Stopwatch clock;
  dt.insert(pts.begin(), pts.end());
  result.seconds = clock.seconds();
  if (dt.dimension() < 3)
    throw GeometryError("CGAL: all points are coplanar (triangulation of dimension " +
                        std::to_string(dt.dimension()) + "): no tetrahedralization");
  // A vertex's id: the canonical id of its point (identical points share one vertex).
  const std::vector<std::uint32_t> canon = canonical_point_ids(points);
  std::vector<std::uint32_t> by_xyz(n);
  std::iota(by_xyz.begin(), by_xyz.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) { return pts[a] < pts[b]; };  // lexicographic
  std::sort(by_xyz.begin(), by_xyz.end(), less);
  CGAL::Unique_hash_map<PlainDt::Vertex_handle, std::uint32_t> id(0, dt.number_of_vertices());
  for (const PlainDt::Vertex_handle v : dt.finite_vertex_handles()) {
    const auto it = std::lower_bound(by_xyz.begin(), by_xyz.end(), v->point(),
                                     [&](std::uint32_t a, const Point& p) { return pts[a] < p; });
    if (it == by_xyz.end() || pts[*it] != v->point()) throw Error("CGAL: a vertex that is no input point");
    id[v] = canon[*it];
  }
  result.tets.reserve(4 * dt.number_of_finite_cells());
  for (const PlainDt::Cell_handle c : dt.finite_cell_handles())
    for (int j = 0; j < 4; ++j) result.tets.push_back(id[c->vertex(j)]);
  result.num_vertices = dt.number_of_vertices();
  return result;
}

}  // namespace

ReferenceResult cgal_delaunay(const PointSet& points, const Ordering* order,
                              const CgalOptions& options) {
  if (points.size() == 0) throw GeometryError("CGAL: no points");
  check_finite(points);
  if (order) check_order(*order, points.size());
  if (options.plain) {
    if (order || options.count)
      throw UsageError("stock CGAL inserts the range in its own order and counts nothing");
    return cgal_plain_run(points);
  }
  return options.count ? cgal_run<CountingDt>(points, order) : cgal_run<Dt>(points, order);
}

double convex_hull_volume(const PointSet& points) {
  const std::size_t n = points.size();
  if (n < 4) return 0;
  check_finite(points);
  std::vector<Point> pts;
  pts.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) pts.push_back(cgal_point(points, i));

  // convex_hull_3 of a coplanar set yields a flat (non-closed or two-sided) mesh: detect
  // dimension < 3 first, exactly. Find p0, p1 != p0, p2 not collinear, p3 not coplanar.
  std::size_t i = 1;
  while (i < n && pts[i] == pts[0]) ++i;
  if (i == n) return 0;
  const std::size_t i1 = i;
  while (i < n && CGAL::collinear(pts[0], pts[i1], pts[i])) ++i;
  if (i == n) return 0;
  const std::size_t i2 = i;
  while (i < n && CGAL::orientation(pts[0], pts[i1], pts[i2], pts[i]) == CGAL::COPLANAR) ++i;
  if (i == n) return 0;

  CGAL::Surface_mesh<Point> hull;
  CGAL::convex_hull_3(pts.begin(), pts.end(), hull);

  // Sum of signed tets (ref, a, b, c) over the (triangular, consistently oriented) hull faces,
  // from a hull vertex as reference to limit cancellation; Kahan-compensated in long double.
  const Point ref = hull.point(*hull.vertices().begin());
  long double sum = 0, comp = 0;
  for (const auto f : hull.faces()) {
    const Point* v[3];
    int k = 0;
    for (const auto h : CGAL::halfedges_around_face(hull.halfedge(f), hull)) {
      if (k == 3) throw Error("convex_hull_3 returned a non-triangular face");
      v[k++] = &hull.point(hull.target(h));
    }
    if (k != 3) throw Error("convex_hull_3 returned a degenerate face");
    const long double ax = (long double)v[0]->x() - ref.x(), ay = (long double)v[0]->y() - ref.y(),
                      az = (long double)v[0]->z() - ref.z();
    const long double bx = (long double)v[1]->x() - ref.x(), by = (long double)v[1]->y() - ref.y(),
                      bz = (long double)v[1]->z() - ref.z();
    const long double cx = (long double)v[2]->x() - ref.x(), cy = (long double)v[2]->y() - ref.y(),
                      cz = (long double)v[2]->z() - ref.z();
    const long double det =
        ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    const long double y = det / 6 - comp;
    const long double s = sum + y;
    comp = (s - sum) - y;
    sum = s;
  }
  return double(std::fabs(sum));
}

}  // namespace kdmesh
