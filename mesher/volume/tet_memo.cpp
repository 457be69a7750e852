// kdmesh — TetMemo (mesher/volume/tet_memo.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/tet_memo.h"

#include <bit>

#include "core/parallel_for.h"
#include "mesher/bucket_scatter.h"

namespace kdmesh {

std::uint64_t TetMemo::hash(const std::uint32_t* v) {
  std::uint64_t h = (std::uint64_t(v[0]) << 32 | v[1]) * 0x9E3779B97F4A7C15ULL;
  h ^= (std::uint64_t(v[2]) << 32 | v[3]) * 0xC2B2AE3D27D4EB4FULL;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ULL;
  return h ^ (h >> 32);
}

std::int32_t TetMemo::find(const std::uint32_t* v) const {
  const std::uint64_t h = hash(v);
  const Part& p = parts_[h >> (64 - kPartBits)];
  if (p.slots.empty()) return kNone;
  const std::size_t mask = p.slots.size() - 1;
  for (std::size_t i = h & mask;; i = (i + 1) & mask) {
    const Slot& s = p.slots[i];
    if (s.v[0] == kFree) return kNone;
    if (s.v[0] == v[0] && s.v[1] == v[1] && s.v[2] == v[2] && s.v[3] == v[3]) return s.answer;
  }
}

void TetMemo::insert(Part& p, const std::uint32_t* v, std::int32_t answer, std::uint64_t h) {
  const std::size_t mask = p.slots.size() - 1;
  for (std::size_t i = h & mask;; i = (i + 1) & mask) {
    Slot& s = p.slots[i];
    if (s.v[0] == kFree) {
      s = Slot{{v[0], v[1], v[2], v[3]}, answer};
      ++p.size;
      return;
    }
    if (s.v[0] == v[0] && s.v[1] == v[1] && s.v[2] == v[2] && s.v[3] == v[3]) {
      s.answer = answer;
      return;
    }
  }
}

void TetMemo::reserve(Part& p, std::size_t more) {
  const std::size_t want = p.size + more;
  if (8 * want <= 5 * p.slots.size()) return;
  std::vector<Slot> old;
  old.swap(p.slots);
  p.slots.assign(std::bit_ceil(std::max<std::size_t>(16, (8 * want + 4) / 5)), Slot{{kFree, 0, 0, 0}, 0});
  p.size = 0;
  for (const Slot& s : old)
    if (s.v[0] != kFree) insert(p, s.v, s.answer, hash(s.v));
}

void TetMemo::put(std::size_t n, const std::function<const std::uint32_t*(std::size_t)>& key,
                  const std::function<std::int32_t(std::size_t)>& answer) {
  if (n == 0) return;
  std::vector<std::uint64_t> h(n);
  parallel_for(n, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) h[k] = hash(key(k));
  }, 1 << 14);
  // The keys by part, each part's in key order (a stable counting sort).
  std::vector<std::uint32_t> order(n);
  const std::vector<std::size_t> start = bucket_scatter(
      n, parts_.size(), [&](std::size_t k) { return std::size_t(h[k] >> (64 - kPartBits)); },
      [&](std::size_t k, std::size_t at) { order[at] = std::uint32_t(k); });
  parallel_for(parts_.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t q = b; q < e; ++q) {
      Part& p = parts_[q];
      reserve(p, start[q + 1] - start[q]);
      for (std::size_t i = start[q]; i < start[q + 1]; ++i) insert(p, key(order[i]), answer(order[i]), h[order[i]]);
    }
  }, 1);
}

void TetMemo::clear() {
  for (Part& p : parts_) {
    std::vector<Slot>().swap(p.slots);
    p.size = 0;
  }
}

std::size_t TetMemo::size() const {
  std::size_t n = 0;
  for (const Part& p : parts_) n += p.size;
  return n;
}

}  // namespace kdmesh
