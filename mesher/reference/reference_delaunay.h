// kdmesh — reference Delaunay tetrahedralizations (TetGen 1.5, CGAL 5.5) behind plain types.
// The third-party types stay in the .cpp adapters.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/ordering.h"
#include "core/point_set.h"

namespace kdmesh {

struct ReferenceResult {
  std::vector<std::uint32_t> tets;  ///< 4 point ids per finite tet, positively oriented
  std::size_t num_vertices = 0;     ///< distinct vertices actually in the triangulation
  double seconds = 0;               ///< time of the triangulation call itself

  /// Predicate counts, summed over all insertions; all 0 unless counting was asked for
  /// (CgalOptions::count; TetGen never counts). See cgal_delaunay for their exact meaning.
  bool counted = false;
  std::uint64_t locate_orient_tests = 0;  ///< Orientation_3 calls made by point location
  std::uint64_t orient_tests = 0;         ///< all Orientation_3 calls (location included)
  std::uint64_t sphere_tests = 0;         ///< Side_of_oriented_sphere_3 calls
  std::uint64_t conflicts = 0;            ///< cells found in conflict (removed by insertions)
};

/// How cgal_delaunay runs. Plain Epick unless `count` is set.
struct CgalOptions {
  /// Count predicates (ReferenceResult's counters). This uses a separate instantiation of
  /// the triangulation, on counting traits, that walks with exact predicates only (see
  /// cgal_delaunay), so its `seconds` are not CGAL's normal speed: time without counting.
  bool count = false;
  /// Stock CGAL, the honest baseline (issue 22): a plain Delaunay_triangulation_3<Epick>, whose
  /// vertices carry no info, inserting a std::vector<Point_3> range (CGAL's own spatial sort).
  /// `seconds` is that insert(first, last) call alone; the point ids of the tets are found
  /// afterwards by looking each vertex's point up. Needs order == nullptr and count off.
  bool plain = false;
};

/// All results use canonical ids (canonical_point_ids: the smallest id of each group of
/// identical points) and positively oriented tets.
///
/// TetGen 1.5 (library) Delaunay tetrahedralization of the points (switches "zQJF": no
/// refinement, input numbering kept). Debian's TetGen 1.5.0 cannot fail cleanly (it aborts or
/// crashes the process), so input it would reject is refused here first with GeometryError:
/// fewer than 4 points, non-finite coordinates, all points coplanar, or a set flatter than
/// TetGen's internal tolerance (relative thickness below ~1e-7 of the bounding-box diagonal).
ReferenceResult tetgen_delaunay(const PointSet& points);

/// Whether this kdmesh was built with TetGen (the CMake option KDMESH_WITH_TETGEN). Without
/// it, tetgen_delaunay throws UsageError with without_tetgen_message; the mesher never needs it.
bool tetgen_available();

/// "<what> needs TetGen, but this kdmesh was built without TetGen (KDMESH_WITH_TETGEN=OFF)":
/// the one message for every TetGen feature asked of a build without it.
std::string without_tetgen_message(const std::string& what);

/// The meaning of a TetGen 1.5 library error code (the int its terminatetetgen throws), for
/// messages: "out of memory", "self-intersection detected", ..., "error code <n>" if unknown.
std::string tetgen_error_text(int code);

/// CGAL Delaunay_triangulation_3 (Epick). With `order`: inserts one point at a time in that
/// order, each located from the vertex of its hint. Without: CGAL's own insert(first, last)
/// (spatial sort). Throws GeometryError when the points span no volume, UsageError for an
/// ordering that is not a permutation.
///
/// With options.count, the points are inserted in the same order on traits derived from Epick
/// whose Orientation_3 and Side_of_oriented_sphere_3 count their calls, with a cell type that
/// counts its removals. Each insertion is CGAL's own insert(p, start), split into its two public
/// halves, locate(p, lt, li, lj, start) then insert(p, lt, c, li, lj), so that:
///  - locate_orient_tests: Orientation_3 calls during location. Plain Epick first walks with
///    inexact double-precision tests outside the traits ("structural filtering") and then
///    confirms with a short exact walk; the counting traits do not enable that filter, so the
///    whole walk (CGAL's remembering stochastic walk from the hint's cell) is made of exact,
///    counted Orientation_3 tests, as in a Delaunay_triangulation_3 on a non-Epick kernel;
///  - orient_tests: every Orientation_3 call of the insertions: location plus the conflict
///    tests of infinite cells and the symbolic-perturbation tie-breaks;
///  - sphere_tests: Side_of_oriented_sphere_3 calls, one per finite cell tested for conflict
///    (the conflict search tests the cavity and its neighbours across the cavity boundary);
///  - conflicts: cells removed by the insertions, i.e. the cells found in conflict (the
///    cavities, infinite cells included), as kdmesh's DelaunayStats::conflicts.
/// The range insertion (order == nullptr) is counted by repeating CGAL's own code: the same
/// spatial_sort of the points, then insertion along it, each located from the previous vertex.
ReferenceResult cgal_delaunay(const PointSet& points, const Ordering* order,
                              const CgalOptions& options = {});

/// Volume of the convex hull of `points`, from CGAL::convex_hull_3 (exact predicates),
/// independent of any tetrahedralization. 0 for fewer than 4 non-coplanar points.
double convex_hull_volume(const PointSet& points);

}  // namespace kdmesh
