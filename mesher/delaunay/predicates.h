// kdmesh — exact geometric predicates with a floating-point filter.
//
// Sign conventions (kdmesh-wide, same as CGAL and VTK_TETRA):
//   orient3d(a,b,c,d) = sign det[b-a, c-a, d-a]
//       > 0  when d lies on the side of plane (a,b,c) that (b-a)x(c-a) points to;
//       (0, e1, e2, e3) is positive.
//   insphere(a,b,c,d,e), for positively oriented (a,b,c,d):
//       > 0  when e lies strictly inside the circumsphere, < 0 outside, 0 on it.
//
// Every function returns the exact sign (-1, 0, +1) for any finite double input: a fast
// floating-point evaluation is accepted when an error bound proves the sign; otherwise the
// determinant is evaluated exactly in integer arithmetic (every double is an integer times a
// power of two): in 64-bit integers and fixed-width products when the coordinate differences
// allow it (nearby points, e.g. lattice ties), else in GMP integers. Two bounds, both from
// Shewchuk's stage-A analysis (error <= c*eps*permanent, c = 7 for orient3d, 16 for insphere,
// for exactly this evaluation order):
//  - semi-static (cheap): for orient3d the permanent is bounded by the largest coordinate
//    differences m_x, m_y, m_z: permanent <= 6 m_x m_y m_z. For insphere it is bounded by the
//    lifts L_a..L_d the evaluation computes anyway (see "insphere lift bound" below). Valid while
//    those products neither underflow nor overflow, which the range checks guarantee;
//  - otherwise (out of range, or for insphere also when the lift bound cannot decide) the
//    permanent itself is computed (any finite input).
// The code requires IEEE double arithmetic without FMA contraction (-ffp-contract=off).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace kdmesh::pred {

/// Exact slow paths (mesher/delaunay/predicates.cpp). Count their calls in exact_calls().
int orient3d_exact(const double* a, const double* b, const double* c, const double* d);
int insphere_exact(const double* a, const double* b, const double* c, const double* d,
                   const double* e);
namespace detail {
/// The exact stage's two paths, public for the tests. The fast one works on the coordinate
/// differences as 64-bit integers of one scale and fixed-width products; it returns 2 when it
/// does not apply (an inexact difference, exponents spread over more than 62 bits, subnormal
/// or non-finite values). The general one computes in GMP integers from the coordinates.
int orient3d_int(const double* a, const double* b, const double* c, const double* d);
int insphere_int(const double* a, const double* b, const double* c, const double* d,
                 const double* e);
int orient3d_gmp(const double* a, const double* b, const double* c, const double* d);
int insphere_gmp(const double* a, const double* b, const double* c, const double* d,
                 const double* e);
}  // namespace detail
/// True if a, b, c lie on one line (exact).
bool collinear(const double* a, const double* b, const double* c);
/// Number of exact evaluations performed by this thread so far.
std::uint64_t exact_calls();

