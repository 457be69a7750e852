// kdmesh — TetGen 1.5 (library mode) as a reference Delaunay tetrahedralization.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Switches "zQJF": z = zero-based indices, Q = quiet, J = do not jettison duplicated points
// (so output point i is input point i and tets carry input ids), F = do not build the list
// of convex-hull faces (not needed). No p/q/r/a: a plain Delaunay tetrahedralization.
//
// Behaviour of TetGen 1.5.0 that this adapter works around (all verified on Debian's 1.5.0-5):
//  - Exact duplicates are detected exactly (point location lands ON a vertex) and skipped;
//    which copy survives depends on TetGen's internal BRIO/Hilbert order, not on input order.
//    Points 1 ulp apart stay distinct. We canonicalise ids with canonical_point_ids().
//  - Without J, TetGen renumbers the output points after dropping duplicates.
//  - TetGen's error exit (terminatetetgen) frees its memory and then throws an int, after which
//    the tetgenmesh destructor frees it again: the process crashes (SIGSEGV) instead of
//    throwing. An axis-aligned planar input even hits an assert() (abort) in exactinit().
//    Its initial simplex search uses a relative tolerance (epsilon = 1e-8, see -T).
//    So inputs that TetGen would reject must be rejected *before* calling it: see
//    check_tetgen_can_handle().
#include <string>

#include "core/error.h"
#include "mesher/reference/reference_delaunay.h"

// Without TetGen (KDMESH_WITH_TETGEN=OFF) only the stubs at the end are built.
#ifdef KDMESH_WITH_TETGEN
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <vector>

#include <tetgen.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "core/timer.h"
#include "mesher/reference/tet_compare.h"

namespace kdmesh {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

Point cgal_point(const PointSet& points, std::uint32_t i) {
  const double* p = points.p(i);
  return Point(p[0], p[1], p[2]);
}

void check_finite(const PointSet& points) {
  const std::size_t i = first_non_finite(points);
  if (i < points.size()) throw GeometryError("point " + std::to_string(i) + " has a non-finite coordinate");
}

/// Throws GeometryError unless the points contain 4 non-coplanar points (exact predicates).
void check_not_coplanar(const PointSet& points) {
  const std::uint32_t n = std::uint32_t(points.size());
  std::uint32_t i = 1;
  const Point p0 = cgal_point(points, 0);
  while (i < n && cgal_point(points, i) == p0) ++i;
  if (i == n) throw GeometryError("all points coincide: no tetrahedralization");
  const Point p1 = cgal_point(points, i);
  while (i < n && CGAL::collinear(p0, p1, cgal_point(points, i))) ++i;
  if (i == n) throw GeometryError("all points are collinear: no tetrahedralization");
  const Point p2 = cgal_point(points, i);
  while (i < n && CGAL::orientation(p0, p1, p2, cgal_point(points, i)) == CGAL::COPLANAR) ++i;
  if (i == n) throw GeometryError("all points are coplanar: no tetrahedralization");
}

/// Rejects inputs so flat that TetGen's toleranced initial-simplex search could fail (which
/// would crash the process, see the file comment).
///
/// Sufficient condition derived from TetGen 1.5.0's incrementaldelaunay(): with D the
/// bounding-box diagonal and eps = 1e-8, its three searches (a 2nd point farther than eps*D from
/// the 1st, a 3rd with |cross|/D^2 >= eps^2, a 4th with |orient|/D^3 >= eps^3) all succeed, for
/// any internal order, if the point set has width > 2*eps*D. Any tet (a,b,c,d) of input points
/// bounds the width from below: width >= 6*vol/D^2 = |orient(a,b,c,d)|/D^2. We build a fat tet
/// greedily (a = min-x point, b farthest from a, c farthest from line ab, d farthest from plane
/// abc) and require |orient|/D^3 >= 1e-7, i.e. width >= 1e-7 * D: a 5x margin, far above the
/// rounding error of the double arithmetic used here. Point sets of relative width below
/// ~1e-7..1e-6 are refused (GeometryError) rather than risk a crash. (Coordinates beyond
/// ~1e100 overflow D^3 here, as they do in TetGen itself: such inputs are refused too.)
void check_tetgen_can_handle(const PointSet& points) {
  const std::size_t n = points.size();
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = points.xyz[k];
  std::size_t a = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double* p = points.p(std::uint32_t(i));
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
    if (p[0] < points.p(std::uint32_t(a))[0]) a = i;
  }
  const double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  const double diag = std::sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);

  auto sub = [&](std::size_t i, std::size_t j, double* d) {
    const double *p = points.p(std::uint32_t(i)), *q = points.p(std::uint32_t(j));
    for (int k = 0; k < 3; ++k) d[k] = p[k] - q[k];
  };
  auto cross = [](const double* u, const double* v, double* w) {
    w[0] = u[1] * v[2] - u[2] * v[1];
    w[1] = u[2] * v[0] - u[0] * v[2];
    w[2] = u[0] * v[1] - u[1] * v[0];
  };
  auto dot = [](const double* u, const double* v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  // Argmax over all points of a score.
  auto farthest = [&](auto score) {
    std::size_t best = 0;
    double best_score = -1;
    for (std::size_t i = 0; i < n; ++i) {
      const double s = score(i);
      if (s > best_score) best_score = s, best = i;
    }
    return best;
  };

  double ab[3], ac[3], normal[3], d[3], w[3];
  const std::size_t b = farthest([&](std::size_t i) {
    sub(i, a, d);
    return dot(d, d);
  });
  sub(b, a, ab);
  const std::size_t c = farthest([&](std::size_t i) {
    sub(i, a, d);
    cross(ab, d, w);
    return dot(w, w);
  });
  sub(c, a, ac);
  cross(ab, ac, normal);
  const std::size_t e = farthest([&](std::size_t i) {
    sub(i, a, d);
    return std::fabs(dot(normal, d));
  });
  sub(e, a, d);
  const double orient = std::fabs(dot(normal, d));
  if (!(orient >= 1e-7 * diag * diag * diag)) {
    throw GeometryError(
        "points are nearly coplanar (relative width below 1e-7): TetGen 1.5 cannot "
        "tetrahedralize them reliably");
  }
}


}  // namespace

