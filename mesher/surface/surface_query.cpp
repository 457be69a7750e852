// kdmesh — SurfaceQuery: CGAL AABB tree adapter (CGAL types stay in this file), with the exact
// segment-parity inside/outside test (ray_parity::side).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface/surface_query.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "core/triangle_distance.h"

namespace kdmesh::ray_parity {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

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

/// +1 strictly inside the closed surface held by `tree` (nested shells: odd parity), -1
/// strictly outside, 0 on a facet (closed).
///
/// Why not CGAL's Point_inside_vertical_ray_cast (used up to issue 19): its rays are
/// p + (0, 0, +-1) and, where that ray grazes an edge, p + a random unit vector, and CGAL's
/// ray-triangle test then builds a + (q - p) at a facet vertex a
/// (Intersections_3/internal/Ray_3_Triangle_3_do_intersect.h:231) in double precision. A
/// direction of absolute length 1 is rounded to ulp(|x|) = 2^(e-52) there: from |x| = 2^52
/// (ulp 1, a half-unit step ties back to a) the direction is lost, a crossing missed and the
/// side wrong (a cube of side 2^52 answered "outside" at its centre), and from 2^53 even the
/// vertical ray is degenerate (z + 1 == z). Here the segment runs from p to a point q beyond
/// the bounding box, q is never derived from a unit vector, and every decision is an exact
/// orientation sign of the input doubles p, q and the facet vertices, so the answer is exact
/// and the same at every scale.
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

namespace kdmesh {

namespace {
using K = ray_parity::K;
using Triangles = ray_parity::Triangles;
using Primitive = ray_parity::Primitive;
using Tree = ray_parity::Tree;
}  // namespace

/// The facets binned on a uniform grid by where their triangles come near a cell
/// (register_triangles): the facets near a small box, and the nearest facet of a point.
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
    corners_.resize(9 * tris.size());
    for (std::size_t f = 0; f < tris.size(); ++f)
      for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) corners_[9 * f + 3 * v + k] = tris[f].vertex(v)[k];
    // Each facet's plane: unit normal, offset, and the rounding slack of a plane distance
    // (a computed normal is off by ~1e-16 |u||v| / |u x v| rad: needle facets get more slack,
    // near-degenerate ones no plane bound at all).
    planes_.assign(6 * tris.size(), 0.0);
    for (std::size_t f = 0; f < tris.size(); ++f) {
      const double* t = &corners_[9 * f];
      const double u[3] = {t[3] - t[0], t[4] - t[1], t[5] - t[2]}, v[3] = {t[6] - t[0], t[7] - t[1], t[8] - t[2]};
      const double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      const double kappa = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) *
                           std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / len;
      if (!(len > 0) || !(kappa < 1e6)) continue;  // zeros: a bound of -slack, never used
      double* pl = &planes_[6 * f];
      for (int k = 0; k < 3; ++k) pl[k] = nrm[k] / len;
      pl[3] = pl[0] * t[0] + pl[1] * t[1] + pl[2] * t[2];
      // slack(p) = pl[4] * (|p|_1 + |t0|_1) >= 1e-12 (|p|_1 + |offset|) + 1e-13 kappa |p - t0|_1
      pl[4] = 1e-12 + 1e-13 * kappa;
      pl[5] = std::fabs(t[0]) + std::fabs(t[1]) + std::fabs(t[2]);
    }
    for (int k = 0; k < 3; ++k) magnitude_ = std::max({magnitude_, std::fabs(lo_[k]), std::fabs(hi_[k])});
    min_cell_ = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
      if (inv_[k] > 0) min_cell_ = std::min(min_cell_, 1 / inv_[k]);
    register_triangles(std::size_t(n_[0]) * n_[1] * n_[2]);
    // The point-triangle distances of the registration and of nearest() take products of four
    // coordinate differences: beyond 2^255 they overflow (a cube of side 2^300 registered no
    // facet anywhere), below 2^-255 they vanish. Outside [2^-200, 2^200] the grid answers
    // nothing and every query goes to the tree.
    double extent = 0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, hi_[k] - lo_[k]);
    usable_ = magnitude_ <= 0x1p200 && extent >= 0x1p-200;
  }

  /// Each facet also in the cells its triangle comes near, not only its box: a long
  /// diagonal facet's box spans many cells its triangle never touches. A cell takes the facet
  /// when the triangle comes within the cell's half diagonal of its centre (plus a margin of
  /// 1e-6 cell and 1e-13 x the coordinates' magnitude for the rounding of the centre, of the
  /// distance and of a point's cell index): every facet that has a point in a cell, or at a
  /// point whose computed cell index is that cell, is in its list.
  void register_triangles(std::size_t cells) {
    double size[3], big = 0;
    for (int k = 0; k < 3; ++k) {
      size[k] = inv_[k] > 0 ? 1 / inv_[k] : 0;
      big = std::max(big, size[k]);
    }
    const double reach =
        0.5 * std::sqrt(size[0] * size[0] + size[1] * size[1] + size[2] * size[2]) + 1e-6 * big + 1e-13 * magnitude_;
    std::vector<std::uint32_t> count(cells + 1, 0);
    auto each_cell = [&](std::uint32_t f, auto&& g) {
      const std::array<double, 6>& b = boxes_[f];
      const double* t = &corners_[9 * std::size_t(f)];
      int a[3], z[3];
      for (int k = 0; k < 3; ++k) a[k] = index(k, b[k]), z[k] = index(k, b[3 + k]);
      for (int l = a[2]; l <= z[2]; ++l)
        for (int j = a[1]; j <= z[1]; ++j)
          for (int i = a[0]; i <= z[0]; ++i) {
            const double c[3] = {lo_[0] + (i + 0.5) * size[0], lo_[1] + (j + 0.5) * size[1],
                                 lo_[2] + (l + 0.5) * size[2]};
            if (triangle_distance(c, t, t + 3, t + 6) <= reach) g((std::size_t(l) * n_[1] + j) * n_[0] + i);
          }
    };
    for (std::uint32_t f = 0; f < boxes_.size(); ++f) each_cell(f, [&](std::size_t c) { ++count[c + 1]; });
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    tstart_ = count;
    titems_.resize(count.back());
    for (std::uint32_t f = 0; f < boxes_.size(); ++f) each_cell(f, [&](std::size_t c) { titems_[count[c]++] = f; });
  }

  /// Calls f(facet) for the facets listed in the cells that the closed box [a, b] spans (per
  /// axis a <= b; each facet that has a point in the box is among them, some more than once)
  /// and returns true; returns false, calling nothing, when the box spans more than
  /// `max_cells` cells.
  template <class F>
  bool facets_near(const double* a, const double* b, std::size_t max_cells, F&& f) const {
    if (!usable_) return false;
    int ia[3], ib[3];
    std::size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      if (b[k] < lo_[k] || a[k] > hi_[k]) return true;  // outside every facet's box
      ia[k] = index(k, a[k]), ib[k] = index(k, b[k]);
      cells *= std::size_t(ib[k] - ia[k] + 1);
    }
    if (cells > max_cells) return false;
    for (int l = ia[2]; l <= ib[2]; ++l)
      for (int j = ia[1]; j <= ib[1]; ++j)
        for (int i = ia[0]; i <= ib[0]; ++i) {
          const std::size_t c = (std::size_t(l) * n_[1] + j) * n_[0] + i;
          for (std::uint32_t x = tstart_[c]; x < tstart_[c + 1]; ++x) f(titems_[x]);
        }
    return true;
  }
  /// Points a and b lie strictly on one side of facet f's plane, each farther from it than
  /// the rounding slack of its computed plane distance (build()): then the segment ab cannot
  /// meet the facet. False when in doubt, and always for a facet without a plane bound.
  bool plane_separates(std::uint32_t facet, const double* a, const double* b) const {
    const double* pl = &planes_[6 * std::size_t(facet)];
    const double da = pl[0] * a[0] + pl[1] * a[1] + pl[2] * a[2] - pl[3];
    const double sa = pl[4] * (std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]) + pl[5]);
    if (!(std::fabs(da) > sa)) return false;
    const double db = pl[0] * b[0] + pl[1] * b[1] + pl[2] * b[2] - pl[3];
    const double sb = pl[4] * (std::fabs(b[0]) + std::fabs(b[1]) + std::fabs(b[2]) + pl[5]);
    return da > 0 ? db > sb : db < -sb;
  }
  /// Whether the nearest facet is within r of p: 1 when one certainly is (its distance below
  /// r by a relative 1e-9), 0 when none certainly is (no facet within r (1 + 1e-9) of p: the
  /// facets listed in the cells of the box around p hold every facet point that near), -1
  /// when a facet's distance is within those margins of r, or the box spans more than 64
  /// cells: the caller decides with the tree then.
  int within(const double* p, double r) const {
    if (!usable_) return -1;
    const double scale = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]);
    const double lo_r = r * (1 - 1e-9), hi_r = r * (1 + 1e-9) + 1e-12 * (scale + magnitude_);
    double a[3], b[3];
    for (int k = 0; k < 3; ++k) a[k] = p[k] - hi_r, b[k] = p[k] + hi_r;
    int verdict = 0;
    const bool searched = facets_near(a, b, 64, [&](std::uint32_t f) {
      if (verdict == 1) return;
      if (box_d2(f, p) > hi_r * hi_r) return;
      const double* t = &corners_[9 * std::size_t(f)];
      double q[3];
      closest_on_triangle(p, t, t + 3, t + 6, q);
      const double e2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
      if (e2 <= lo_r * lo_r) verdict = 1;
      else if (e2 <= hi_r * hi_r) verdict = -1;
    });
    return searched ? verdict : -1;
  }
  /// The number of cells (the range of cell()'s ids).
  std::size_t cells() const { return tstart_.empty() ? 0 : tstart_.size() - 1; }
  /// Cell c (< cells()) lists no facet. No facet comes within that cell's half diagonal (plus
  /// margins) of its centre, and a point whose cell() is c lies in that ball whatever the
  /// rounding of its index (register_triangles): all such points lie in one facet-free ball,
  /// so on one side of the surface, never on it.
  bool lists_no_facet(std::size_t c) const { return tstart_[c] == tstart_[c + 1]; }
  /// p's cell when p lies in the grid's box (and the grid is usable), else cells().
  std::size_t cell(const double* p) const {
    if (!usable_) return cells();
    std::size_t c = 0;
    for (int k = 2; k >= 0; --k) {
      if (!(p[k] >= lo_[k] && p[k] <= hi_[k])) return cells();  // off the box, or NaN
      c = c * std::size_t(n_[k]) + std::size_t(index(k, p[k]));
    }
    return c;
  }
  /// A point near the centre of cell c (< cells()), rounded: a reference point, not a bound.
  void centre(std::size_t c, double* out) const {
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = c % std::size_t(n_[k]);
      c /= std::size_t(n_[k]);
      out[k] = inv_[k] > 0 ? std::min(hi_[k], lo_[k] + (double(i) + 0.5) / inv_[k]) : lo_[k];
    }
  }
  /// The largest |coordinate| of the facets.
  double magnitude() const { return magnitude_; }
  /// The squared distance from p to facet f's bounding box: a lower bound of its distance.
  double box_d2(std::uint32_t facet, const double* p) const {
    const std::array<double, 6>& bx = boxes_[facet];
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double o = std::max({bx[k] - p[k], p[k] - bx[3 + k], 0.0});
      d2 += o * o;
    }
    return d2;
  }
  /// Facet f's bounding box meets the closed box [a, b] (exact comparisons).
  bool box_meets(std::uint32_t facet, const double* a, const double* b) const {
    const std::array<double, 6>& f = boxes_[facet];
    return f[0] <= b[0] && a[0] <= f[3] && f[1] <= b[1] && a[1] <= f[4] && f[2] <= b[2] && a[2] <= f[5];
  }

  /// The distance from p to the nearest facet, searched ring by ring of cells around p's
  /// cell; NaN when that search would pass `max_ring` rings (p far from every facet: the
  /// caller asks the tree). A facet in no list of rings 0..r has no point in those cells
  /// (register_triangles), so it is at least as far as the block's nearest face that is not
  /// on the grid's boundary (less a 1e-6 cell margin for the rounding of cell indices); the
  /// search stops once the nearest facet found is that near.
  /// Within a ring, the facets are taken nearest lower bound first (the distance to the
  /// facet's box, and to its plane less a slack for rounding, see build()),
  /// and one is computed only while its bound is below the nearest distance so far. On long
  /// facets (a gear's teeth) p lies in many facet boxes, and a box bound alone let ~120
  /// triangles per query be computed. The minimum is of the same point-triangle distances
  /// as the tree's, computed in another order of operations: equal up to rounding.
  ///
  /// With `facet`: also the nearest facet, and *unique = whether every other facet is farther
  /// by a margin (1e-6 of the squared distance, plus (1e-12 x the coordinates' magnitude)^2)
  /// that no rounding of either computation can close, so that CGAL's tree returns this
  /// facet too. The search then goes on while a facet may come within that margin.
  double nearest(const double* p, int max_ring, std::uint32_t* facet = nullptr, bool* unique = nullptr) const {
    if (!usable_) return std::numeric_limits<double>::quiet_NaN();
    int c0[3];
    for (int k = 0; k < 3; ++k) c0[k] = index(k, p[k]);
    const double scale = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]);
    double best2 = std::numeric_limits<double>::infinity();
    // The nearest facet, and the least squared distance of the others (facet queries only).
    std::uint32_t best_f = std::numeric_limits<std::uint32_t>::max();
    double second2 = std::numeric_limits<double>::infinity();
    const double slack2 = facet ? std::pow(1e-12 * (scale + magnitude_), 2) : 0.0;
    // The squared distance below which a facet still matters: the nearest's, or its margin.
    double limit2 = best2;
    auto consider = [&](std::uint32_t f, double d2) {
      if (!facet) {
        limit2 = best2 = std::min(best2, d2);
        return;
      }
      if (f == best_f) return;  // listed in several cells
      if (d2 < best2) {
        second2 = best2;
        best2 = d2, best_f = f;
        limit2 = best2 * (1 + 1e-6) + slack2;
      } else {
        second2 = std::min(second2, d2);
      }
    };
    constexpr std::size_t kPending = 256;
    std::array<std::pair<double, std::uint32_t>, kPending> pending;  // (lower bound^2, facet)
    std::size_t m = 0;
    auto exact2 = [&](std::uint32_t f) {
      const double* t = &corners_[9 * std::size_t(f)];
      double q[3];
      closest_on_triangle(p, t, t + 3, t + 6, q);
      return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
    };
    auto scan = [&](std::size_t c) {
      for (std::uint32_t x = tstart_[c]; x < tstart_[c + 1]; ++x) {
        const std::uint32_t f = titems_[x];
        double d2 = box_d2(f, p);
        const double* pl = &planes_[6 * std::size_t(f)];
        const double dp = std::fabs(pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2] - pl[3]) - pl[4] * (scale + pl[5]);
        if (dp > 0) d2 = std::max(d2, dp * dp);
        if (!(d2 < limit2)) continue;
        if (m < kPending)
          pending[m++] = {d2, f};
        else
          consider(f, exact2(f));  // a crowded ring: no ordering past kPending
      }
    };
    // The pending facets, lowest bound first, while a bound is below the nearest so far.
    auto settle = [&] {
      while (m > 0) {
        std::size_t i = 0;
        for (std::size_t j = 1; j < m; ++j)
          if (pending[j].first < pending[i].first) i = j;
        if (!(pending[i].first < limit2)) break;
        const std::uint32_t f = pending[i].second;
        consider(f, exact2(f));
        std::size_t keep = 0;  // drop f (listed once per cell) and what can no longer win
        for (std::size_t j = 0; j < m; ++j)
          if (pending[j].second != f && pending[j].first < limit2) pending[keep++] = pending[j];
        m = keep;
      }
      m = 0;
    };
    for (int r = 0;; ++r) {
      int a[3], b[3];
      double reach = std::numeric_limits<double>::infinity();  // to the block's inner faces
      for (int k = 0; k < 3; ++k) {
        a[k] = std::max(c0[k] - r, 0), b[k] = std::min(c0[k] + r, n_[k] - 1);
        const double size = 1 / inv_[k];
        if (a[k] > 0) reach = std::min(reach, p[k] - (lo_[k] + a[k] * size) - 1e-6 * size);
        if (b[k] < n_[k] - 1) reach = std::min(reach, lo_[k] + (b[k] + 1) * size - p[k] - 1e-6 * size);
      }
      for (int l = a[2]; l <= b[2]; ++l)
        for (int j = a[1]; j <= b[1]; ++j) {
          const std::size_t row = (std::size_t(l) * n_[1] + j) * n_[0];
          if (std::abs(l - c0[2]) < r && std::abs(j - c0[1]) < r) {  // inside: the ring's two ends
            if (c0[0] - r >= 0) scan(row + std::size_t(c0[0] - r));
            if (c0[0] + r < n_[0]) scan(row + std::size_t(c0[0] + r));
          } else {
            for (int i = a[0]; i <= b[0]; ++i) scan(row + std::size_t(i));
          }
        }
      settle();
      if (reach == std::numeric_limits<double>::infinity() || (reach > 0 && limit2 <= reach * reach)) {
        if (facet) *facet = best_f, *unique = !(second2 <= limit2) && best_f < boxes_.size();
        return std::sqrt(best2);
      }
      if (r == max_ring) return std::numeric_limits<double>::quiet_NaN();
    }
  }
 private:
  int index(int k, double x) const {
    return std::clamp(int(std::floor((x - lo_[k]) * inv_[k])), 0, n_[k] - 1);
  }
  double lo_[3], hi_[3], inv_[3];
  int n_[3];
  double min_cell_ = 0;
  double magnitude_ = 0;  // largest |coordinate| of the facets
  bool usable_ = false;   // the coordinates' scale allows the grid's arithmetic (build())
  std::vector<std::array<double, 6>> boxes_;
  std::vector<double> corners_;  // 3 x 3 coordinates per facet
  std::vector<double> planes_;   // per facet: unit normal, offset, rounding slack (2 terms)
  std::vector<std::uint32_t> tstart_, titems_;  // per cell: the facets whose triangle comes near it
};