inline constexpr double kEps = 0x1p-53;  // unit roundoff of IEEE double
inline constexpr double kOrient3dBound = (7.0 + 56.0 * kEps) * kEps;
inline constexpr double kInsphereBound = (16.0 + 224.0 * kEps) * kEps;
// Semi-static constant of orient3d: 6 * 7 eps = 4.663e-15, rounded up by more than 0.5% to
// absorb the O(eps) rounding of the bound's own products.
inline constexpr double kOrient3dStatic = 4.7e-15;
// Insphere lift bound (2026-11-21; replaces 72 M^2 m_x m_y m_z, which cost ~50 instructions of
// fabs/max per call). Notation: x_i, y_i, z_i the computed differences of row i in {a,b,c,d}
// (i - e), L_i = fl(x_i^2 + y_i^2 + z_i^2) the computed lift, lambda_i the exact sum of squares,
// so lambda_i <= L_i (1 + 4 eps) (a square that underflows adds at most 2^-1074, negligible
// against L_i >= 1e-50, the range below). The permanent of insphere_eval<true> is
//   P = sum_d L_d * sum over the 6 permutations (i,j,k) of the other three rows of
//       |x_i| |y_j| |z_k|,
// and |x_i| |y_j| |z_k| <= sqrt(lambda_i lambda_j lambda_k), hence
//   P <= 6 (1 + 6 eps) sum_d L_d sqrt(prod_{i != d} L_i)
//      = 6 (1 + 6 eps) sqrt(L_a L_b L_c L_d) sum_d sqrt(L_d)
//     <= 24 (1 + 6 eps) sqrt(Q),   Q = L_a L_b L_c L_d Lmax,  Lmax = max_i L_i.
// With |det - fl(det)| <= (16 + 224 eps) eps P, the sign of fl(det) is proven when
// fl(det)^2 > K^2 Q, K = 24 (16 + 224 eps)(1 + 6 eps) eps <= 384 eps (1 + 21 eps) = 4.2633e-14.
// The code tests fl(fl(det) * fl(det)) > fl(kInsphereLiftStatic * Qf), Qf the computed product
// ((L_a L_b)(L_c L_d)) Lmax (4 roundings): that test implies
//   fl(det)^2 >= fl(det^2) / (1 + eps) > kInsphereLiftStatic Q (1 - eps)^5 / (1 + eps),
// which is >= K^2 Q as kInsphereLiftStatic = 1.83e-27 >= K^2 (1 + 7 eps) = 1.8175e-27 (0.7%
// margin). Range: Lmin >= 1e-50 and Lmax <= 1e60 keep every product normal: Q in
// [1e-250, 1e300], kInsphereLiftStatic Q >= 1.8e-277, |fl(det)| <= 1.01 * 24 sqrt(Q), so
// fl(det)^2 <= 6e302; a subnormal or zero fl(det)^2 cannot pass the test. Outside that range
// the permanent itself is computed (insphere_permanent). The bound is about as tight as the old
// one on well-shaped input (sqrt(Q) ~ r^5 against 72 M^5 with r the row norm).
inline constexpr double kInsphereLiftStatic = 1.83e-27;

/// Out-of-line filters with the permanent as bound: for inputs outside the semi-static range.
int orient3d_permanent(const double* a, const double* b, const double* c, const double* d);
int insphere_permanent(const double* a, const double* b, const double* c, const double* d,
                       const double* e);

namespace detail {
// Plain comparisons compile to maxsd/minsd (std::fmax/fmin carry NaN rules; inputs are finite).
inline double max2(double x, double y) { return x > y ? x : y; }
inline double min2(double x, double y) { return x < y ? x : y; }

/// A determinant evaluated in floating point with the scale of its error bound: the largest
/// coordinate differences (orient3d) or the lifts (insphere) for the semi-static bound, or the
/// permanent (kPermanent).
struct Eval {
  double det;
  double mx, my, mz;  // orient3d_eval<false>: largest |difference| per axis (semi-static scale)
  double permanent;   // only with kPermanent
  double lift_min, lift_max, lift_q;  // insphere_eval<false>: min, max lift, Q (see above)
};

/// det[b-a, c-a, d-a] in one fixed evaluation order (the one the bounds are derived for).
template <bool kPermanent>
[[gnu::always_inline]] inline Eval orient3d_eval(const double* a, const double* b, const double* c, const double* d) {
  const double bax = b[0] - a[0], bay = b[1] - a[1], baz = b[2] - a[2];
  const double cax = c[0] - a[0], cay = c[1] - a[1], caz = c[2] - a[2];
  const double dax = d[0] - a[0], day = d[1] - a[1], daz = d[2] - a[2];
  const double m1 = cay * daz, m2 = caz * day;
  const double m3 = caz * dax, m4 = cax * daz;
  const double m5 = cax * day, m6 = cay * dax;
  Eval r{};
  r.det = bax * (m1 - m2) + bay * (m3 - m4) + baz * (m5 - m6);
  if constexpr (kPermanent) {
    r.permanent = std::fabs(bax) * (std::fabs(m1) + std::fabs(m2)) +
                  std::fabs(bay) * (std::fabs(m3) + std::fabs(m4)) +
                  std::fabs(baz) * (std::fabs(m5) + std::fabs(m6));
  } else {
    r.mx = max2(std::fabs(bax), max2(std::fabs(cax), std::fabs(dax)));
    r.my = max2(std::fabs(bay), max2(std::fabs(cay), std::fabs(day)));
    r.mz = max2(std::fabs(baz), max2(std::fabs(caz), std::fabs(daz)));
  }
  return r;
}

/// Shewchuk's insphere determinant det[[a-e, |a-e|^2], ..., [d-e, |d-e|^2]]: > 0 when e is
/// inside for (a,b,c,d) negatively oriented in kdmesh's convention (callers negate).
template <bool kPermanent>
[[gnu::always_inline]] inline Eval insphere_eval(const double* a, const double* b, const double* c, const double* d,
                          const double* e) {
  const double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
  const double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
  const double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
  const double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];

