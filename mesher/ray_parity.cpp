// kdmesh — exact segment-parity inside/outside test (see ray_parity.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/ray_parity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/rng.h"

namespace kdmesh::ray_parity {

namespace {

using Point = K::Point_3;
using Point2 = K::Point_2;

/// p, coplanar with the non-degenerate triangle abc, lies in the closed triangle: the three
/// edge orientations in a projection where abc stays a triangle (an affine bijection of the
/// plane, so containment is preserved; the projected coordinates are the input doubles).
bool in_closed_triangle(const Point& a, const Point& b, const Point& c, const Point& p) {
  for (int drop = 0; drop < 3; ++drop) {
    auto pr = [drop](const Point& q) {
      return drop == 0 ? Point2(q.y(), q.z()) : drop == 1 ? Point2(q.x(), q.z()) : Point2(q.x(), q.y());
    };
    const CGAL::Orientation o = CGAL::orientation(pr(a), pr(b), pr(c));
    if (o == CGAL::COLLINEAR) continue;
    return CGAL::orientation(pr(a), pr(b), pr(p)) != -o && CGAL::orientation(pr(b), pr(c), pr(p)) != -o &&
           CGAL::orientation(pr(c), pr(a), pr(p)) != -o;
  }
  return false;  // a degenerate facet (prepared surfaces have none) holds no area
}

enum class Meet { none, cross, on_facet, degenerate };

/// How the segment pq, with q strictly outside the surface's bounding box, meets triangle t.
Meet meet(const K::Triangle_3& t, const Point& p, const Point& q) {
  const Point &a = t[0], &b = t[1], &c = t[2];
  const CGAL::Orientation op = CGAL::orientation(a, b, c, p);
  if (op == CGAL::COPLANAR && in_closed_triangle(a, b, c, p)) return Meet::on_facet;
  const CGAL::Orientation oq = CGAL::orientation(a, b, c, q);
  // q is outside the box, so not on the facet: pq meets the plane at q alone, or lies in it.
  if (oq == CGAL::COPLANAR) return op == CGAL::COPLANAR ? Meet::degenerate : Meet::none;
  if (op == CGAL::COPLANAR || op == oq) return Meet::none;  // p off the facet, or one side
  // pq crosses the plane; it crosses the facet iff the line pq passes each edge on one side.
  const CGAL::Orientation s[3] = {CGAL::orientation(p, q, a, b), CGAL::orientation(p, q, b, c),
                                  CGAL::orientation(p, q, c, a)};
  bool pos = false, neg = false, zero = false;
  for (const CGAL::Orientation o : s) {
    pos = pos || o == CGAL::POSITIVE;
    neg = neg || o == CGAL::NEGATIVE;
    zero = zero || o == CGAL::COPLANAR;
  }
  if (pos && neg) return Meet::none;
  return zero ? Meet::degenerate : Meet::cross;  // zero: through an edge or a vertex
}

/// AABB traversal counting the crossings of segment pq; stops at a facet holding p or a
/// degenerate meeting.
struct Crossings {
  Point p, q;
  bool vertical;  // q = (p.x, p.y, z): boxes are tested by exact comparisons alone
  std::size_t count = 0;
  Meet stop = Meet::none;

  bool go_further() const { return stop == Meet::none; }
  bool box_meets(const CGAL::Bbox_3& b) const {
    if (vertical)
      return p.x() >= b.xmin() && p.x() <= b.xmax() && p.y() >= b.ymin() && p.y() <= b.ymax() &&
             std::max(p.z(), q.z()) >= b.zmin() && std::min(p.z(), q.z()) <= b.zmax();
    return K().do_intersect_3_object()(K::Segment_3(p, q), b);  // filtered exact
  }
  template <class Query>
  void intersection(const Query&, const Primitive& primitive) {
    const K::Triangle_3& t = primitive.datum();
    if (!box_meets(t.bbox())) return;
    switch (meet(t, p, q)) {
      case Meet::cross: ++count; break;
      case Meet::none: break;
      case Meet::on_facet: stop = Meet::on_facet; break;
      case Meet::degenerate: stop = Meet::degenerate; break;
    }
  }
  template <class Query, class Node>
  bool do_intersect(const Query&, const Node& node) const {
    return box_meets(node.bbox());
  }
};

bool outside_box(const Point& q, const CGAL::Bbox_3& b) {
  return q.x() < b.xmin() || q.x() > b.xmax() || q.y() < b.ymin() || q.y() > b.ymax() || q.z() < b.zmin() ||
         q.z() > b.zmax();
}

}  // namespace

int side(const Tree& tree, const double* pp) {
  const Point p(pp[0], pp[1], pp[2]);
  const CGAL::Bbox_3 box = tree.bbox();
  if (tree.empty() || outside_box(p, box)) return -1;
  // First a vertical segment to just beyond the nearer of the box's z faces (like CGAL's cast:
  // fewer boxes to visit), then, while a segment grazes an edge or a vertex or lies in a
  // facet's plane, segments in seeded random directions to a point beyond the box.
  const bool down = p.z() - box.zmin() < box.zmax() - p.z();
  const double z = down ? std::nextafter(box.zmin(), -std::numeric_limits<double>::infinity())
                        : std::nextafter(box.zmax(), std::numeric_limits<double>::infinity());
  Crossings c{p, Point(p.x(), p.y(), z), true};
  tree.traversal(K::Segment_3(c.p, c.q), c);
  const double span = std::max({box.xmax() - box.xmin(), box.ymax() - box.ymin(), box.zmax() - box.zmin()});
  Rng rng(0x9a17c0ffee5eedULL);
  for (int attempt = 0; c.stop == Meet::degenerate; ++attempt) {
    if (attempt == 1000)
      throw GeometryError("inside/outside test: 1000 random segments from (" + std::to_string(pp[0]) + ", " +
                          std::to_string(pp[1]) + ", " + std::to_string(pp[2]) + ") all graze an edge");
    double u[3], n2 = 0;
    do {  // uniform on the sphere: rejection from the cube
      n2 = 0;
      for (double& x : u) {
        x = rng.uniform(-1, 1);
        n2 += x * x;
      }
    } while (!(n2 > 1e-4 && n2 <= 1));
    // Length 2 x span per unit of u: beyond the box whatever p's place in it (doubled again
    // if rounding kept q inside); only q's side of the box matters, not its exact place.
    double len = 2 * span / std::sqrt(n2);
    Point q;
    for (;;) {
      q = Point(pp[0] + len * u[0], pp[1] + len * u[1], pp[2] + len * u[2]);
      if (outside_box(q, box)) break;
      len *= 2;
    }
    c = Crossings{p, q, false};
    tree.traversal(K::Segment_3(c.p, c.q), c);
  }
  if (c.stop == Meet::on_facet) return 0;
  return c.count % 2 == 1 ? 1 : -1;
}

}  // namespace kdmesh::ray_parity
