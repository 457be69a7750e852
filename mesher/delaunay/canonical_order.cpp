// kdmesh — canonical record order of a Delaunay triangulation (see canonical_order.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/delaunay/canonical_order.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <vector>

#include "core/error.h"
#include "mesher/bucket_scatter.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"

namespace kdmesh {

namespace {

/// The 12 even permutations of (0, 1, 2, 3): new position k takes old vertex kEven[p][k].
constexpr std::uint8_t kEven[12][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 0, 3, 2},
                                       {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 0, 1, 3}, {2, 1, 3, 0},
                                       {2, 3, 0, 1}, {3, 0, 2, 1}, {3, 1, 0, 2}, {3, 2, 1, 0}};

/// kInverse[p][j]: the new position of old vertex j under kEven[p].
constexpr std::array<std::array<std::uint8_t, 4>, 12> inverse_table() {
  std::array<std::array<std::uint8_t, 4>, 12> inv{};
  for (int p = 0; p < 12; ++p)
    for (int k = 0; k < 4; ++k) inv[std::size_t(p)][kEven[p][k]] = std::uint8_t(k);
  return inv;
}
constexpr auto kInverse = inverse_table();

/// kFirstTwo[i][j] (i != j): the even permutation that puts old vertex i first and j second
/// (each such pair begins exactly one of the twelve).
constexpr std::array<std::array<std::uint8_t, 4>, 4> first_two_table() {
  std::array<std::array<std::uint8_t, 4>, 4> t{};
  for (int p = 0; p < 12; ++p) t[kEven[p][0]][kEven[p][1]] = std::uint8_t(p);
  return t;
}
constexpr auto kFirstTwo = first_two_table();

/// Of each set of equal points the stats name, every tet names the one of least rank.
void keep_first_duplicates(Triangulation& tri, const std::vector<std::uint32_t>& rank,
                           DelaunayStats& stats, unsigned threads) {
  std::map<std::uint32_t, std::vector<std::uint32_t>> sets;  // kept vertex -> its repeats
  for (std::size_t i = 0; i < stats.duplicates.size(); ++i)
    sets[stats.duplicate_of[i]].push_back(stats.duplicates[i]);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> dups;  // (duplicate, the one kept)
  std::vector<std::uint32_t> renamed(rank.size(), kInfiniteVertex);  // kept -> least rank
  bool any = false;
  for (auto& [kept, reps] : sets) {
    std::uint32_t first = kept;
    for (const std::uint32_t d : reps)
      if (rank[d] < rank[first]) first = d;
    if (first != kept) renamed[kept] = first, any = true;
    reps.push_back(kept);
    for (const std::uint32_t d : reps)
      if (d != first) dups.emplace_back(d, first);
  }
  std::sort(dups.begin(), dups.end(), [&](const auto& a, const auto& b) { return rank[a.first] < rank[b.first]; });
  stats.duplicates.clear();
  stats.duplicate_of.clear();
  for (const auto& [d, first] : dups) {
    stats.duplicates.push_back(d);
    stats.duplicate_of.push_back(first);
  }
  if (!any) return;
  parallel_for(tri.num_tets(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      for (int i = 0; i < 4; ++i) {
        std::uint32_t& v = tri.v(t, i);
        if (v != kInfiniteVertex && renamed[v] != kInfiniteVertex) v = renamed[v];
      }
  }, 1 << 14, threads);
}

}  // namespace

