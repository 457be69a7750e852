// kdmesh — per-cell candidate lists of the sizing field's weighted segments, built on first use.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sizing/segment_bvh.h"

namespace kdmesh {

/// The segments' least term at a point, min_i (w_i + g·d(x, s_i)), from a short list per cell
/// instead of a BVH search.
///
/// Over a grid of cubic cells (the sizing field's clear-cell grid), a cell asked 64 times
/// gets a block and its own list: the BVH's collect() over the cell's ball (every segment that
/// can be least somewhere in it, or below the cap). (Until then, and for a cell whose list
/// would exceed 65,535 segments, min_value() returns false and the caller searches the BVH.)
/// The block halves the cell 0-3 times along each axis, so that a finest sub-cell holds about
/// 16 segments. A sub-cell's list is made when it is first needed, by collect_from() its
/// parent's list (a sub-cell's ball lies in its parent's), and holds 16-bit positions in the
/// cell's own list. A point's value is min_of() over its finest sub-cell's list: bit for bit
/// the BVH's min_value(), since the list holds every segment that can be least there and the
/// terms are computed alike.
///
/// On occt_sh2.stl at diag/20 (8,375 thickness, crease and edge segments, 3.7M queries at
/// reach 0) the BVH's search visited about 33 nodes and 26 segments a query; a list holds
/// about 12, and the queries took 1.0 s with the lists' making against 2.1 s (one thread,
/// replayed; docs/performance.md, seventeenth session).
///
/// Blocks and lists live in an arena of reserved address space (`max_bytes`, paged in as
/// written), addressed by 32-bit offsets; when it is full, new blocks and lists are refused
/// (the caller searches the BVH, which gives the same value). Thread-safe: the arena is a
/// bump allocator on an atomic counter, and blocks and lists are published with a
/// compare-and-swap, so whichever thread makes one first, every thread reads the same contents.
class SegmentCells {
 public:
  /// Cells of side `cell`, n[0] x n[1] x n[2] of them (the caller numbers them and gives their
  /// centres); `bvh` must outlive this. `rho_margin` is added to every ball's radius (the caller's
  /// rounding of points to cells); terms at or above `cap` never matter to the caller.
  SegmentCells(const SegmentBvh* bvh, double g, double cap, double cell, const int* n,
               double rho_margin, std::size_t max_bytes);
  ~SegmentCells();
  SegmentCells(const SegmentCells&) = delete;
  SegmentCells& operator=(const SegmentCells&) = delete;

  /// x lies in cell `index` (its centre `centre`): best = min(best, the segments' least term
  /// at x). False, with best untouched, when the cell has no lists (yet, or the arena is full).
  bool min_value(std::size_t index, const double* centre, const double* x, double& best) const;

 private:
  struct Block;
  /// Cells are split into at most 8 x 8 x 8 sub-cells (three levels of halving).
  static constexpr int kMaxLevels = 3;
  const Block* block(std::size_t index, const double* centre) const;
  /// A sub-cell's list: `count` positions in level 0's list. In the arena it is one 32-bit
  /// word (the count), then the 16-bit positions; `at` null means no list.
  struct Positions {
    std::uint32_t count = 0;
    const std::uint16_t* at = nullptr;
  };
  /// The list stored at arena word `offset`.
  Positions positions(std::uint32_t offset) const;
  /// The list of sub-cell j at `level` >= 1, made (with its parents') on first use; no list
  /// when the arena is full.
  Positions list(const Block& b, int level, const int* j) const;
  std::atomic<std::uint32_t>* slots(const Block& b, int level) const;
  /// `words` 32-bit words of the arena (8-byte aligned): their offset, 0 when it is full.
  std::uint32_t take(std::size_t words) const;
  bool full() const;
  double radius(int level) const;

  const SegmentBvh* bvh_ = nullptr;
  double g_ = 0, cap_ = 0, cell_ = 0, rho_margin_ = 0;
  std::size_t cells_ = 0;
  std::uint32_t* arena_ = nullptr;  // reserved address space of words_ words (mmap)
  std::size_t words_ = 0;
  mutable std::atomic<std::size_t> next_{2};      // the arena's first free word (0 means none)
  std::unique_ptr<std::atomic<std::uint32_t>[]> blocks_;  // per cell: its block's offset, or 0
  std::unique_ptr<std::uint8_t[]> asked_;  // per cell: queries before its block (to kWarmup)
};

}  // namespace kdmesh
