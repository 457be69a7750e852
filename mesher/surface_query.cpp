// kdmesh — SurfaceQuery: CGAL AABB tree adapter (CGAL types stay in this file).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface_query.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/internal/Side_of_triangle_mesh/Point_inside_vertical_ray_cast.h>

#include <cmath>
#include <vector>

#include "core/error.h"

namespace kdmesh {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
}  // namespace

struct SurfaceQuery::Impl {
  Triangles triangles;
  Tree tree;
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
}

SurfaceQuery::~SurfaceQuery() = default;

int SurfaceQuery::side(const double* p) const {
  const K::Point_3 q(p[0], p[1], p[2]);
  const CGAL::Bbox_3 box = impl_->tree.bbox();
  if (q.x() < box.xmin() || q.x() > box.xmax() || q.y() < box.ymin() || q.y() > box.ymax() ||
      q.z() < box.zmin() || q.z() > box.zmax())
    return -1;
  // Parity of the crossings of a ray (vertical first, random ones if it grazes an edge):
  // right for nested shells too. Filtered-exact predicates decide each crossing.
  const CGAL::Bounded_side s =
      CGAL::internal::Point_inside_vertical_ray_cast<K, Tree>()(q, impl_->tree);
  return s == CGAL::ON_BOUNDED_SIDE ? 1 : s == CGAL::ON_UNBOUNDED_SIDE ? -1 : 0;
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

double SurfaceQuery::distance(const double* p) const {
  const K::Point_3 q(p[0], p[1], p[2]);
  return std::sqrt(impl_->tree.squared_distance(q));
}

}  // namespace kdmesh
