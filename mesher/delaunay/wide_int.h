// kdmesh — fixed-width two's-complement integers of N 64-bit limbs, for the exact stage of the
// geometric predicates (mesher/delaunay/predicates.cpp). No allocation; the caller chooses the widths
// so that no sum or product can overflow (the bounds are derived there).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>

namespace kdmesh::pred::wide {

using u128 = unsigned __int128;

/// w[0] is the least significant limb; the value is sum w[i] 2^(64 i) - (top bit) 2^(64 N).
template <int N>
struct Int {
  std::uint64_t w[N];
};

[[gnu::always_inline]] inline Int<1> from_i64(std::int64_t x) { return {{std::uint64_t(x)}}; }
[[gnu::always_inline]] inline Int<2> from_i128(__int128 x) {
  const u128 u = u128(x);
  return {{std::uint64_t(u), std::uint64_t(u >> 64)}};
}

template <int N>
[[gnu::always_inline]] inline bool negative(const Int<N>& a) {
  return (a.w[N - 1] >> 63) != 0;
}

template <int N>
[[gnu::always_inline]] inline Int<N> neg(const Int<N>& a) {
  Int<N> r;
  std::uint64_t carry = 1;
  for (int i = 0; i < N; ++i) {
    const u128 s = u128(~a.w[i]) + carry;
    r.w[i] = std::uint64_t(s);
    carry = std::uint64_t(s >> 64);
  }
  return r;
}

template <int N>
[[gnu::always_inline]] inline Int<N> add(const Int<N>& a, const Int<N>& b) {
  Int<N> r;
  std::uint64_t carry = 0;
  for (int i = 0; i < N; ++i) {
    const u128 s = u128(a.w[i]) + b.w[i] + carry;
    r.w[i] = std::uint64_t(s);
    carry = std::uint64_t(s >> 64);
  }
  return r;
}

template <int N>
[[gnu::always_inline]] inline Int<N> sub(const Int<N>& a, const Int<N>& b) {
  return add(a, neg(b));
}

/// The full product, A + B limbs (exact: |a b| <= 2^(64(A+B) - 2) always holds). Without a
/// branch on the signs (they are coin tosses in the predicates' exact stage): the product of
/// the two's complement patterns read as unsigned, then, mod 2^(64(A+B)), b 2^(64A) taken off
/// where a is negative (its pattern is a + 2^(64A)) and a 2^(64B) where b is.
template <int A, int B>
[[gnu::always_inline]] inline Int<A + B> mul(const Int<A>& a, const Int<B>& b) {
  Int<A + B> r{};
  for (int i = 0; i < A; ++i) {
    std::uint64_t carry = 0;
    for (int j = 0; j < B; ++j) {
      const u128 t = u128(a.w[i]) * b.w[j] + r.w[i + j] + carry;
      r.w[i + j] = std::uint64_t(t);
      carry = std::uint64_t(t >> 64);
    }
    r.w[i + B] = carry;
  }
  const std::uint64_t a_neg = std::uint64_t(0) - (a.w[A - 1] >> 63);  // all ones if a < 0
  const std::uint64_t b_neg = std::uint64_t(0) - (b.w[B - 1] >> 63);
  std::uint64_t borrow = 0;
  for (int j = 0; j < B; ++j) {
    const u128 d = u128(r.w[A + j]) - (b.w[j] & a_neg) - borrow;
    r.w[A + j] = std::uint64_t(d);
    borrow = std::uint64_t(d >> 64) & 1;
  }
  borrow = 0;
  for (int i = 0; i < A; ++i) {
    const u128 d = u128(r.w[B + i]) - (a.w[i] & b_neg) - borrow;
    r.w[B + i] = std::uint64_t(d);
    borrow = std::uint64_t(d >> 64) & 1;
  }
  return r;
}

template <int N>
[[gnu::always_inline]] inline int sign(const Int<N>& a) {
  if (negative(a)) return -1;
  for (int i = 0; i < N; ++i)
    if (a.w[i] != 0) return 1;
  return 0;
}

}  // namespace kdmesh::pred::wide
