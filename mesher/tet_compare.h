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
  std::vector<std::uint32_t> example_only_a, example_only_b;  ///< up to 5 tets each, 4 ids per tet
  bool same_count() const { return tets_a == tets_b; }
  bool same_set() const { return only_in_a == 0 && only_in_b == 0 && same_count(); }
};

/// Tets are compared as unordered vertex sets. Volume uses |orient| of each tet.
TetComparison compare_tets(const PointSet& points, const std::vector<std::uint32_t>& a,
                           const std::vector<std::uint32_t>& b);

/// Sum of the volumes of tets (4 ids each), Kahan-compensated in long double.
double total_volume(const PointSet& points, const std::vector<std::uint32_t>& tets);

}  // namespace kdmesh
