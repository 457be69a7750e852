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
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "core/uninit_allocator.h"
#include "mesher/order/hilbert.h"
#include "mesher/order/order_kd.h"

namespace kdmesh::detail {

namespace {
/// Inputs at least this large compute their Hilbert keys and sort half the levels on a second
/// thread.
constexpr std::size_t kThreadThreshold = std::size_t(1) << 16;

/// Scratch space, written before it is read: no zeroing pass.
using Scratch = std::vector<std::uint64_t, UninitAllocator<std::uint64_t>>;

/// Sorts one level, ids[0..m), by (keys[id] >> (b - 1), position in ids), b = the bits of a
/// position (at least 1): each record is one 64-bit word, the 63-bit key's top 64 - b bits
/// over the position, so the records are distinct and their order is that order. Levels of
/// 256 records and more are sorted by an LSD radix sort of the key bits only, in digits of at
/// most 12 bits: it is stable and the records start in position order, so positions need no
/// pass of their own. At 1M points the keys keep 45 bits (15 per axis), sorted in 4 passes
/// over 8-byte records, where 63-bit keys with ids took 6 over 16-byte ones. The level's
/// hints move with their ids. `a` and `tmp` are scratch space of at least m words.
void sort_level(std::uint32_t* ids, std::uint32_t* hints, std::size_t m, const std::uint64_t* keys,
                Scratch& a, Scratch& tmp) {
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
  // (async | deferred: where no thread can be started, the keys are computed at get().)
  const auto launch = threads != 1 && points.size() >= kThreadThreshold
                          ? std::launch::async | std::launch::deferred
                          : std::launch::deferred;
  std::future<std::vector<std::uint64_t>> key_task =
      std::async(launch, [&points] { return hilbert::point_keys(points); });
  Ordering bfs = make_kd_order(points, false, threads);
  std::vector<std::uint64_t> keys = key_task.get();
  const std::size_t n = bfs.order.size();
  bfs.name = "kd-bfs-hilbert";
  if (n == 0) return bfs;
  // Levels are contiguous in a breadth-first order; each keeps its place and its size. Large
  // inputs sort them on two threads, in two groups of about equal total size (largest level
  // first, each to the lighter group); the levels are independent, so the result is a serial
  // run's. The scratch space is allocated and freed here: freed in a second thread's malloc
  // arena, the sort's buffers stayed resident through the Delaunay stage (+15 MB of peak at
  // 1M points).
  {
    std::vector<std::size_t> start;  // each level's first rank, then n
    for (std::size_t k = 0; k < n; ++k)
      if (k == 0 || bfs.level[k] != bfs.level[k - 1]) start.push_back(k);
    start.push_back(n);
    const std::size_t levels = start.size() - 1;
    auto size = [&](std::size_t l) { return start[l + 1] - start[l]; };
    std::vector<std::size_t> by_size(levels);
    for (std::size_t l = 0; l < levels; ++l) by_size[l] = l;
    std::stable_sort(by_size.begin(), by_size.end(),
                     [&](std::size_t a, std::size_t b) { return size(a) > size(b); });
    const int groups = threads != 1 && n >= kThreadThreshold ? 2 : 1;
    std::array<std::vector<std::size_t>, 2> group;
    std::array<std::size_t, 2> load = {0, 0}, largest = {0, 0};
    for (std::size_t l : by_size) {
      const int g = groups == 2 && load[1] < load[0] ? 1 : 0;
      group[g].push_back(l);
      load[g] += size(l);
      largest[g] = std::max(largest[g], size(l));
    }
    std::array<Scratch, 2> a, tmp;  // scratch of each group
    for (int g = 0; g < groups; ++g) {
      a[g].resize(largest[g]);
      tmp[g].resize(largest[g]);
    }
    auto sort_group = [&](int g) {
      for (std::size_t l : group[g])
        sort_level(bfs.order.data() + start[l], bfs.hint.data() + start[l], size(l), keys.data(),
                   a[g], tmp[g]);
    };
    bool sorted = false;
    if (groups == 2) {
      try {
        std::thread second(sort_group, 1);  // sort_level() allocates nothing and cannot throw
        sort_group(0);
        second.join();
        sorted = true;
      } catch (const std::system_error&) {
        // No thread available (thrown before either group was sorted): sort both here.
      }
    }
    if (!sorted)
      for (int g = 0; g < groups; ++g) sort_group(g);
  }
  return bfs;
}

}  // namespace kdmesh::detail
