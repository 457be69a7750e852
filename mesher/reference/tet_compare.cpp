// kdmesh — compare two tetrahedralizations of the same points by their invariants.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/reference/tet_compare.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/error.h"

namespace kdmesh {
namespace {

constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

/// Bit pattern of x with -0.0 mapped to +0.0, so that values that compare equal hash equally.
std::uint64_t value_bits(double x) {
  if (x == 0.0) x = 0.0;
  return std::bit_cast<std::uint64_t>(x);
}

/// splitmix64 finaliser: a cheap, well-mixing 64-bit hash step.
std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t hash_point(const double* p) {
  std::uint64_t h = mix(value_bits(p[0]) + 0x9e3779b97f4a7c15ULL);
  h = mix(h ^ value_bits(p[1]));
  return mix(h ^ value_bits(p[2]));
}

bool same_point(const double* p, const double* q) {
  return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

void check_tet_list(const PointSet& points, const std::vector<std::uint32_t>& tets,
                    const char* what) {
  if (tets.size() % 4 != 0) {
    throw UsageError(std::string(what) + ": tet list length " + std::to_string(tets.size()) +
                     " is not a multiple of 4");
  }
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < tets.size(); ++i) {
    if (tets[i] >= n) {
      throw UsageError(std::string(what) + ": tet " + std::to_string(i / 4) +
                       " refers to point " + std::to_string(tets[i]) + " but there are only " +
                       std::to_string(n) + " points");
    }
  }
}

/// A tet as its sorted vertex set, packed in two words so that comparisons are cheap.
struct TetKey {
  std::uint64_t hi, lo;
  friend bool operator==(const TetKey&, const TetKey&) = default;
  friend auto operator<=>(const TetKey&, const TetKey&) = default;
};

std::vector<TetKey> sorted_keys(const std::vector<std::uint32_t>& tets) {
  std::vector<TetKey> keys(tets.size() / 4);
  for (std::size_t t = 0; t < keys.size(); ++t) {
    std::uint32_t v[4] = {tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3]};
    // 5-comparator sorting network for 4 elements.
    auto cs = [&](int i, int j) {
      if (v[j] < v[i]) std::swap(v[i], v[j]);
    };
    cs(0, 1), cs(2, 3), cs(0, 2), cs(1, 3), cs(1, 2);
    keys[t] = {(std::uint64_t(v[0]) << 32) | v[1], (std::uint64_t(v[2]) << 32) | v[3]};
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

void append_example(std::vector<std::uint32_t>& out, const TetKey& k) {
  if (out.size() >= 4 * 5) return;  // at most 5 examples
  out.push_back(std::uint32_t(k.hi >> 32));
  out.push_back(std::uint32_t(k.hi));
  out.push_back(std::uint32_t(k.lo >> 32));
  out.push_back(std::uint32_t(k.lo));
}

/// Kahan-compensated sum of |det|/6 over the tets, in long double. Ids must be valid.
double volume_sum(const PointSet& points, const std::vector<std::uint32_t>& tets) {
  long double sum = 0, comp = 0;
  for (std::size_t t = 0; t + 3 < tets.size(); t += 4) {
    const double* a = points.p(tets[t]);
    const double* b = points.p(tets[t + 1]);
    const double* c = points.p(tets[t + 2]);
    const double* d = points.p(tets[t + 3]);
    const long double bx = (long double)b[0] - a[0], by = (long double)b[1] - a[1],
                      bz = (long double)b[2] - a[2];
    const long double cx = (long double)c[0] - a[0], cy = (long double)c[1] - a[1],
                      cz = (long double)c[2] - a[2];
    const long double dx = (long double)d[0] - a[0], dy = (long double)d[1] - a[1],
                      dz = (long double)d[2] - a[2];
    const long double det =
        bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
    const long double y = std::fabs(det) / 6 - comp;
    const long double s = sum + y;
    comp = (s - sum) - y;
    sum = s;
  }
  return double(sum);
}

}  // namespace

std::vector<std::uint32_t> canonical_point_ids(const PointSet& points) {
  const std::size_t n = points.size();
  if (n >= std::size_t(kEmpty)) {
    throw UsageError("too many points for 32-bit ids: " + std::to_string(n));
  }
  std::vector<std::uint32_t> canon(n);
  if (n == 0) return canon;

  // Open addressing with linear probing; load factor <= 1/2. Points are inserted in increasing
  // id order, so the first id stored for a coordinate triple is the smallest one.
  const std::size_t cap = std::bit_ceil(2 * n);
  const std::size_t mask = cap - 1;
  std::vector<std::uint32_t> table(cap, kEmpty);
  for (std::uint32_t i = 0; i < n; ++i) {
    const double* p = points.p(i);
    std::size_t slot = hash_point(p) & mask;
    for (;;) {
      const std::uint32_t j = table[slot];
      if (j == kEmpty) {
        table[slot] = i;
        canon[i] = i;
        break;
      }
      if (same_point(points.p(j), p)) {
        canon[i] = j;
        break;
      }
      slot = (slot + 1) & mask;
    }
  }
  return canon;
}

TetComparison compare_tets(const PointSet& points, const std::vector<std::uint32_t>& a,
                           const std::vector<std::uint32_t>& b) {
  check_tet_list(points, a, "compare_tets (first list)");
  check_tet_list(points, b, "compare_tets (second list)");

  TetComparison r;
  r.tets_a = a.size() / 4;
  r.tets_b = b.size() / 4;
  r.volume_a = volume_sum(points, a);
  r.volume_b = volume_sum(points, b);

  // Merge the two sorted multisets of vertex sets; equal keys cancel one for one.
  const std::vector<TetKey> ka = sorted_keys(a);
  const std::vector<TetKey> kb = sorted_keys(b);
  std::size_t i = 0, j = 0;
  while (i < ka.size() || j < kb.size()) {
    if (j == kb.size() || (i < ka.size() && ka[i] < kb[j])) {
      ++r.only_in_a;
      append_example(r.example_only_a, ka[i++]);
    } else if (i == ka.size() || kb[j] < ka[i]) {
      ++r.only_in_b;
      append_example(r.example_only_b, kb[j++]);
    } else {
      ++i, ++j;
    }
  }
  return r;
}

double total_volume(const PointSet& points, const std::vector<std::uint32_t>& tets) {
  check_tet_list(points, tets, "total_volume");
  return volume_sum(points, tets);
}

}  // namespace kdmesh
