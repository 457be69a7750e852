// kdmesh — per-cell candidate lists of the sizing field's weighted segments
// (sizing/segment_cells.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/segment_cells.h"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>
#include <vector>

namespace kdmesh {

namespace {
/// A finest sub-cell's list is aimed at about this many segments.
constexpr std::size_t kTarget = 16;
/// A cell asked fewer times than this is left to the BVH (its lists would not pay for
/// themselves). Measured with an earlier layout of the lists (one heap vector each), 64
/// against none took the job's peak growth from 37 to 15 MB on retinal.ply at diag/40 at the
/// same speed, and from 47 to 31 MB on turbine.ply at diag/40, 2 % faster.
constexpr std::uint8_t kWarmup = 64;
/// A cell whose own list is longer is left to the BVH: a sub-cell's list holds 16-bit
/// positions in it.
constexpr std::size_t kMaxWhole = 65535;
/// asked_'s mark of such a cell.
constexpr std::uint8_t kRefused = 255;
}  // namespace

/// A cell's lists, in the arena (trivially destructible). Level l has (2^l)^3 list slots, x
/// fastest, made on first use from their parent's list at level l - 1 (a sub-cell's ball lies
/// in its parent's, so the parent's list holds every segment it could need, and filtering a
/// list about 3x as long is cheaper than a search from the tree's root). Level 0 is the cell's
/// own list (its count, then segment ids), made with the block; a list of level 1 or more is
/// its count, then 16-bit positions in level 0's list.
struct SegmentCells::Block {
  std::uint32_t levels = 0;  // the cell is halved `levels` times along each axis
  std::uint32_t slots[kMaxLevels + 1] = {};  // arena offsets of each level's slots
  double corner[3] = {0, 0, 0};
};

SegmentCells::SegmentCells(const SegmentBvh* bvh, double g, double cap, double cell, const int* n,
                           double rho_margin, std::size_t max_bytes)
    : bvh_(bvh), g_(g), cap_(cap), cell_(cell), rho_margin_(rho_margin) {
  cells_ = std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]);
  blocks_.reset(new std::atomic<std::uint32_t>[cells_]);
  for (std::size_t i = 0; i < cells_; ++i) blocks_[i].store(0, std::memory_order_relaxed);
  asked_.reset(new std::uint8_t[cells_]());
  // The arena: address space for max_bytes (at most 2^32 words, its offsets' range), whose
  // pages the system provides when first written. Without it every cell uses the BVH.
  const std::size_t words = std::min(max_bytes / 4, std::size_t(0xffffffffu));
  if (words >= 64) {
    void* p = mmap(nullptr, words * 4, PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p != MAP_FAILED) {
      arena_ = static_cast<std::uint32_t*>(p);
      words_ = words;
    }
  }
}

SegmentCells::~SegmentCells() {
  if (arena_) munmap(arena_, words_ * 4);
}

std::uint32_t SegmentCells::take(std::size_t words) const {
  words = (words + 1) & ~std::size_t(1);  // 8-byte pieces (the blocks hold doubles)
  const std::size_t at = next_.fetch_add(words, std::memory_order_relaxed);
  return at + words <= words_ ? std::uint32_t(at) : 0;  // (0 is never given: next_ starts at 2)
}

bool SegmentCells::full() const { return next_.load(std::memory_order_relaxed) >= words_; }

double SegmentCells::radius(int level) const {
  // Half the diagonal, with the caller's margin (a point rounded into its cell).
  return 0.5 * std::sqrt(3.0) * std::ldexp(cell_, -level) * (1 + 1e-6) + rho_margin_;
}

std::atomic<std::uint32_t>* SegmentCells::slots(const Block& b, int level) const {
  return reinterpret_cast<std::atomic<std::uint32_t>*>(arena_ + b.slots[level]);
}

