// kdmesh — exact validity check of a Delaunay triangulation.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/reference/delaunay_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "mesher/delaunay/conflict.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"

namespace kdmesh {

namespace {

std::string tet_str(const Triangulation& tri, std::size_t t) {
  std::string s = "tet " + std::to_string(t) + " (";
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t v = tri.v(t, i);
    if (i) s += ' ';
    s += v == kInfiniteVertex ? std::string("inf") : std::to_string(v);
  }
  return s + ")";
}

std::array<std::uint32_t, 3> face_of(const Triangulation& tri, std::size_t t, int f) {
  std::array<std::uint32_t, 3> x{};
  for (int i = 0, k = 0; i < 4; ++i)
    if (i != f) x[k++] = tri.v(t, i);
  std::sort(x.begin(), x.end());
  return x;
}

/// Is the face (t, f) with opposite vertex q decided by the perturbation alone (the
/// unperturbed test is exactly 0)? For a hull face: q coplanar with it and on its circumcircle.
bool is_tie(const PointSet& points, const Triangulation& tri, std::size_t t, int f, std::uint32_t q) {
  const std::uint32_t* v = &tri.data[8 * t];
  int inf = -1;
  for (int i = 0; i < 4; ++i)
    if (v[i] == kInfiniteVertex) inf = i;
  if (inf < 0)
    return pred::insphere(points.p(v[0]), points.p(v[1]), points.p(v[2]), points.p(v[3]),
                          points.p(q)) == 0;
  (void)f;
  const double* p[4];
  for (int i = 0; i < 4; ++i) p[i] = i == inf ? points.p(q) : points.p(v[i]);
  if (pred::orient3d(p[0], p[1], p[2], p[3]) != 0) return false;
  // Coplanar: a tie only if q is on the circumcircle of the hull face. The sphere through the
  // face and the apex behind it meets the plane in that circle.
  const double* apex = points.p(tri.opposite(tri.adj(t, inf)));
  const double* a[3];
  for (int i = 0, k = 0; i < 4; ++i)
    if (i != inf) a[k++] = points.p(v[i]);
  if (pred::orient3d(a[0], a[1], a[2], apex) < 0) std::swap(a[0], a[1]);
  return pred::insphere(a[0], a[1], a[2], apex, points.p(q)) == 0;
}

}  // namespace

ValidityReport check_delaunay(const PointSet& points, const Triangulation& tri,
                              std::size_t max_problems) {
  ValidityReport r;
  auto problem = [&](std::string msg) {
    if (r.problems.size() < max_problems) r.problems.push_back(std::move(msg));
  };
  const std::size_t m = tri.num_tets();
  const std::size_t n = points.size();
  if (tri.data.size() % 8 != 0) {
    r.asymmetric_adjacencies = 1;
    problem("tet records are not 8 entries each");
    return r;
  }

  // 1. Structure: vertex ids, one infinite vertex at most, symmetric adjacency.
  std::vector<bool> used(n, false);
  bool structure_ok = true;
  for (std::size_t t = 0; t < m; ++t) {
    int inf = 0;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t v = tri.v(t, i);
      if (v == kInfiniteVertex) ++inf;
      else if (v >= n) {
        structure_ok = false;
        problem(tet_str(tri, t) + ": vertex id out of range");
      } else used[v] = true;
    }
    if (inf > 1) {
      structure_ok = false;
      problem(tet_str(tri, t) + ": more than one infinite vertex");
    }
    for (int f = 0; f < 4; ++f) {
      const std::uint32_t a = tri.adj(t, f);
      const std::size_t u = a >> 2;
      if (u >= m || tri.adj(u, a & 3) != 4 * t + f || face_of(tri, t, f) != face_of(tri, u, a & 3)) {
        ++r.asymmetric_adjacencies;
        problem(tet_str(tri, t) + " face " + std::to_string(f) +
                ": neighbour does not point back through the same face");
      }
    }
  }
  if (!structure_ok) ++r.asymmetric_adjacencies;
  if (r.asymmetric_adjacencies) return r;  // the geometric checks below need sound topology

  // 2. Every point is a vertex, unless it repeats another point's coordinates.
  // Which copy of a repeated point became the vertex depends on the insertion order, so
  // coverage is tested per class of identical points.
  const std::vector<std::uint32_t> canon = canonical_point_ids(points);
  std::vector<bool> class_used(n, false);
  for (std::size_t i = 0; i < n; ++i)
    if (used[i]) class_used[canon[i]] = true;
  for (std::size_t i = 0; i < n; ++i)
    if (!class_used[canon[i]]) {
      ++r.asymmetric_adjacencies;
      problem("point " + std::to_string(i) + " is not a vertex of the triangulation");
    }

  // 3. Orientation and local Delaunay property of every face (exact, perturbed).
  for (std::size_t t = 0; t < m; ++t) {
    const std::uint32_t* v = &tri.data[8 * t];
    const bool infinite = tri.is_infinite(t);
    if (infinite) {
      for (int i = 0; i < 4; ++i) r.hull_faces += v[i] == kInfiniteVertex;
    } else {
      ++r.finite_tets;
      if (pred::orient3d(points.p(v[0]), points.p(v[1]), points.p(v[2]), points.p(v[3])) <= 0) {
        ++r.bad_orientation;
        problem(tet_str(tri, t) + ": not positively oriented");
      }
    }
    for (int f = 0; f < 4; ++f) {
      const std::uint32_t q = tri.opposite(tri.adj(t, f));  // vertex opposite face f, in the neighbour
      if (q == kInfiniteVertex) continue;                  // never in conflict with a finite tet
      if (tri.adj(t, f) >> 2 > t && is_tie(points, tri, t, f, q)) ++r.tie_faces;
      if (tet_in_conflict(points.xyz.data(), tri.data.data(), std::uint32_t(t), points.p(q))) {
        ++r.non_delaunay_faces;
        problem(tet_str(tri, t) + " face " + std::to_string(f) + ": opposite vertex " +
                std::to_string(q) + (infinite ? " breaks hull convexity" : " is inside its circumsphere"));
      }
    }
  }

  // 4. The tets cover the convex hull exactly once: compare volumes with an independent hull.
  //    Compared with the largest coordinate scaled into [0.5, 1) (a power-of-two rescaling),
  //    so that large inputs do not overflow (1e+104: inf vs inf), also when they are mixed
  //    with tiny ones (1e-300), whose volumes are negligible against the tolerance; reported
  //    in the input's units (inf when beyond double range).
  const int k = magnitude_scale_exponent(points);
  const PointSet scaled = k != 0 ? scaled_copy(points, k) : points;
  const double volume = total_volume(scaled, finite_tets(tri));
  const double hull = convex_hull_volume(scaled);
  r.volume = std::ldexp(volume, -3 * k);
  r.hull_volume = std::ldexp(hull, -3 * k);
  r.scaled_volume = volume;
  r.scaled_hull_volume = hull;
  r.volume_exponent = k;
  r.volume_matches = std::fabs(volume - hull) <= 1e-9 * std::max(std::fabs(hull), 1e-300);
  if (!r.volume_matches)
    problem("total tet volume " + std::to_string(r.volume) + " differs from the convex hull's " +
            std::to_string(r.hull_volume));
  return r;
}

}  // namespace kdmesh
