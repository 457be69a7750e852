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
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <future>
#include <utility>
#include <vector>

#include "mesher/order/hilbert.h"
#include "mesher/order/order_kd.h"

namespace kdmesh::detail {

namespace {
/// Inputs at least this large compute their Hilbert keys on a second thread.
constexpr std::size_t kThreadThreshold = std::size_t(1) << 16;

/// Sorts one level, ids[0..m), by (keys[id] >> (b - 1), position in ids), b = the bits of a
/// position (at least 1): each record is one 64-bit word, the 63-bit key's top 64 - b bits
/// over the position, so the records are distinct and their order is that order. Levels of
/// 256 records and more are sorted by an LSD radix sort of the key bits only, in digits of at
/// most 12 bits: it is stable and the records start in position order, so positions need no
/// pass of their own. At 1M points the keys keep 45 bits (15 per axis), sorted in 4 passes
/// over 8-byte records, where 63-bit keys with ids took 6 over 16-byte ones. The level's
/// hints move with their ids. `a` and `tmp` are scratch space of at least m words.
void sort_level(std::uint32_t* ids, std::uint32_t* hints, std::size_t m, const std::uint64_t* keys,
                std::vector<std::uint64_t>& a, std::vector<std::uint64_t>& tmp) {
  const int b = std::max(1, int(std::bit_width(m - 1)));
  for (std::size_t i = 0; i < m; ++i) a[i] = (keys[ids[i]] >> (b - 1)) << b | i;
  if (m < 256) {
    std::sort(a.begin(), a.begin() + std::ptrdiff_t(m));
  } else {
    const int key_bits = 64 - b;
    const int passes = (key_bits + 11) / 12;
    const int digit = (key_bits + passes - 1) / passes;  // <= 12
    const std::uint64_t digit_mask = (std::uint64_t(1) << digit) - 1;
    std::array<std::uint32_t, 4096> count;
    for (int lo = b; lo < 64; lo += digit) {
      count.fill(0);
      for (std::size_t i = 0; i < m; ++i) ++count[(a[i] >> lo) & digit_mask];
      std::uint32_t sum = 0;
      for (std::uint32_t& c : count) sum += std::exchange(c, sum);
      for (std::size_t i = 0; i < m; ++i) tmp[count[(a[i] >> lo) & digit_mask]++] = a[i];
      a.swap(tmp);
    }
  }
  const std::uint64_t mask = (std::uint64_t(1) << b) - 1;
  for (std::size_t i = 0; i < m; ++i) tmp[i] = std::uint64_t(ids[i]) << 32 | hints[i];
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint64_t was = tmp[a[i] & mask];
    ids[i] = std::uint32_t(was >> 32);
    hints[i] = std::uint32_t(was);
  }
}
}  // namespace

Ordering make_kd_hilbert_order(const PointSet& points, unsigned threads) {
  // The keys are computed beside the tree's first, single-threaded partition. (std::async:
  // an exception reaches get(), and the future waits for its task if the tree throws.)
  const auto launch = threads != 1 && points.size() >= kThreadThreshold ? std::launch::async
                                                                       : std::launch::deferred;
  std::future<std::vector<std::uint64_t>> key_task =
      std::async(launch, [&points] { return hilbert::point_keys(points); });
  Ordering bfs = make_kd_order(points, false, threads);
  std::vector<std::uint64_t> keys = key_task.get();
  const std::size_t n = bfs.order.size();
  bfs.name = "kd-bfs-hilbert";
  if (n == 0) return bfs;
  // Levels are contiguous in a breadth-first order; each keeps its place and its size. (Not
  // on a second thread: the sort's buffers, freed in that thread's malloc arena, stayed
  // resident through the Delaunay stage, +15 MB of peak at 1M points.)
  {
    std::vector<std::size_t> start;  // each level's first rank, then n
    std::size_t largest = 0;         // the largest level: the scratch space
    for (std::size_t k = 0; k < n; ++k)
      if (k == 0 || bfs.level[k] != bfs.level[k - 1]) start.push_back(k);
    start.push_back(n);
    for (std::size_t l = 0; l + 1 < start.size(); ++l) largest = std::max(largest, start[l + 1] - start[l]);
    std::vector<std::uint64_t> a(largest), tmp(largest);
    for (std::size_t l = 0; l + 1 < start.size(); ++l)
      sort_level(bfs.order.data() + start[l], bfs.hint.data() + start[l], start[l + 1] - start[l],
                 keys.data(), a, tmp);
  }
  return bfs;
}

}  // namespace kdmesh::detail