  const double aexbey = aex * bey, bexaey = bex * aey, ab = aexbey - bexaey;
  const double bexcey = bex * cey, cexbey = cex * bey, bc = bexcey - cexbey;
  const double cexdey = cex * dey, dexcey = dex * cey, cd = cexdey - dexcey;
  const double dexaey = dex * aey, aexdey = aex * dey, da = dexaey - aexdey;
  const double aexcey = aex * cey, cexaey = cex * aey, ac = aexcey - cexaey;
  const double bexdey = bex * dey, dexbey = dex * bey, bd = bexdey - dexbey;

  const double abc = aez * bc - bez * ac + cez * ab;
  const double bcd = bez * cd - cez * bd + dez * bc;
  const double cda = cez * da + dez * ac + aez * cd;
  const double dab = dez * ab + aez * bd + bez * da;

  const double alift = aex * aex + aey * aey + aez * aez;
  const double blift = bex * bex + bey * bey + bez * bez;
  const double clift = cex * cex + cey * cey + cez * cez;
  const double dlift = dex * dex + dey * dey + dez * dez;

  Eval r{};
  r.det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
  if constexpr (kPermanent) {
    const double paz = std::fabs(aez), pbz = std::fabs(bez), pcz = std::fabs(cez),
                 pdz = std::fabs(dez);
    const double pab = std::fabs(aexbey) + std::fabs(bexaey);
    const double pbc = std::fabs(bexcey) + std::fabs(cexbey);
    const double pcd = std::fabs(cexdey) + std::fabs(dexcey);
    const double pda = std::fabs(dexaey) + std::fabs(aexdey);
    const double pac = std::fabs(aexcey) + std::fabs(cexaey);
    const double pbd = std::fabs(bexdey) + std::fabs(dexbey);
    r.permanent = (pcd * pbz + pbd * pcz + pbc * pdz) * alift +
                  (pda * pcz + pac * pdz + pcd * paz) * blift +
                  (pab * pdz + pbd * paz + pda * pbz) * clift +
                  (pbc * paz + pac * pbz + pab * pcz) * dlift;
  } else {
    r.lift_max = max2(max2(alift, blift), max2(clift, dlift));
    r.lift_min = min2(min2(alift, blift), min2(clift, dlift));
    r.lift_q = ((alift * blift) * (clift * dlift)) * r.lift_max;
  }
  return r;
}
}  // namespace detail

