// Predicates against an independent exact oracle (GMP rationals, Gaussian elimination on the
// homogeneous determinants), on random, near-degenerate and exactly degenerate inputs.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gmp.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/delaunay/wide_int.h"

namespace kdmesh {
namespace {

using P3 = std::array<double, 3>;

/// Sign of the determinant of a k x k rational matrix, by fraction-exact Gaussian elimination.
int det_sign(std::vector<std::vector<double>> rows) {
  const int k = int(rows.size());
  std::vector<mpq_t> m(k * k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      mpq_init(m[i * k + j]);
      mpq_set_d(m[i * k + j], rows[i][j]);
    }
  int sign = 1;
  mpq_t f, t;
  mpq_init(f);
  mpq_init(t);
  for (int c = 0; c < k && sign != 0; ++c) {
    int piv = -1;
    for (int r = c; r < k; ++r)
      if (mpq_sgn(m[r * k + c]) != 0) { piv = r; break; }
    if (piv < 0) { sign = 0; break; }
    if (piv != c) {
      for (int j = 0; j < k; ++j) mpq_swap(m[c * k + j], m[piv * k + j]);
      sign = -sign;
    }
    if (mpq_sgn(m[c * k + c]) < 0) sign = -sign;
    for (int r = c + 1; r < k; ++r) {
      mpq_div(f, m[r * k + c], m[c * k + c]);
      for (int j = c; j < k; ++j) {
        mpq_mul(t, f, m[c * k + j]);
        mpq_sub(m[r * k + j], m[r * k + j], t);
      }
    }
  }
  mpq_clear(f);
  mpq_clear(t);
  for (auto& x : m) mpq_clear(x);
  return sign;
}

// Homogeneous forms: rows (x, y, z, 1) and (x, y, z, x^2+y^2+z^2, 1). The lifted coordinate is
// computed exactly by the oracle (mpq) - here we only pass the coordinates.
int oracle_orient(const P3& a, const P3& b, const P3& c, const P3& d) {
  // det[b-a, c-a, d-a] = -det[[a,1],[b,1],[c,1],[d,1]] (expand along the column of ones).
  return -det_sign({{a[0], a[1], a[2], 1}, {b[0], b[1], b[2], 1}, {c[0], c[1], c[2], 1},
                    {d[0], d[1], d[2], 1}});
}

int oracle_insphere(const P3& a, const P3& b, const P3& c, const P3& d, const P3& e) {
  // Build the 5x5 matrix with exact lifted entries: use the 4x4 form on differences to e,
  // each lift computed exactly as an mpq.
  const P3* p[4] = {&a, &b, &c, &d};
  std::vector<mpq_t> m(16);
  for (auto& x : m) mpq_init(x);
  mpq_t u, v;
  mpq_init(u);
  mpq_init(v);
  for (int i = 0; i < 4; ++i) {
    mpq_set_ui(m[i * 4 + 3], 0, 1);
    for (int k = 0; k < 3; ++k) {
      mpq_set_d(u, (*p[i])[k]);
      mpq_set_d(v, e[k]);
      mpq_sub(m[i * 4 + k], u, v);
      mpq_mul(u, m[i * 4 + k], m[i * 4 + k]);
      mpq_add(m[i * 4 + 3], m[i * 4 + 3], u);
    }
  }
  // Laplace-free: Gaussian elimination on this 4x4 rational matrix.
  int sign = 1;
  for (int c = 0; c < 4 && sign != 0; ++c) {
    int piv = -1;
    for (int r = c; r < 4; ++r)
      if (mpq_sgn(m[r * 4 + c]) != 0) { piv = r; break; }
    if (piv < 0) { sign = 0; break; }
    if (piv != c) {
      for (int j = 0; j < 4; ++j) mpq_swap(m[c * 4 + j], m[piv * 4 + j]);
      sign = -sign;
    }
    if (mpq_sgn(m[c * 4 + c]) < 0) sign = -sign;
    for (int r = c + 1; r < 4; ++r) {
      mpq_div(u, m[r * 4 + c], m[c * 4 + c]);
      for (int j = c; j < 4; ++j) {
        mpq_mul(v, u, m[c * 4 + j]);
        mpq_sub(m[r * 4 + j], m[r * 4 + j], v);
      }
    }
  }
  mpq_clear(u);
  mpq_clear(v);
  for (auto& x : m) mpq_clear(x);
  // det[[a-e, |a-e|^2], ...] is positive for e inside when (a,b,c,d) is negatively oriented in
  // the det[b-a,c-a,d-a] convention (checked on the unit tet below), so negate.
  return -sign;
}

const P3 O{0, 0, 0}, X{1, 0, 0}, Y{0, 1, 0}, Z{0, 0, 1};

TEST(Predicates, UnitTetSigns) {
  EXPECT_EQ(pred::orient3d(O.data(), X.data(), Y.data(), Z.data()), 1);
  EXPECT_EQ(pred::orient3d(X.data(), O.data(), Y.data(), Z.data()), -1);
  EXPECT_EQ(oracle_orient(O, X, Y, Z), 1);
  const P3 in{0.25, 0.25, 0.25}, out{2, 2, 2}, on{1, 1, 0};  // sphere: centre (.5,.5,.5), r^2 = .75
  EXPECT_EQ(pred::insphere(O.data(), X.data(), Y.data(), Z.data(), in.data()), 1);
  EXPECT_EQ(pred::insphere(O.data(), X.data(), Y.data(), Z.data(), out.data()), -1);
  EXPECT_EQ(pred::insphere(O.data(), X.data(), Y.data(), Z.data(), on.data()), 0);
  EXPECT_EQ(oracle_insphere(O, X, Y, Z, in), 1);
  EXPECT_EQ(oracle_insphere(O, X, Y, Z, on), 0);
  const P3 coplanar{0.3, 0.7, 0};
  EXPECT_EQ(pred::orient3d(O.data(), X.data(), Y.data(), coplanar.data()), 0);
}

// Random inputs, near-coplanar/near-cospherical inputs built to defeat the filter, and exact
// degeneracies on small integer grids: every sign must equal the oracle's.
TEST(Predicates, AgreeWithExactOracle) {
  Rng rng(7);
  const std::uint64_t exact_before = pred::exact_calls();
  for (int iter = 0; iter < 3000; ++iter) {
    P3 p[5];
    const int mode = iter % 3;
    for (auto& q : p)
      for (auto& x : q)
        x = mode == 2 ? double(rng.below(3)) : rng.uniform(-1, 1) * (iter % 7 == 0 ? 1e-200 : 1.0);
    if (mode == 1) {
      // d and e nearly on the plane / sphere spanned by the others: tiny offsets.
      const double s = rng.uniform(), t = rng.uniform();
      for (int k = 0; k < 3; ++k)
        p[3][k] = p[0][k] + s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[0][k]) +
                  std::ldexp(rng.uniform(-1, 1), -60);
      // e: a point on the circumsphere is hard to construct; a mirrored vertex through the
      // centroid plane gives near-ties often enough.
      for (int k = 0; k < 3; ++k) p[4][k] = p[1][k] + std::ldexp(rng.uniform(-1, 1), -58);
    }
    ASSERT_EQ(pred::orient3d(p[0].data(), p[1].data(), p[2].data(), p[3].data()),
              oracle_orient(p[0], p[1], p[2], p[3]))
        << "iter " << iter;
    ASSERT_EQ(pred::insphere(p[0].data(), p[1].data(), p[2].data(), p[3].data(), p[4].data()),
              oracle_insphere(p[0], p[1], p[2], p[3], p[4]))
        << "iter " << iter;
  }
  // The test is only meaningful if the exact path was exercised.
  EXPECT_GT(pred::exact_calls() - exact_before, 500u);
}

// The insphere filter's lift bound (predicates.h, kInsphereLiftStatic) on the inputs it is
// weakest on: scales from 2^-80 to 2^80, rows flattened along y or z (points near a plane or a
// line, where the lifts overestimate the permanent), points on a common sphere, e a rounding
// step away from a vertex, and exact ties on a grid. Every sign must equal the oracle's.
TEST(Predicates, InsphereFilterAgreesWithOracleAcrossScalesAndShapes) {
  Rng rng(13);
  for (int iter = 0; iter < 20000; ++iter) {
    const double s = std::ldexp(1.0, int(rng.below(161)) - 80);
    const double sy = s * (rng.below(4) == 0 ? 1e-9 : 1), sz = s * (rng.below(8) == 0 ? 1e-12 : 1);
    P3 p[5];
    for (int i = 0; i < 5; ++i) p[i] = {rng.uniform(-1, 1) * s, rng.uniform(-1, 1) * sy, rng.uniform(-1, 1) * sz};
    switch (iter % 4) {
      case 0:  // e one rounding step from a: |det| tiny, far below the filter's reach
        p[4] = p[0];
        p[4][0] = std::nextafter(p[4][0], 1e300);
        break;
      case 1:  // all five near one sphere of radius s
        for (auto& q : p) {
          const double a = rng.uniform(-3.14159, 3.14159), b = rng.uniform(-1.5, 1.5);
          q = {s * std::cos(a) * std::cos(b), s * std::sin(a) * std::cos(b), s * std::sin(b)};
        }
        break;
      case 2:  // exact ties
        for (auto& q : p)
          for (double& x : q) x = double(rng.below(3)) * s;
        break;
      default:  // e near the origin of the row differences
        for (int k = 0; k < 3; ++k) p[4][k] *= 1e-3;
    }
    if (pred::orient3d(p[0].data(), p[1].data(), p[2].data(), p[3].data()) < 0) std::swap(p[0], p[1]);
    ASSERT_EQ(pred::insphere(p[0].data(), p[1].data(), p[2].data(), p[3].data(), p[4].data()),
              oracle_insphere(p[0], p[1], p[2], p[3], p[4]))
        << "iter " << iter;
  }
}

TEST(Predicates, ExtremeScalesUseExactArithmetic) {
  // Coordinates spanning 1e-200 .. 1e200 in one call: products underflow/overflow the filter.
  const P3 a{1e-200, 0, 0}, b{0, 1e-200, 0}, c{0, 0, 1e-200}, d{1e-200, 1e-200, 1e-200};
  EXPECT_EQ(pred::orient3d(a.data(), b.data(), c.data(), d.data()), oracle_orient(a, b, c, d));
  EXPECT_EQ(pred::orient3d(O.data(), a.data(), b.data(), c.data()), 1);
  const P3 big{1e200, 1e200, 1e200};
  EXPECT_EQ(pred::insphere(O.data(), a.data(), b.data(), c.data(), big.data()), -1);
  EXPECT_EQ(pred::insphere(O.data(), a.data(), b.data(), c.data(), d.data()),
            oracle_insphere(O, a, b, c, d));
}

// The exact stage's fast path (64-bit integers of one scale, fixed-width products) against
// the GMP path and the rational oracle, on the inputs it exists for: ties and near-ties among
// nearby points of a lattice whose spacing is not a power of two (as the block model's BCC
// interior: full 53-bit mantissas, differences exact by Sterbenz). A bug here would give wrong
// tie signs, so every sign is compared, and the test asserts that the fast path did run and
// that exact ties occurred.
TEST(Predicates, ExactIntegerStageAgreesWithGmpOnLatticeTies) {
  Rng rng(11);
  const double h = 0.40071, off = 3.2056799999999996;
  auto lattice = [&](P3& q) {  // a BCC lattice node near the origin of a 4x4x4 block
    const double half = rng.below(2) ? 0.5 : 0.0;
    for (int k = 0; k < 3; ++k) q[k] = off + (double(rng.below(4)) + half) * h;
  };
  int fast = 0, orient_ties = 0, insphere_ties = 0;
  for (int iter = 0; iter < 4000; ++iter) {
    P3 p[5];
    for (auto& q : p) lattice(q);
    if (iter % 4 == 3)  // a near-tie: e one rounding step off a lattice node
      p[4][iter % 3] = std::nextafter(p[4][iter % 3], 10.0);
    const double *a = p[0].data(), *b = p[1].data(), *c = p[2].data(), *d = p[3].data(),
                 *e = p[4].data();
    const int oi = pred::detail::orient3d_int(a, b, c, d);
    const int si = pred::detail::insphere_int(a, b, c, d, e);
    fast += (oi != 2) + (si != 2);
    const int og = pred::detail::orient3d_gmp(a, b, c, d), sg = pred::detail::insphere_gmp(a, b, c, d, e);
    if (oi != 2) {
      ASSERT_EQ(oi, og) << "iter " << iter;
    }
    if (si != 2) {
      ASSERT_EQ(si, sg) << "iter " << iter;
    }
    orient_ties += og == 0;
    insphere_ties += sg == 0;
    if (iter % 10 == 0) {  // the oracle is slow
      ASSERT_EQ(og, oracle_orient(p[0], p[1], p[2], p[3])) << "iter " << iter;
      ASSERT_EQ(sg, oracle_insphere(p[0], p[1], p[2], p[3], p[4])) << "iter " << iter;
    }
  }
  EXPECT_GT(fast, 7900);  // nearby lattice points: the fast path applies to (nearly) all
  EXPECT_GT(orient_ties, 100);
  EXPECT_GT(insphere_ties, 100);
}

// The exact stage's fixed-width products (mesher/delaunay/wide_int.h), multiplied without a
// branch on the signs: every sign combination and magnitudes up to the widths' limits, against
// GMP. A wrong two's complement correction would show in the top limbs.
template <int N>
void to_mpz(mpz_t out, const pred::wide::Int<N>& a) {
  mpz_import(out, N, -1, sizeof(std::uint64_t), 0, 0, a.w);  // least significant limb first
  if (a.w[N - 1] >> 63) {  // two's complement: the pattern is a + 2^(64 N)
    mpz_t m;
    mpz_init_set_ui(m, 1);
    mpz_mul_2exp(m, m, 64 * N);
    mpz_sub(out, out, m);
    mpz_clear(m);
  }
}

/// A random value of N limbs below 2^(64 N - 2 - spare) in magnitude, of either sign.
template <int N>
pred::wide::Int<N> random_wide(Rng& rng, int spare) {
  pred::wide::Int<N> a;
  for (int i = 0; i < N; ++i) a.w[i] = rng.next();
  a.w[N - 1] >>= 2 + spare;
  return rng.below(2) ? pred::wide::neg(a) : a;
}

template <int A, int B>
void check_products(Rng& rng, int iterations) {
  mpz_t x, y, want, got;
  mpz_inits(x, y, want, got, nullptr);
  for (int iter = 0; iter < iterations; ++iter) {
    // |a b| < 2^(64(A+B) - 4): inside the product's width, as the predicates' bounds keep it.
    const pred::wide::Int<A> a = random_wide<A>(rng, iter % 7);
    const pred::wide::Int<B> b = random_wide<B>(rng, 0);
    to_mpz(x, a);
    to_mpz(y, b);
    mpz_mul(want, x, y);
    to_mpz(got, pred::wide::mul(a, b));
    ASSERT_EQ(mpz_cmp(want, got), 0) << "A " << A << " B " << B << " iter " << iter;
  }
  mpz_clears(x, y, want, got, nullptr);
}

TEST(Predicates, WideProductsOfEverySignMatchGmp) {
  Rng rng(3);
  check_products<1, 1>(rng, 4000);
  check_products<1, 2>(rng, 4000);
  check_products<2, 3>(rng, 4000);
  // Zero and -1 (all ones) as either factor.
  const pred::wide::Int<2> minus_one{{~std::uint64_t(0), ~std::uint64_t(0)}}, zero{{0, 0}};
  const pred::wide::Int<3> m = random_wide<3>(rng, 0);
  EXPECT_EQ(pred::wide::sign(pred::wide::mul(zero, m)), 0);
  const pred::wide::Int<5> p = pred::wide::mul(minus_one, m), q = pred::wide::neg(pred::wide::mul(pred::wide::Int<2>{{1, 0}}, m));
  for (int i = 0; i < 5; ++i) EXPECT_EQ(p.w[i], q.w[i]) << i;
}

// The fast path's widths are sized for differences below 2^62 of their common scale: inputs at
// that limit (the largest products) must still agree with the oracle, and one bit more, an
// inexact difference, or a subnormal must hand over to the GMP path (2).
TEST(Predicates, ExactIntegerStageAtItsLimits) {
  const double big = std::ldexp(double((std::uint64_t(1) << 53) - 1), 9);  // just below 2^62
  Rng rng(5);
  int zeros = 0;
  for (int iter = 0; iter < 2000; ++iter) {
    P3 p[5];
    for (auto& q : p)
      for (double& x : q) {
        const std::uint64_t r = rng.below(5);
        x = r == 0 ? 0.0 : r == 1 ? 1.0 : r == 2 ? -1.0 : r == 3 ? big : -big;
      }
    p[4] = {0, 0, 0};  // differences against e are the coordinates themselves
    const double *a = p[0].data(), *b = p[1].data(), *c = p[2].data(), *d = p[3].data(),
                 *e = p[4].data();
    const int si = pred::detail::insphere_int(a, b, c, d, e);
    ASSERT_NE(si, 2);
    ASSERT_EQ(si, oracle_insphere(p[0], p[1], p[2], p[3], p[4])) << "iter " << iter;
    const int oi = pred::detail::orient3d_int(e, a, b, c);
    ASSERT_NE(oi, 2);
    ASSERT_EQ(oi, oracle_orient(p[4], p[0], p[1], p[2])) << "iter " << iter;
    zeros += si == 0;
  }
  EXPECT_GT(zeros, 10);
  EXPECT_LT(zeros, 1900);
  const P3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0};
  const P3 wide{std::ldexp(1.0, 62), 0, 0};  // |d| < 2^63: one bit beyond the widths
  EXPECT_EQ(pred::detail::insphere_int(wide.data(), x.data(), y.data(), o.data(), o.data()), 2);
  EXPECT_EQ(pred::detail::orient3d_int(o.data(), wide.data(), x.data(), y.data()), 2);
  const P3 tenth{0.1, 0, 0}, huge{1e17, 0, 0};  // 1e17 - 0.1 is not exact in double
  EXPECT_EQ(pred::detail::orient3d_int(tenth.data(), huge.data(), x.data(), y.data()), 2);
  const P3 sub{4.9e-324, 0, 0};  // subnormal difference
  EXPECT_EQ(pred::detail::orient3d_int(o.data(), sub.data(), x.data(), y.data()), 2);
  // The public entry points still answer exactly through the GMP path.
  EXPECT_EQ(pred::orient3d_exact(tenth.data(), huge.data(), x.data(), y.data()),
            oracle_orient(tenth, huge, x, y));
}

