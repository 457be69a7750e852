// kdmesh — Hilbert keys of a point set and sorting by key (used by the hilbert and brio
// orders in order.cpp).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "mesher/order/hilbert.h"

namespace kdmesh::hilbert {

std::vector<std::uint64_t> point_keys(const PointSet& points) {
  const std::size_t n = points.size();
  std::vector<std::uint64_t> keys(n);
  if (n == 0) return keys;
  const double* xyz = points.xyz.data();

  // Bounding cube: lower corner of the bounding box, side = largest extent.
  double lo[3] = {xyz[0], xyz[1], xyz[2]};
  double hi[3] = {xyz[0], xyz[1], xyz[2]};
  for (std::size_t i = 1; i < n; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double v = xyz[3 * i + j];
      lo[j] = v < lo[j] ? v : lo[j];
      hi[j] = v > hi[j] ? v : hi[j];
    }
  }
  constexpr std::uint32_t kCells = std::uint32_t(1) << kBits;
  constexpr double kMaxCell = double(kCells - 1);
  constexpr double kMax = std::numeric_limits<double>::max();
  // Extreme spreads: an overflowing side is avoided by halving the coordinates (pre), an
  // overflowing 2^21 / side (side < 2^-1000) by scaling the differences up (post). Both
  // factors are powers of two, so normal inputs (pre = post = 1) are unaffected.
  double pre = 1.0, post = 1.0;
  double side = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  if (!(side <= kMax)) {
    pre = 0.5;
  } else if (side > 0 && !(double(kCells) / side <= kMax)) {
    post = 0x1p600;
  }
  double base_lo[3];
  for (int j = 0; j < 3; ++j) base_lo[j] = lo[j] * pre;
  side = 0;
  for (int j = 0; j < 3; ++j) side = std::max(side, (hi[j] * pre - base_lo[j]) * post);
  // side == 0: every point is in cell 0 (no division by zero).
  const double scale = side > 0 ? double(kCells) / side : 0.0;

  // Quantise and encode kBatch points at a time (the tail batch is padded with cell 0).
  for (std::size_t base = 0; base < n; base += kBatch) {
    std::uint32_t c[3][kBatch] = {};
    std::uint64_t out[kBatch];
    const std::size_t count = std::min<std::size_t>(kBatch, n - base);
    for (std::size_t l = 0; l < count; ++l) {
      for (int j = 0; j < 3; ++j) {
        // (v - lo) * scale is in [0, 2^21]; the top face belongs to the last cell.
        const double f = ((xyz[3 * (base + l) + j] * pre - base_lo[j]) * post) * scale;
        c[j][l] = std::uint32_t(f < kMaxCell ? f : kMaxCell);
      }
    }
    key_batch(c[0], c[1], c[2], out, kBits);
    for (std::size_t l = 0; l < count; ++l) keys[base + l] = out[l];
  }
  return keys;
}

namespace {

struct KeyId {
  std::uint64_t key;
  std::uint32_t id;
};

inline bool key_id_less(const KeyId& a, const KeyId& b) {
  return a.key < b.key || (a.key == b.key && a.id < b.id);
}

/// Stable LSD radix sort of a[0..n) by key (63 bits: six 11-bit digits). `tmp` has n slots.
void radix_sort_by_key(std::vector<KeyId>& a, std::vector<KeyId>& tmp) {
  constexpr int kDigitBits = 11;
  constexpr int kPasses = 6;
  constexpr std::size_t kBuckets = std::size_t(1) << kDigitBits;
  const std::size_t n = a.size();
  std::vector<std::array<std::size_t, kBuckets>> count(kPasses);
  for (auto& c : count) c.fill(0);
  for (const KeyId& e : a) {
    for (int p = 0; p < kPasses; ++p) ++count[p][(e.key >> (p * kDigitBits)) & (kBuckets - 1)];
  }
  for (int p = 0; p < kPasses; ++p) {
    auto& c = count[p];
    // A digit shared by every element does not reorder anything: skip the pass.
    if (c[(a[0].key >> (p * kDigitBits)) & (kBuckets - 1)] == n) continue;
    std::size_t sum = 0;
    for (auto& v : c) {
      const std::size_t t = v;
      v = sum;
      sum += t;
    }
    for (const KeyId& e : a) tmp[c[(e.key >> (p * kDigitBits)) & (kBuckets - 1)]++] = e;
    a.swap(tmp);
  }
}

}  // namespace

void sort_ids_by_key(std::uint32_t* ids, std::size_t count, const std::uint64_t* keys) {
  std::vector<KeyId> a(count);
  for (std::size_t i = 0; i < count; ++i) a[i] = KeyId{keys[ids[i]], ids[i]};
  if (count < 4096) {
    std::sort(a.begin(), a.end(), key_id_less);
  } else {
    std::vector<KeyId> tmp(count);
    radix_sort_by_key(a, tmp);
    // Equal keys (points sharing a cell) are now in input order: sort each run by id.
    for (std::size_t i = 0; i < count;) {
      std::size_t j = i + 1;
      while (j < count && a[j].key == a[i].key) ++j;
      if (j - i > 1) std::sort(a.begin() + i, a.begin() + j, key_id_less);
      i = j;
    }
  }
  for (std::size_t i = 0; i < count; ++i) ids[i] = a[i].id;
}

}  // namespace kdmesh::hilbert