struct SurfaceQuery::Impl {
  Triangles triangles;
  Tree tree;
  BoxGrid boxes;
  /// Per grid cell, 0 until first asked, then:
  ///  - a cell that lists no facet (BoxGrid::lists_no_facet): its side, +1 / -1, found by the
  ///    first point asked there. Any point of the cell has that side, so the answer does not
  ///    depend on which point (or thread) came first.
  ///  - a cell that lists facets: the side of its centre point (BoxGrid::centre), or
  ///    kCentreOnSurface.
  std::unique_ptr<std::int8_t[]> cell_side;
  static constexpr std::int8_t kCentreOnSurface = 2;
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
  impl_->cell_side.reset(new std::int8_t[impl_->boxes.cells()]());
}

SurfaceQuery::~SurfaceQuery() = default;

int SurfaceQuery::side(const double* p) const {
  // Parity of a segment's crossings, exact at any magnitude: ray_parity::side above, whose
  // segment runs to beyond the surface's box and crosses every wall on the way. Two shortcuts,
  // both exact, from the grid's cells (the gear box's assembly asked 3.7M interior nodes'
  // bodies):
  //  - in a facet-free cell, the cell's side, found once;
  //  - in a cell that lists facets, the side of the cell's centre (found once), when the
  //    segment from p to the centre meets no facet (segment_clear, exact). A point on the
  //    surface meets a facet there, so it goes to the parity test, which finds it on.
  const BoxGrid& grid = impl_->boxes;
  const std::size_t c = grid.cell(p);
  if (c == grid.cells()) return ray_parity::side(impl_->tree, p);
  std::atomic_ref<std::int8_t> known(impl_->cell_side[c]);
  int s = known.load(std::memory_order_relaxed);
  if (grid.lists_no_facet(c)) {
    if (s == 0) {
      s = ray_parity::side(impl_->tree, p);
      if (s != 0) known.store(std::int8_t(s), std::memory_order_relaxed);  // (never 0 here)
    }
    return s;
  }
  double centre[3];
  grid.centre(c, centre);
  if (s == 0) {
    s = ray_parity::side(impl_->tree, centre);
    if (s == 0) s = Impl::kCentreOnSurface;
    known.store(std::int8_t(s), std::memory_order_relaxed);
  }
  if (s != Impl::kCentreOnSurface && segment_clear(p, centre)) return s;
  return ray_parity::side(impl_->tree, p);
}

