// kdmesh — insertion orders (pipeline stage: PointSet -> Ordering).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/ordering.h"
#include "core/point_set.h"

namespace kdmesh {

enum class OrderKind {
  kd_bfs,      ///< paper: kd-tree, cut-longest-edge rule, breadth-first; hint = kd parent
  kd_bfs_alt,  ///< same tree with the alternating x/y/z split rule (paper's ablation)
  kd_bfs_hilbert,  ///< kd_bfs's tree, levels and parent hints; each level in Hilbert order
                   ///< instead of left to right (not in the paper)
  hilbert,     ///< Hilbert curve order; hint = previous point
  brio,        ///< BRIO rounds of ratio 1/8, each Hilbert-sorted; hint = previous point
  kd_local,    ///< same kd tree and hints as kd_bfs; breadth-first down to the level whose
               ///< subtrees hold <= local_points points, then each subtree breadth-first in
               ///< turn, left to right (keeps each subtree's work in cache; not in the paper)
  random,      ///< seeded uniform shuffle; hint = previous point
  input,       ///< identity; hint = previous point
};

struct OrderOptions {
  OrderKind kind = OrderKind::kd_bfs_hilbert;
  std::uint64_t seed = 1;      ///< for random and brio
  double brio_ratio = 0.125;   ///< fraction of points in each round relative to the next
  std::size_t local_points = 4096;  ///< kd_local: largest subtree inserted as one block
  /// 1: the kd orders are built on the calling thread alone; otherwise inputs of 64k points
  /// and more use a second thread (copy, the two halves below the root, Hilbert keys). The
  /// order is the same either way.
  unsigned threads = 0;
};

/// Builds the insertion order of `points`. Deterministic for given points and options.
Ordering make_order(const PointSet& points, const OrderOptions& options);

/// "kd-bfs", "kd-bfs-alt", "kd-bfs-hilbert", "kd-local", "hilbert", "brio", "random", "input".
/// Throws UsageError otherwise.
OrderKind parse_order_kind(std::string_view name);
std::string_view order_kind_name(OrderKind kind);
std::vector<std::string> order_kind_names();

}  // namespace kdmesh
