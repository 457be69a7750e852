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
  // Each tet's rotation, and its last inserted vertex's rank (its bucket).
  std::vector<std::uint8_t> perm(nt);
  std::vector<std::uint32_t> slot(nt);  // the bucket, then the tet's new id
  std::vector<std::array<std::uint32_t, 3>> rest(nt);  // the other three ranks, largest first
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      const std::uint32_t r[4] = {rank_of(tri.v(t, 0)), rank_of(tri.v(t, 1)), rank_of(tri.v(t, 2)),
                                  rank_of(tri.v(t, 3))};
      int best = 0;
      for (int p = 1; p < 12; ++p) {
        const std::uint8_t* P = kEven[p];
        const std::uint8_t* B = kEven[best];
        if (r[P[0]] < r[B[0]] || (r[P[0]] == r[B[0]] && r[P[1]] < r[B[1]])) best = p;
      }
      perm[t] = std::uint8_t(best);
      std::array<std::uint32_t, 4> d{r[0], r[1], r[2], r[3]};
      std::sort(d.begin(), d.end(), std::greater<>());
      slot[t] = d[0];
      rest[t] = {d[1], d[2], d[3]};
    }
  }, 1 << 14, threads);

  // Counting sort by the last vertex (ranks 0..n, n = infinite), stable, then each bucket by
  // the other three ranks, largest first (distinct tets differ in some rank).
  std::vector<std::uint32_t> sorted(nt);
  const std::vector<std::size_t> start = bucket_scatter(
      nt, n + 1, [&](std::size_t t) { return slot[t]; },
      [&](std::size_t t, std::size_t at) { sorted[at] = std::uint32_t(t); });
  parallel_for(n + 1, [&](std::size_t b, std::size_t e, unsigned) {
    std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> bucket;
    for (std::size_t r = b; r < e; ++r) {
      if (start[r + 1] - start[r] < 2) continue;
      bucket.clear();
      for (std::size_t k = start[r]; k < start[r + 1]; ++k) bucket.emplace_back(rest[sorted[k]], sorted[k]);
      std::sort(bucket.begin(), bucket.end(), [](const auto& a, const auto& c) { return a.first > c.first; });
      for (std::size_t k = start[r]; k < start[r + 1]; ++k) sorted[k] = bucket[k - start[r]].second;
    }
  }, 1 << 12, threads);
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) slot[sorted[k]] = std::uint32_t(k);
  }, 1 << 14, threads);

  // The records in their new order, turned, with their face references renamed.
  TetRecords out;
  // The same capacity as the kernel's records (untouched, it costs no memory): a later
  // delaunay_insert then adds its tets without copying the records.
  out.reserve(tri.data.capacity());
  out.resize(tri.data.size());
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
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