double SurfaceQuery::closest(const double* p, double* out, std::uint32_t* facet) const {
  const K::Point_3 q(p[0], p[1], p[2]);
  // Near the surface the facet grid finds the nearest facet (CGAL's tree took 0.3 s of CPU
  // in pinion.ply's boundary judgement alone). Where it is nearer than every other facet by a
  // margin, the tree returns it too (its traversal keeps the point found last among those not
  // farther than its best, so only a tie could displace it); the point is then the tree's own
  // construction on that facet, so the answer is the tree's, bit for bit. Near ties (a point
  // nearest to an edge or a corner of the surface, where the tree's choice among the facets
  // depends on its traversal) are the tree's.
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) {
    std::uint32_t f = 0;
    bool unique = false;
    const double d = impl_->boxes.nearest(p, 2, &f, &unique);
    if (d == d && unique) {
      const K::Point_3 c = K().construct_projected_point_3_object()(impl_->triangles[f], q);
      out[0] = c.x();
      out[1] = c.y();
      out[2] = c.z();
      if (facet) *facet = f;
      return std::sqrt(CGAL::squared_distance(q, c));
    }
  }
  const auto [c, id] = impl_->tree.closest_point_and_primitive(q);
  out[0] = c.x();
  out[1] = c.y();
  out[2] = c.z();
  if (facet) *facet = std::uint32_t(id - impl_->triangles.cbegin());
  return std::sqrt(CGAL::squared_distance(q, c));
}

