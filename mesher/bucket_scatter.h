// kdmesh — a stable counting sort into buckets, counted and scattered on a few threads.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/cpu_count.h"
#include "core/error.h"
#include "core/parallel_for.h"

namespace kdmesh {

/// Items 0..n-1 go to buckets 0..buckets-1: bucket_of(i) names item i's bucket (called twice
/// per item, from any thread), and place(i, at) puts item i at position `at` of the output.
/// Returns the buckets' start positions (buckets + 1 entries). Stable: within a bucket the
/// items keep their order, so the output is the one-thread counting sort's whatever the
/// thread count. Each contiguous part of the items is counted and scattered on its own thread
/// (one part per 64k items, at most one per core); the counts take parts x buckets x 4 bytes.
/// Throws UsageError from 2^32 items.
template <class BucketOf, class Place>
std::vector<std::size_t> bucket_scatter(std::size_t n, std::size_t buckets, BucketOf&& bucket_of, Place&& place) {
  if (n >= (std::size_t(1) << 32)) throw UsageError("bucket_scatter: 2^32 items or more");
  const std::size_t parts =
      std::clamp<std::size_t>(n / (1 << 16), 1, available_cpus());
  auto part_begin = [&](std::size_t p) { return n * p / parts; };
  // at[p * buckets + b]: part p's items in bucket b, then where the next one goes.
  std::vector<std::uint32_t> at(parts * buckets, 0);
  parallel_for(parts, [&](std::size_t pb, std::size_t pe, unsigned) {
    for (std::size_t p = pb; p < pe; ++p) {
      std::uint32_t* count = &at[p * buckets];
      for (std::size_t i = part_begin(p); i < part_begin(p + 1); ++i) ++count[bucket_of(i)];
    }
  }, 1);
  std::vector<std::size_t> start(buckets + 1, 0);
  for (std::size_t b = 0; b < buckets; ++b) {
    std::size_t next = start[b];
    for (std::size_t p = 0; p < parts; ++p) {
      const std::uint32_t c = at[p * buckets + b];
      at[p * buckets + b] = std::uint32_t(next);
      next += c;
    }
    start[b + 1] = next;
  }
  parallel_for(parts, [&](std::size_t pb, std::size_t pe, unsigned) {
    for (std::size_t p = pb; p < pe; ++p) {
      std::uint32_t* to = &at[p * buckets];
      for (std::size_t i = part_begin(p); i < part_begin(p + 1); ++i) place(i, to[bucket_of(i)]++);
    }
  }, 1);
  return start;
}

}  // namespace kdmesh
