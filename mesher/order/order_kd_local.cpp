// kdmesh — kd-local: the kd-bfs tree inserted subtree by subtree below a cache-sized level.
//
// kd-bfs spreads every level over the whole domain, so at large n each insertion lands in a
// region whose tets were last touched a full sweep earlier (cold in cache). kd-local keeps the
// paper's tree, hints and the breadth-first order inside each block, but once the subtrees
// are small (<= subtree_points points) it finishes one subtree before starting the next.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cstdint>
#include <vector>

#include "mesher/order/order_kd.h"

namespace kdmesh::detail {

Ordering make_kd_local_order(Ordering bfs, std::size_t subtree_points) {
  const std::size_t n = bfs.order.size();
  if (n == 0) return bfs;
  // Block level L0: the first level at which every subtree has at most subtree_points points.
  // A node at depth d of a median-split tree over n points roots at most n / 2^d points.
  int block_level = 0;
  while ((n >> block_level) > subtree_points) ++block_level;

  // group[k]: for a node at the block level, its own rank; deeper nodes inherit their
  // parent's group (parents come earlier in BFS order); shallower nodes have none.
  constexpr std::uint32_t kTop = 0xFFFFFFFFu;
  std::vector<std::uint32_t> rank_of(n);
  for (std::size_t k = 0; k < n; ++k) rank_of[bfs.order[k]] = std::uint32_t(k);
  std::vector<std::uint32_t> group(n, kTop);
  std::vector<std::uint32_t> block_index(n, 0);  // block number of a block-level rank
  std::uint32_t blocks = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (bfs.level[k] == block_level) {
      group[k] = std::uint32_t(k);
      block_index[k] = blocks++;
    } else if (bfs.level[k] > block_level) {
      group[k] = group[rank_of[bfs.hint[k]]];
    }
  }
  // Counting sort, stable: the top levels first (BFS), then block by block (BFS inside).
  std::vector<std::uint32_t> start(std::size_t(blocks) + 2, 0);
  for (std::size_t k = 0; k < n; ++k) ++start[group[k] == kTop ? 0 : block_index[group[k]] + 1];
  std::uint32_t sum = 0;
  for (auto& s : start) {
    const std::uint32_t c = s;
    s = sum;
    sum += c;
  }
  Ordering out;
  out.name = "kd-local";
  out.order.resize(n);
  out.hint.resize(n);
  out.level.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t dst = start[group[k] == kTop ? 0 : block_index[group[k]] + 1]++;
    out.order[dst] = bfs.order[k];
    out.hint[dst] = bfs.hint[k];
    out.level[dst] = bfs.level[k];
  }
  return out;
}

}  // namespace kdmesh::detail
