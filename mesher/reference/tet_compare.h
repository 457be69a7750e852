// kdmesh — compare two tetrahedralizations of the same points by their invariants.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

struct TetComparison {
  std::size_t tets_a = 0, tets_b = 0;
  double volume_a = 0, volume_b = 0;   ///< sums of tet volumes (compensated summation)
  std::size_t only_in_a = 0, only_in_b = 0;  ///< tets (as vertex sets) present in one only
  std::vector<std::uint32_t> example_only_a, example_only_b;  ///< up to 5 tets each, 4 sorted ids per tet
  bool same_count() const { return tets_a == tets_b; }
  bool same_set() const { return only_in_a == 0 && only_in_b == 0 && same_count(); }
};

/// For each point i, the smallest id j with coordinates equal to point i's (j == i if point i
/// is unique). Coordinates are compared by value (so -0.0 == +0.0), as the exact predicates of
/// every Delaunay kernel see them. Expected O(n) (hashing). Tet lists compared across kernels
/// are expressed in these canonical ids, so that each kernel's choice of duplicate is irrelevant.
std::vector<std::uint32_t> canonical_point_ids(const PointSet& points);

/// Tets are compared as unordered vertex sets. Volume uses |orient| of each tet.
TetComparison compare_tets(const PointSet& points, const std::vector<std::uint32_t>& a,
                           const std::vector<std::uint32_t>& b);

/// Sum of the volumes of tets (4 ids each), Kahan-compensated in long double.
double total_volume(const PointSet& points, const std::vector<std::uint32_t>& tets);

}  // namespace kdmesh
