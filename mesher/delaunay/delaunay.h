// kdmesh — incremental Bowyer–Watson Delaunay tetrahedralization
// (pipeline stage: PointSet + Ordering -> Triangulation).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/ordering.h"
#include "core/point_set.h"
#include "core/tet_mesh.h"

namespace kdmesh {

struct DelaunayOptions {
  /// Called now and then with the fraction of points inserted (0..1]; may be empty.
  std::function<void(double)> progress;
  /// Inserting threads: 1 = sequential, 0 = one per CPU the process may use (available_cpus).
  /// Any count gives the same tets (in a different order); runs with the same count are
  /// identical, counts included.
  /// Below ~40k points the kernel runs sequentially whatever this says. At most 256
  /// (UsageError otherwise).
  unsigned threads = 1;
};

/// Bins of DelaunayStats' walk histogram: bin 0 holds the walks of 0 orientation tests, bin
/// b >= 1 those of [2^(b-1), 2^b) tests, and the last bin every walk of 2^(kWalkBins-2) = 1024
/// tests or more.
inline constexpr std::size_t kWalkBins = 12;

struct DelaunayStats {
  std::uint64_t inserted = 0;       ///< points in the triangulation
  std::uint64_t orient_tests = 0;   ///< orientation tests during point location (paper's count)
  /// Point locations (walks) by their orientation tests, binned as kWalkBins says: the walks
  /// in each bin and their tests. A mean hides a heavy tail: on 37.5k axes points 2% of the
  /// walks make a quarter of the tests. Sum of walk_tests == orient_tests; a point a parallel
  /// worker defers is located again later, so there may be more walks than points.
  std::array<std::uint64_t, kWalkBins> walks{}, walk_tests{};
  std::uint64_t conflicts = 0;      ///< conflicting tets summed over all insertions (paper's count)
  std::uint64_t exact_fallbacks = 0;  ///< predicate calls the float filter could not decide
  std::vector<std::uint32_t> duplicates;    ///< ids of points skipped as exact duplicates ...
  std::vector<std::uint32_t> duplicate_of;  ///< ... and the id of the vertex each one repeats
  unsigned threads = 1;             ///< inserting threads the run was given (options resolved)
  unsigned parallel_rounds = 0;     ///< rounds on several threads (0: sequential run)
  std::uint64_t deferrals = 0;      ///< times a parallel worker put a point off to a later round
  double seconds = 0;               ///< wall time of the whole insertion
};

struct DelaunayResult {
  Triangulation tri;  ///< the full triangulation (infinite tets included), original point ids
  DelaunayStats stats;
};

/// Delaunay tetrahedralization of `points`, inserting them in `order` and locating each from
/// its hint. Exact predicates with symbolic perturbation: the result is a Delaunay
/// tetrahedralization of the points; cospherical ties are broken consistently (independent of
/// the order), so every order yields the same tets.
/// Throws GeometryError for empty input or input with no 4 non-coplanar points,
/// UsageError if `order` is not a permutation of the points or has too many points.
DelaunayResult delaunay(const PointSet& points, const Ordering& order,
                        const DelaunayOptions& options = {});

/// Inserts more points into a Delaunay triangulation (e.g. Steiner points).
///  - tri:    a Triangulation from delaunay() (or this function) whose vertex ids index `points`
///  - points: every point, those already in `tri` at the same ids and the new ones
///  - ids:    the points to insert, in this order
///  - hints:  per inserted point, a point id already in the triangulation to start locating
///            from (e.g. a vertex of the face being repaired), or kNoHint
/// Adds to `stats` (inserted, orient_tests, walks, conflicts, duplicates, seconds). The result is the
/// Delaunay tetrahedralization of all points, under the same tie-breaking as delaunay().
/// Throws UsageError for out-of-range ids or a mismatched triangulation.
void delaunay_insert(Triangulation& tri, const PointSet& points,
                     const std::vector<std::uint32_t>& ids,
                     const std::vector<std::uint32_t>& hints, DelaunayStats& stats);

/// The finite tets of `tri`, 4 point ids each, positively oriented.
std::vector<std::uint32_t> finite_tets(const Triangulation& tri);

/// How many tets of `tri` are finite (no copy).
std::size_t count_finite_tets(const Triangulation& tri);

}  // namespace kdmesh
