// kdmesh — the indices of a range that pass a test, in order, found on a few threads.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/cpu_count.h"
#include "core/parallel_for.h"

namespace kdmesh {

/// The indices i of [0, n) for which take(i) is true, in increasing order (the result of one
/// loop), with take called on up to `max_workers` threads (0 = available_cpus()), each on
/// a contiguous chunk. take(i) may write data of index i only. n must fit in 32 bits.
template <class Take>
std::vector<std::uint32_t> parallel_collect(std::size_t n, Take&& take, std::size_t grain = 65536,
                                            unsigned max_workers = 0) {
  std::vector<std::vector<std::uint32_t>> part(available_cpus());
  parallel_for(n, [&](std::size_t b, std::size_t e, unsigned w) {
    for (std::size_t i = b; i < e; ++i)
      if (take(i)) part[w].push_back(std::uint32_t(i));
  }, grain, max_workers);
  std::size_t total = 0;
  for (const auto& p : part) total += p.size();
  std::vector<std::uint32_t> out;
  out.reserve(total);
  for (const auto& p : part) out.insert(out.end(), p.begin(), p.end());  // chunks in order
  return out;
}

}  // namespace kdmesh
