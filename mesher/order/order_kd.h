// kdmesh — the kd-tree breadth-first orders (private to mesher/; public entry: make_order).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/ordering.h"
#include "core/point_set.h"

namespace kdmesh::detail {

/// The kd-tree breadth-first order of the paper (cut-longest-edge rule), or with
/// `alternate` the x/y/z-alternating rule. Defined in order_kd.cpp.
/// With `threads` 1 everything runs on the calling thread (OrderOptions::threads).
Ordering make_kd_order(const PointSet& points, bool alternate, unsigned threads = 0);

/// Reorders a kd-bfs ordering (with its levels and parent hints) so that, below the first
/// level whose subtrees hold at most `subtree_points` points, each subtree is inserted as one
/// block (breadth-first inside it), subtrees left to right. Defined in order_kd_local.cpp.
Ordering make_kd_local_order(Ordering bfs, std::size_t subtree_points);

/// The kd-bfs order (make_kd_order(points, false)) reordered inside each level by Hilbert key
/// (hilbert::point_keys, truncated to leave room for the position; ties in kd-bfs order),
/// every point keeping its level and parent hint. Defined in order_kd_hilbert.cpp.
Ordering make_kd_hilbert_order(const PointSet& points, unsigned threads = 0);

}  // namespace kdmesh::detail
