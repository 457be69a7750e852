// kdmesh — kd-bfs-hilbert: the kd-bfs tree, levels and parent hints, each level in Hilbert order.
//
// kd-bfs emits each level of the tree left to right, i.e. in the tree's own in-order, which
// jumps wherever two neighbouring cells sit in different subtrees. On points along three axes
// the root's median plane runs along two of the tubes, and consecutive points of a level
// alternate between far-apart pieces of the domain. Sorting each level by the points' Hilbert
// keys (the `hilbert` order's keys) keeps every property the kernel relies on: the same tree,
// breadth first (a point's parent is on an earlier level, so it is inserted first), the same
// parent hints. Only the visiting order inside a level changes. Not in the paper; measured in
// docs/performance.md ("Each kd level in Hilbert order").
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cstdint>
#include <future>
#include <vector>

#include "mesher/hilbert.h"
#include "mesher/order_kd.h"

namespace kdmesh::detail {

namespace {
/// Inputs at least this large compute their Hilbert keys on a second thread.
constexpr std::size_t kThreadThreshold = std::size_t(1) << 16;
}  // namespace

Ordering make_kd_hilbert_order(const PointSet& points) {
  // The keys are computed beside the tree's first, single-threaded partition. (std::async:
  // an exception reaches get(), and the future waits for its task if the tree throws.)
  const auto launch = points.size() >= kThreadThreshold ? std::launch::async : std::launch::deferred;
  std::future<std::vector<std::uint64_t>> key_task =
      std::async(launch, [&points] { return hilbert::point_keys(points); });
  Ordering bfs = make_kd_order(points, false);
  std::vector<std::uint64_t> keys = key_task.get();
  const std::size_t n = bfs.order.size();
  bfs.name = "kd-bfs-hilbert";
  if (n == 0) return bfs;
  std::vector<std::uint32_t> parent(n);  // by point id
  for (std::size_t k = 0; k < n; ++k) parent[bfs.order[k]] = bfs.hint[k];
  // Levels are contiguous in a breadth-first order; each keeps its place and its size. (Not
  // on a second thread: the sort's buffers, freed in that thread's malloc arena, stayed
  // resident through the Delaunay stage, +15 MB of peak at 1M points.)
  for (std::size_t a = 0; a < n;) {
    std::size_t b = a + 1;
    while (b < n && bfs.level[b] == bfs.level[a]) ++b;
    hilbert::sort_ids_by_key(bfs.order.data() + a, b - a, keys.data());
    a = b;
  }
  std::vector<std::uint64_t>().swap(keys);
  for (std::size_t k = 0; k < n; ++k) bfs.hint[k] = parent[bfs.order[k]];
  return bfs;
}

}  // namespace kdmesh::detail