void canonicalize_triangulation(Triangulation& tri, const Ordering& order, DelaunayStats& stats,
                                unsigned threads) {
  const std::size_t n = order.size(), nt = tri.num_tets();
  if (n >= kInfiniteVertex || nt >= (std::size_t(1) << 30))
    throw UsageError("canonicalize_triangulation: too many points or tets");
  std::vector<std::uint32_t> rank(n, kInfiniteVertex);
  for (std::size_t k = 0; k < n; ++k) {
    if (order.order[k] >= n) throw UsageError("canonicalize_triangulation: order is not a permutation");
    rank[order.order[k]] = std::uint32_t(k);
  }
  if (!stats.duplicates.empty()) keep_first_duplicates(tri, rank, stats, threads);
  const std::uint32_t inf_rank = std::uint32_t(n);
  auto rank_of = [&](std::uint32_t v) { return v == kInfiniteVertex ? inf_rank : rank[v]; };
  // Each tet's rotation, and its last inserted vertex's rank (its bucket). A tet's ranks are
  // distinct (the infinite vertex's is n), so the rotation is the even permutation that puts
  // the least first and the least of the other three second (kFirstTwo).
  // Per-tet arrays written whole by the parallel loops below: left unzeroed, so their pages
  // are first touched on all threads, not by one core's memset (the paper gear box's mesh
  // stage, two calls: its Delaunay steps 6.45, 6.61 s against 6.73, 7.03 s).
  std::vector<std::uint8_t, UninitAllocator<std::uint8_t>> perm(nt);
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> slot(nt);  // the bucket, then the tet's new id
  // The other three ranks, largest first.
  std::vector<std::array<std::uint32_t, 3>, UninitAllocator<std::array<std::uint32_t, 3>>> rest(nt);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      std::uint32_t r[4] = {rank_of(tri.v(t, 0)), rank_of(tri.v(t, 1)), rank_of(tri.v(t, 2)),
                            rank_of(tri.v(t, 3))};
      int i0 = 0;
      for (int k = 1; k < 4; ++k)
        if (r[k] < r[i0]) i0 = k;
      int j0 = i0 == 0 ? 1 : 0;
      for (int k = j0 + 1; k < 4; ++k)
        if (k != i0 && r[k] < r[j0]) j0 = k;
      perm[t] = kFirstTwo[std::size_t(i0)][std::size_t(j0)];
      // Largest first: a sorting network of four.
      auto order2 = [](std::uint32_t& x, std::uint32_t& y) {
        if (x < y) std::swap(x, y);
      };
      order2(r[0], r[1]), order2(r[2], r[3]), order2(r[0], r[2]), order2(r[1], r[3]), order2(r[1], r[2]);
      slot[t] = r[0];
      rest[t] = {r[1], r[2], r[3]};
    }
  }, 1 << 14, threads);

  // Counting sort by the last vertex (ranks 0..n, n = infinite), stable, then each bucket by
  // the other three ranks, largest first (distinct tets differ in some rank), and each tet's
  // new id. The buckets are taken in order, so the other ranks of the tets 16 places ahead
  // are requested while a bucket is sorted (carrying them through the scatter in 16-byte
  // records instead took 12 bytes a tet more at the peak, for the same time).
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> sorted(nt);
  const std::vector<std::size_t> start = bucket_scatter(
      nt, n + 1, [&](std::size_t t) { return slot[t]; },
      [&](std::size_t t, std::size_t at) { sorted[at] = std::uint32_t(t); });
  struct Rec {
    std::array<std::uint32_t, 3> rest;
    std::uint32_t tet;
  };
  // Blocks of buckets taken by free workers: the buckets' sizes follow the order's levels,
  // and one half of the ranks each kept the paper gear box's second core idle 0.5-0.75 s.
  parallel_blocks(n + 1, 1 << 12, [&](std::size_t b, std::size_t e, unsigned) {
    std::vector<Rec> bucket;
    const std::size_t end = start[e];
    auto before = [](const Rec& x, const Rec& y) { return x.rest > y.rest; };
    for (std::size_t r = b; r < e; ++r) {
      const std::size_t k0 = start[r], k1 = start[r + 1];
      bucket.clear();
      for (std::size_t k = k0; k < k1; ++k) {
        if (k + 16 < end) {
          __builtin_prefetch(&rest[sorted[k + 16]]);
          __builtin_prefetch(&slot[sorted[k + 16]], 1);
        }
        bucket.push_back({rest[sorted[k]], sorted[k]});
      }
      if (bucket.size() > 16) {
        std::sort(bucket.begin(), bucket.end(), before);
      } else {
        for (std::size_t x = 1; x < bucket.size(); ++x)  // a few tets: insertion
          for (std::size_t y = x; y > 0 && before(bucket[y], bucket[y - 1]); --y)
            std::swap(bucket[y], bucket[y - 1]);
      }
      for (std::size_t i = 0; i < bucket.size(); ++i) {
        sorted[k0 + i] = bucket[i].tet;
        slot[bucket[i].tet] = std::uint32_t(k0 + i);
      }
    }
  }, threads);

  // The records in their new order, turned, with their face references renamed. Each tet's
  // record is requested 16 ahead, its neighbours' new ids and rotations 8 ahead.
  TetRecords out;
  // The same capacity as the kernel's records (untouched, it costs no memory): a later
  // delaunay_insert then adds its tets without copying the records.
  out.reserve(tri.data.capacity());
  out.resize(tri.data.size());
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      if (k + 16 < e) __builtin_prefetch(&tri.data[8 * std::size_t(sorted[k + 16]) + 4]);
      if (k + 8 < e)
        for (int i = 0; i < 4; ++i) {
          const std::uint32_t u = tri.adj(sorted[k + 8], i) >> 2;
          __builtin_prefetch(&slot[u]);
          __builtin_prefetch(&perm[u]);
        }
      const std::size_t t = sorted[k];
      const std::uint8_t* P = kEven[perm[t]];
      std::uint32_t* o = &out[8 * k];
      for (int i = 0; i < 4; ++i) {
        o[i] = tri.v(t, P[i]);
        const std::uint32_t a = tri.adj(t, P[i]), u = a >> 2;
        o[4 + i] = 4 * slot[u] + kInverse[perm[u]][a & 3];
      }
    }
  }, 1 << 14, threads);
  tri.data.swap(out);
}

}  // namespace kdmesh