ReferenceResult tetgen_delaunay(const PointSet& original) {
  // TetGen's internal tolerances are not scale-free (it crashed on points scaled by 1e-200):
  // hand it the points scaled exactly by a power of two to unit size. Ids are unchanged.
  const UnitScaled unit(original);
  const PointSet& points = unit.points();
  const std::size_t n = points.size();
  if (n < 4) throw GeometryError("TetGen: fewer than 4 points, no tetrahedralization");
  if (n > std::size_t(INT_MAX)) {
    throw UsageError("TetGen: too many points (" + std::to_string(n) + "), its ids are int");
  }
  check_finite(points);
  check_not_coplanar(points);
  check_tetgen_can_handle(points);
  const std::vector<std::uint32_t> canon = canonical_point_ids(points);

  // tetgenio's destructor frees its arrays with delete[]: allocate the input with new[].
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = int(n);
  in.pointlist = new REAL[3 * n];
  std::copy(points.xyz.begin(), points.xyz.end(), in.pointlist);

  char switches[] = "zQJF";
  ReferenceResult result;
  Stopwatch clock;
  try {
    tetrahedralize(switches, &in, &out);
  } catch (int code) {
    throw Error("TetGen tetrahedralize failed: " + tetgen_error_text(code) +
                (code == 10 ? " (e.g. points (nearly) coplanar)" : ""));
  } catch (const std::bad_alloc&) {
    throw Error("TetGen tetrahedralize failed: out of memory");
  } catch (const std::exception& e) {
    throw Error(std::string("TetGen tetrahedralize failed: ") + e.what());
  } catch (...) {
    throw Error("TetGen tetrahedralize failed with an unknown exception");
  }
  result.seconds = clock.seconds();

  // With J and z, output point i must be input point i, unchanged: check rather than assume.
  if (out.numberofpoints != int(n) || out.pointlist == nullptr ||
      std::memcmp(out.pointlist, points.xyz.data(), 3 * n * sizeof(double)) != 0) {
    throw Error("TetGen renumbered or moved the input points (expected " + std::to_string(n) +
                ", got " + std::to_string(out.numberofpoints) + ")");
  }
  if (out.numberofcorners != 4 || out.numberoftetrahedra < 0 ||
      (out.numberoftetrahedra > 0 && out.tetrahedronlist == nullptr)) {
    throw Error("TetGen returned an unexpected tetrahedron list");
  }

  // Map to canonical ids and orient positively: det[v1-v0, v2-v0, v3-v0] > 0, which is
  // CGAL::orientation(v0, v1, v2, v3) == POSITIVE (both are positive on (0, e1, e2, e3)).
  const std::size_t m = std::size_t(out.numberoftetrahedra);
  result.tets.resize(4 * m);
  std::vector<bool> used(n, false);
  for (std::size_t t = 0; t < m; ++t) {
    std::uint32_t v[4];
    for (int j = 0; j < 4; ++j) {
      const int id = out.tetrahedronlist[4 * t + j];
      if (id < 0 || std::size_t(id) >= n) {
        throw Error("TetGen returned a tet with an invalid vertex id " + std::to_string(id));
      }
      v[j] = canon[std::size_t(id)];
      used[v[j]] = true;
    }
    const CGAL::Orientation o =
        CGAL::orientation(cgal_point(points, v[0]), cgal_point(points, v[1]),
                          cgal_point(points, v[2]), cgal_point(points, v[3]));
    if (o == CGAL::COPLANAR) {
      throw Error("TetGen returned a flat tet (" + std::to_string(v[0]) + ", " +
                  std::to_string(v[1]) + ", " + std::to_string(v[2]) + ", " +
                  std::to_string(v[3]) + ")");
    }
    if (o == CGAL::NEGATIVE) std::swap(v[0], v[1]);
    std::copy(v, v + 4, result.tets.begin() + std::ptrdiff_t(4 * t));
  }
  result.num_vertices = std::size_t(std::count(used.begin(), used.end(), true));
  return result;
}

bool tetgen_available() { return true; }

}  // namespace kdmesh

#else  // without TetGen

namespace kdmesh {

bool tetgen_available() { return false; }

ReferenceResult tetgen_delaunay(const PointSet&) {
  throw UsageError(without_tetgen_message("the TetGen reference tetrahedralization"));
}

}  // namespace kdmesh

#endif  // KDMESH_WITH_TETGEN

namespace kdmesh {

std::string without_tetgen_message(const std::string& what) {
  return what + " needs TetGen, but this kdmesh was built without TetGen (KDMESH_WITH_TETGEN=OFF)";
}

std::string tetgen_error_text(int code) {
  switch (code) {
    case 1: return "out of memory";
    case 2: return "internal error";
    case 3: return "self-intersection detected";
    case 4: return "very small input feature size";
    case 5: return "two very close input facets";
    case 10: return "input error";
    default: return "error code " + std::to_string(code);
  }
}

}  // namespace kdmesh