// The two-lane filter of the cavity search (insphere_filter2) on the inputs of the scalar
// filter's test above: every sign it decides equals the oracle's, in both lanes, whichever lane
// a tet is in; and on well-shaped tets it decides nearly everything (a filter that always
// answered 0 would be correct but would make the kernel slow without any test failing).
TEST(Predicates, TwoLaneInsphereFilterAgreesWithOracle) {
  Rng rng(23);
  int decided = 0, total = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    P3 t[2][4], e;
    for (auto& tet : t)
      for (auto& q : tet)
        for (double& x : q) x = rng.uniform(-1, 1);
    for (double& x : e) x = rng.uniform(-1, 1);
    const int mode = iter % 4;
    if (mode == 1)  // e a rounding step from a vertex of the first tet: undecidable by floats
      for (int k = 0; k < 3; ++k) e[k] = std::nextafter(t[0][2][k], 2.0);
    if (mode == 2)  // exact ties: small integer grid
      for (auto& tet : t)
        for (auto& q : tet)
          for (double& x : q) x = double(rng.below(3));
    if (mode == 3)  // far out of the filter's range in the second tet
      for (auto& q : t[1])
        for (double& x : q) x *= 1e-40;
    const double* a[4];
    const double* b[4];
    for (int i = 0; i < 4; ++i) {
      a[i] = t[0][i].data();
      b[i] = t[1][i].data();
    }
    int s[2], r[2];
    pred::insphere_filter2(a, b, e.data(), s);
    pred::insphere_filter2(b, a, e.data(), r);
    EXPECT_EQ(s[0], r[1]);
    EXPECT_EQ(s[1], r[0]);
    for (int l = 0; l < 2; ++l) {
      const P3* q = t[l];
      ++total;
      if (s[l] == 0) continue;
      ++decided;
      ASSERT_EQ(s[l], oracle_insphere(q[0], q[1], q[2], q[3], e)) << "iter " << iter << " lane " << l;
    }
  }
  EXPECT_GT(decided, total / 2);
  EXPECT_LT(decided, total);  // the undecidable modes did reach the fallback
}