[[gnu::always_inline]] inline int orient3d(const double* a, const double* b, const double* c, const double* d) {
  using detail::max2;
  using detail::min2;
  const detail::Eval r = detail::orient3d_eval<false>(a, b, c, d);
  const double lo = min2(r.mx, min2(r.my, r.mz)), hi = max2(r.mx, max2(r.my, r.mz));
  if (!(lo >= 1e-97 && hi <= 1e102)) return orient3d_permanent(a, b, c, d);  // products of 3
  const double bound = kOrient3dStatic * (r.mx * r.my * r.mz);                  // in [1e-291, 1e306]
  if (r.det > bound) return 1;
  if (-r.det > bound) return -1;
  return orient3d_exact(a, b, c, d);
}

namespace detail {
/// The lift bound's verdict on insphere_eval<false>'s result (see kInsphereLiftStatic): the
/// sign in kdmesh's convention when det^2 > kInsphereLiftStatic Q proves it, 0 when it does
/// not or when the lifts are outside the bound's range.
[[gnu::always_inline]] inline int insphere_lift_sign(const Eval& r) {
  if (!(r.lift_min >= 1e-50 && r.lift_max <= 1e60)) return 0;
  if (r.det * r.det > kInsphereLiftStatic * r.lift_q)
    return r.det > 0 ? -1 : 1;  // Shewchuk's sign is opposite to kdmesh's convention
  return 0;
}
}  // namespace detail

inline int insphere(const double* a, const double* b, const double* c, const double* d,
                    const double* e) {
  const int s = detail::insphere_lift_sign(detail::insphere_eval<false>(a, b, c, d, e));
  if (s != 0) return s;
  // Undecided or out of range: the permanent bound is tighter (it follows anisotropic rows,
  // e.g. points near a line, where sqrt(Q) overestimates), then the exact evaluation.
  return insphere_permanent(a, b, c, d, e);
}