bool SurfaceQuery::segment_clear(const double* a, const double* b) const {
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = std::min(a[k], b[k]), hi[k] = std::max(a[k], b[k]);
  const bool point = a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
  const K::Segment_3 seg(K::Point_3(a[0], a[1], a[2]), K::Point_3(b[0], b[1], b[2]));
  // The facets near the box's cells (register_triangles), each tested exactly: the kernel's
  // do_intersect is filtered exact, as in AABB_traits. A box over many cells: the tree.
  bool meets = false;
  const bool searched = impl_->boxes.facets_near(lo, hi, 64, [&](std::uint32_t f) {
    if (meets || !impl_->boxes.box_meets(f, lo, hi)) return;
    if (point) {
      meets = true;
    } else if (!impl_->boxes.plane_separates(f, a, b)) {  // a cheap bound first, then exact
      meets = K().do_intersect_3_object()(seg, impl_->triangles[f]);
    }
  });
  if (searched) return !meets;  // always for a point, unless the grid is off (its scale)
  if (point) return side(a) != 0;  // a point meets a closed facet iff it is on the surface
  return !impl_->tree.do_intersect(seg);
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
  const double reach = std::max({impl_->boxes.magnitude(), std::fabs(origin[0]), std::fabs(origin[1]), std::fabs(origin[2])});
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
  // Near the surface (most callers' points), a few cells of the facet grid hold the nearest
  // facet: cheaper than the tree's traversal. Farther away, the tree.
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) {
    const double d = impl_->boxes.nearest(p, 2);
    if (d == d) return d;
  }
  const K::Point_3 q(p[0], p[1], p[2]);
  return std::sqrt(impl_->tree.squared_distance(q));
}