TEST(Predicates, Collinear) {
  const P3 a{0, 0, 0}, b{1, 2, 3}, c{2, 4, 6}, d{2, 4, 6.000000000000001};
  EXPECT_TRUE(pred::collinear(a.data(), b.data(), c.data()));
  EXPECT_FALSE(pred::collinear(a.data(), b.data(), d.data()));
  const P3 e{0.1, 0.2, 0.3}, f{0.3, 0.6, 0.9};  // 0.1*3 != 0.3 in binary: not exactly collinear
  EXPECT_EQ(pred::collinear(a.data(), e.data(), f.data()),
            oracle_orient(a, e, f, {1, 0, 0}) == 0 && oracle_orient(a, e, f, {0, 1, 0}) == 0 &&
                oracle_orient(a, e, f, {0, 0, 1}) == 0);
}

// Perturbed predicates are never 0, agree with the unperturbed sign when it is non-zero,
// and break ties by lexicographic priority independently of argument order.
TEST(Predicates, PerturbationBreaksEveryTie) {
  // The 8 corners of the unit cube are cospherical: every insphere among them is a tie.
  std::vector<P3> corners;
  for (int i = 0; i < 8; ++i) corners.push_back({double(i & 1), double(i >> 1 & 1), double(i >> 2)});
  int ties = 0;
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b)
      for (int c = 0; c < 8; ++c)
        for (int d = 0; d < 8; ++d)
          for (int e = 0; e < 8; ++e) {
            if (a == b || a == c || a == d || a == e || b == c || b == d || b == e || c == d ||
                c == e || d == e)
              continue;
            const double *pa = corners[a].data(), *pb = corners[b].data(), *pc = corners[c].data(),
                         *pd = corners[d].data(), *pe = corners[e].data();
            if (pred::orient3d(pa, pb, pc, pd) <= 0) continue;
            ASSERT_EQ(pred::insphere(pa, pb, pc, pd, pe), 0);
            ++ties;
            const int s = pred::insphere_perturbed(pa, pb, pc, pd, pe);
            ASSERT_NE(s, 0);
            // An even permutation of the tet's vertices keeps it positive: same answer.
            ASSERT_EQ(s, pred::insphere_perturbed(pb, pc, pa, pd, pe));
            ASSERT_EQ(s, pred::insphere_perturbed(pc, pd, pa, pb, pe));
          }
  EXPECT_GT(ties, 1000);
  // Non-tie: the perturbed result is the plain result.
  const P3 in{0.25, 0.25, 0.25};
  EXPECT_EQ(pred::insphere_perturbed(O.data(), X.data(), Y.data(), Z.data(), in.data()), 1);
}

