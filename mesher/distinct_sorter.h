// kdmesh — the distinct values of a small group, sorted: std::sort + std::unique, faster on
// small groups with many repeats.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

namespace kdmesh {

/// Puts the distinct values of a[0..m) in ascending order at a[0..k) and returns k, as
/// std::sort then std::unique do (what lies past k is unspecified). A group of at most 128
/// values goes through an open-addressing table of 256 slots, and only its distinct values
/// are sorted; a larger one is sorted whole. Sorting a vertex's 34 edge ends (each edge comes
/// once from each of its ~5 tets) spent most of its time in mispredicted comparisons: on the
/// paper gear box, 4.2M such groups took 2.7 s on two threads. One object per thread (it holds
/// the table, empty between calls).
class DistinctSorter {
 public:
  DistinctSorter() { table_.fill(kEmpty); }

  std::size_t operator()(std::uint32_t* a, std::size_t m) {
    if (m <= kMaxHashed) {
      std::size_t k = 0;
      bool marker = false;  // kEmpty, which marks a free slot, is in the group
      for (std::size_t i = 0; i < m; ++i) {
        const std::uint32_t x = a[i];
        marker |= x == kEmpty;
        std::uint32_t h = (x * 2654435761u) >> 24;  // Fibonacci hashing into 256 slots
        while (table_[h] != x && table_[h] != kEmpty) h = (h + 1) & 255;
        if (table_[h] == kEmpty) {
          table_[h] = x;
          slot_[k] = std::uint8_t(h);
          distinct_[k++] = x;
        }
      }
      for (std::size_t j = 0; j < k; ++j) table_[slot_[j]] = kEmpty;
      if (!marker) {
        for (std::size_t j = 1; j < k; ++j) {  // insertion sort: k is small
          const std::uint32_t x = distinct_[j];
          std::size_t i = j;
          for (; i > 0 && distinct_[i - 1] > x; --i) distinct_[i] = distinct_[i - 1];
          distinct_[i] = x;
        }
        std::copy(distinct_.begin(), distinct_.begin() + std::ptrdiff_t(k), a);
        return k;
      }
    }
    std::sort(a, a + m);
    return std::size_t(std::unique(a, a + m) - a);
  }

 private:
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
  static constexpr std::size_t kMaxHashed = 128;
  std::array<std::uint32_t, 256> table_;
  std::array<std::uint32_t, kMaxHashed> distinct_;
  std::array<std::uint8_t, kMaxHashed> slot_;
};

}  // namespace kdmesh