bool SurfaceQuery::within(const double* p, double r, const double* hint) const {
  // distance(p, hint) <= r, decided by the facet grid wherever the margins allow: distance(p,
  // hint) is min(|p - hint|, the distance), and both are compared with r by a relative 1e-9
  // (far above the rounding of either computation) before the tree is asked.
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && r >= 0 && std::isfinite(r)) {
    const double ph = std::sqrt((p[0] - hint[0]) * (p[0] - hint[0]) + (p[1] - hint[1]) * (p[1] - hint[1]) +
                                (p[2] - hint[2]) * (p[2] - hint[2]));
    if (ph <= r * (1 - 1e-9)) return true;
    if (ph > r * (1 + 1e-9) + 1e-12 * (std::fabs(hint[0]) + std::fabs(hint[1]) + std::fabs(hint[2]))) {
      const int v = impl_->boxes.within(p, r);
      if (v >= 0) return v == 1;
    }
  }
  return distance(p, hint) <= r;
}

bool SurfaceQuery::within(const double* p, double r) const {
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && r >= 0 && std::isfinite(r)) {
    const int v = impl_->boxes.within(p, r);
    if (v >= 0) return v == 1;
  }
  return distance(p) <= r;
}

double SurfaceQuery::distance(const double* p, const double* hint) const {
  const K::Point_3 q(p[0], p[1], p[2]), h(hint[0], hint[1], hint[2]);
  return std::sqrt(impl_->tree.squared_distance(q, h));
}

}  // namespace kdmesh