TEST(Predicates, CoplanarIncircle) {
  const P3 q{0.2, 0.3, 5};  // reference point off the plane z = 0
  const P3 inside{0.3, 0.3, 0}, outside{3, 3, 0}, on{1, 1, 0};
  EXPECT_EQ(pred::incircle_coplanar_perturbed(O.data(), X.data(), Y.data(), inside.data(), q.data()), 1);
  EXPECT_EQ(pred::incircle_coplanar_perturbed(X.data(), O.data(), Y.data(), inside.data(), q.data()), 1);
  EXPECT_EQ(pred::incircle_coplanar_perturbed(O.data(), X.data(), Y.data(), outside.data(), q.data()), -1);
  const P3 q2{0.7, -0.1, -3};  // the answer must not depend on the reference point's side
  const int s = pred::incircle_coplanar_perturbed(O.data(), X.data(), Y.data(), on.data(), q.data());
  EXPECT_NE(s, 0);
  EXPECT_EQ(s, pred::incircle_coplanar_perturbed(O.data(), X.data(), Y.data(), on.data(), q2.data()));
  EXPECT_EQ(s, pred::incircle_coplanar_perturbed(Y.data(), O.data(), X.data(), on.data(), q2.data()));
}

}  // namespace
}  // namespace kdmesh