const SegmentCells::Block* SegmentCells::block(std::size_t index, const double* centre) const {
  if (const std::uint32_t at = blocks_[index].load(std::memory_order_acquire))
    return reinterpret_cast<const Block*>(arena_ + at);
  std::atomic_ref<std::uint8_t> asked(asked_[index]);
  const std::uint8_t times = asked.load(std::memory_order_relaxed);
  if (times < kWarmup) {
    asked.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  if (times == kRefused || full()) return nullptr;
  thread_local std::vector<std::uint32_t> whole;
  whole.clear();
  bvh_->collect(centre, radius(0), g_, cap_, whole);
  if (whole.size() > kMaxWhole) {
    asked.store(kRefused, std::memory_order_relaxed);
    return nullptr;
  }
  std::uint32_t levels = 0;
  while (levels < kMaxLevels && whole.size() > (kTarget << levels)) ++levels;
  std::size_t words = (sizeof(Block) + 3) / 4;
  for (std::uint32_t l = 0; l <= levels; ++l) words += std::size_t(1) << (3 * l);
  const std::uint32_t at = take(words), list = take(1 + whole.size());
  if (!at || !list) return nullptr;
  Block* b = new (arena_ + at) Block;
  b->levels = levels;
  for (int a = 0; a < 3; ++a) b->corner[a] = centre[a] - 0.5 * cell_;
  std::uint32_t next = at + std::uint32_t((sizeof(Block) + 3) / 4);
  for (std::uint32_t l = 0; l <= levels; ++l) {
    b->slots[l] = next;
    const std::size_t n = std::size_t(1) << (3 * l);
    for (std::size_t s = 0; s < n; ++s) new (arena_ + next + s) std::atomic<std::uint32_t>(0);
    next += std::uint32_t(n);
  }
  arena_[list] = std::uint32_t(whole.size());
  std::copy(whole.begin(), whole.end(), arena_ + list + 1);
  slots(*b, 0)[0].store(list, std::memory_order_relaxed);  // (before the block is seen)
  std::uint32_t expected = 0;
  if (!blocks_[index].compare_exchange_strong(expected, at, std::memory_order_acq_rel,
                                              std::memory_order_acquire))
    return reinterpret_cast<const Block*>(arena_ + expected);  // another thread's, the same
  return b;
}

SegmentCells::Positions SegmentCells::positions(std::uint32_t offset) const {
  return {arena_[offset], reinterpret_cast<const std::uint16_t*>(arena_ + offset + 1)};
}

SegmentCells::Positions SegmentCells::list(const Block& b, int level, const int* j) const {
  const int side = 1 << level;
  std::atomic<std::uint32_t>& slot = slots(b, level)[(std::size_t(j[2]) * side + j[1]) * side + j[0]];
  if (const std::uint32_t at = slot.load(std::memory_order_acquire)) return positions(at);
  if (full()) return {};
  const std::uint32_t* whole = arena_ + slots(b, 0)[0].load(std::memory_order_relaxed);
  Positions parent{whole[0], nullptr};  // level 1's parent is level 0's list itself
  if (level > 1) {
    const int up[3] = {j[0] >> 1, j[1] >> 1, j[2] >> 1};
    parent = list(b, level - 1, up);
    if (!parent.at) return {};
  }
  double c[3];
  for (int a = 0; a < 3; ++a) c[a] = b.corner[a] + (j[a] + 0.5) * std::ldexp(cell_, -level);
  thread_local std::vector<std::uint32_t> kept;
  kept.clear();
  bvh_->collect_from(whole + 1, parent.at, parent.count, c, radius(level), g_, cap_, kept);
  const std::uint32_t at = take(1 + (kept.size() + 1) / 2);
  if (!at) return {};
  arena_[at] = std::uint32_t(kept.size());  // the layout positions() reads
  auto* pos = reinterpret_cast<std::uint16_t*>(arena_ + at + 1);
  for (std::size_t k = 0; k < kept.size(); ++k)
    pos[k] = parent.at ? parent.at[kept[k]] : std::uint16_t(kept[k]);
  std::uint32_t expected = 0;
  if (!slot.compare_exchange_strong(expected, at, std::memory_order_acq_rel,
                                    std::memory_order_acquire))
    return positions(expected);  // another thread's, the same
  return positions(at);
}

bool SegmentCells::min_value(std::size_t index, const double* centre, const double* x,
                             double& best) const {
  if (!arena_) return false;
  const Block* b = block(index, centre);
  if (!b) return false;
  const std::uint32_t* whole = arena_ + slots(*b, 0)[0].load(std::memory_order_relaxed);
  if (b->levels == 0) {
    best = bvh_->min_of(whole + 1, nullptr, whole[0], x, g_, best);
    return true;
  }
  const int side = 1 << b->levels;
  const double inv = side / cell_;
  int j[3];
  for (int a = 0; a < 3; ++a)  // (x is in the cell up to the caller's rounding: the radii's margin)
    j[a] = std::clamp(int(std::floor((x[a] - b->corner[a]) * inv)), 0, side - 1);
  const Positions l = list(*b, int(b->levels), j);
  if (!l.at) return false;
  best = bvh_->min_of(whole + 1, l.at, l.count, x, g_, best);
  return true;
}

}  // namespace kdmesh