/// The lift-bound stage of insphere() for two tets at once against one point e, lane by lane
/// in SSE2 (t0 and t1: the tets' four vertices each). out[l] is insphere()'s sign where the
/// lift bound decides it, and 0 where insphere() would go on to the permanent filter (the
/// caller then calls it). Each lane performs exactly the IEEE operations of insphere_eval<false>
/// and insphere() in the same order (packed SSE2 arithmetic rounds like scalar SSE2; no FMA), so
/// every decided sign is the one insphere() returns.
[[gnu::always_inline]] inline void insphere_filter2(const double* const* t0, const double* const* t1,
                                                    const double* e, int out[2]) {
#if defined(__SSE2__)
  const __m128d ex = _mm_set1_pd(e[0]), ey = _mm_set1_pd(e[1]), ez = _mm_set1_pd(e[2]);
  auto row = [&](int v, int k, __m128d ek) { return _mm_sub_pd(_mm_set_pd(t1[v][k], t0[v][k]), ek); };
  const __m128d aex = row(0, 0, ex), aey = row(0, 1, ey), aez = row(0, 2, ez);
  const __m128d bex = row(1, 0, ex), bey = row(1, 1, ey), bez = row(1, 2, ez);
  const __m128d cex = row(2, 0, ex), cey = row(2, 1, ey), cez = row(2, 2, ez);
  const __m128d dex = row(3, 0, ex), dey = row(3, 1, ey), dez = row(3, 2, ez);
  auto mul = _mm_mul_pd;
  auto sub = _mm_sub_pd;
  auto add = _mm_add_pd;
  const __m128d ab = sub(mul(aex, bey), mul(bex, aey));
  const __m128d bc = sub(mul(bex, cey), mul(cex, bey));
  const __m128d cd = sub(mul(cex, dey), mul(dex, cey));
  const __m128d da = sub(mul(dex, aey), mul(aex, dey));
  const __m128d ac = sub(mul(aex, cey), mul(cex, aey));
  const __m128d bd = sub(mul(bex, dey), mul(dex, bey));
  const __m128d abc = add(sub(mul(aez, bc), mul(bez, ac)), mul(cez, ab));
  const __m128d bcd = add(sub(mul(bez, cd), mul(cez, bd)), mul(dez, bc));
  const __m128d cda = add(add(mul(cez, da), mul(dez, ac)), mul(aez, cd));
  const __m128d dab = add(add(mul(dez, ab), mul(aez, bd)), mul(bez, da));
  const __m128d alift = add(add(mul(aex, aex), mul(aey, aey)), mul(aez, aez));
  const __m128d blift = add(add(mul(bex, bex), mul(bey, bey)), mul(bez, bez));
  const __m128d clift = add(add(mul(cex, cex), mul(cey, cey)), mul(cez, cez));
  const __m128d dlift = add(add(mul(dex, dex), mul(dey, dey)), mul(dez, dez));
  const __m128d det = add(sub(mul(dlift, abc), mul(clift, dab)), sub(mul(blift, cda), mul(alift, bcd)));
  // _mm_max_pd(x, y) is x > y ? x : y and _mm_min_pd(x, y) is x < y ? x : y, as max2 and min2.
  const __m128d lmax = _mm_max_pd(_mm_max_pd(alift, blift), _mm_max_pd(clift, dlift));
  const __m128d lmin = _mm_min_pd(_mm_min_pd(alift, blift), _mm_min_pd(clift, dlift));
  const __m128d q = mul(mul(mul(alift, blift), mul(clift, dlift)), lmax);
  const __m128d in_range =
      _mm_and_pd(_mm_cmpge_pd(lmin, _mm_set1_pd(1e-50)), _mm_cmple_pd(lmax, _mm_set1_pd(1e60)));
  const __m128d decided =
      _mm_and_pd(in_range, _mm_cmpgt_pd(mul(det, det), mul(_mm_set1_pd(kInsphereLiftStatic), q)));
  const int dm = _mm_movemask_pd(decided), pm = _mm_movemask_pd(_mm_cmpgt_pd(det, _mm_setzero_pd()));
  // Arithmetic, not selects: GCC turns those into branches, mispredicted half the time.
  for (int l = 0; l < 2; ++l)
    out[l] = (dm >> l & 1) * (1 - 2 * (pm >> l & 1));  // Shewchuk's sign is opposite
#else
  const double* const* t[2] = {t0, t1};
  for (int l = 0; l < 2; ++l)
    out[l] = detail::insphere_lift_sign(detail::insphere_eval<false>(t[l][0], t[l][1], t[l][2], t[l][3], e));
#endif
}

/// The tie-break of insphere_perturbed, for e exactly on the sphere (out of line: rare).
int insphere_tiebreak(const double* a, const double* b, const double* c, const double* d,
                      const double* e);

/// Lexicographic (x, then y, then z) comparison: the priority of symbolic perturbation.
inline bool lex_less(const double* p, const double* q) {
  if (p[0] != q[0]) return p[0] < q[0];
  if (p[1] != q[1]) return p[1] < q[1];
  return p[2] < q[2];
}

/// Symbolically perturbed insphere for positively oriented (a,b,c,d) and e distinct from
/// them: never 0. Ties (e exactly on the sphere) are broken by perturbing the lifted
/// coordinate of each point, with larger perturbations for lexicographically larger
/// points (the scheme of CGAL's Delaunay_triangulation_3, so the tie-break does not depend
/// on insertion order and matches CGAL's).
inline int insphere_perturbed(const double* a, const double* b, const double* c, const double* d,
                              const double* e) {
  const int s = insphere(a, b, c, d, e);
  return s != 0 ? s : insphere_tiebreak(a, b, c, d, e);
}

/// For e coplanar with triangle (a,b,c) and q any point off that plane: > 0 if e lies
/// inside the circumcircle of (a,b,c), < 0 outside; never 0 (same perturbation scheme).
int incircle_coplanar_perturbed(const double* a, const double* b, const double* c,
                                const double* e, const double* q);

}  // namespace kdmesh::pred
