// kdmesh — an insertion order: a permutation of point ids plus a locate hint per point.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace kdmesh {

inline constexpr std::uint32_t kNoHint = std::numeric_limits<std::uint32_t>::max();

/// Output of the ordering stage. All arrays are indexed by *rank* k (the k-th inserted point).
///  - order[k]: id of the point inserted k-th. `order` is a permutation of 0..n-1.
///  - hint[k]:  id of an earlier-inserted point to start locating order[k] from
///              (its kd-tree parent for kd orders, the previous point otherwise);
///              kNoHint for k == 0.
///  - level[k]: depth of order[k] in the kd-tree (root = 0); empty for non-kd orders.
struct Ordering {
  std::string name;
  std::vector<std::uint32_t> order;
  std::vector<std::uint32_t> hint;
  std::vector<std::uint8_t> level;

  std::size_t size() const { return order.size(); }
};

}  // namespace kdmesh
