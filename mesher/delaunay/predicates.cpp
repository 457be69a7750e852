// kdmesh — exact slow paths of the geometric predicates, and symbolic perturbation.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/delaunay/predicates.h"

#include <gmp.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "mesher/delaunay/wide_int.h"

namespace kdmesh::pred {

namespace {

thread_local std::uint64_t t_exact_calls = 0;

/// Scratch big integers, initialised once per thread (no allocation in steady state).
struct Scratch {
  static constexpr int kRegs = 48;
  mpz_t r[kRegs];
  Scratch() {
    for (auto& z : r) mpz_init2(z, 256);
  }
  ~Scratch() {
    for (auto& z : r) mpz_clear(z);
  }
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

/// Loads `count` coordinates (3 per point) into big integers sharing one power-of-two scale:
/// value = out / 2^(-emin). Every finite double is m * 2^e with an integer |m| < 2^53, so the
/// scaled values are exact integers; a common positive scale preserves determinant signs
/// (the determinants are homogeneous in the coordinate differences).
void load_scaled(const double* const* pts, int npts, mpz_t* out) {
  int emin = 0;
  bool any = false;
  long long mant[15];
  int expo[15];
  for (int i = 0; i < npts; ++i)
    for (int k = 0; k < 3; ++k) {
      const double v = pts[i][k];
      const int idx = 3 * i + k;
      if (v == 0.0) {
        mant[idx] = 0;
        expo[idx] = 0;
        continue;
      }
      int e;
      const double m = std::frexp(v, &e);  // v = m * 2^e, 0.5 <= |m| < 1
      mant[idx] = static_cast<long long>(std::ldexp(m, 53));
      expo[idx] = e - 53;
      if (!any || expo[idx] < emin) emin = expo[idx];
      any = true;
    }
  for (int idx = 0; idx < 3 * npts; ++idx) {
    mpz_set_si(out[idx], mant[idx]);
    if (mant[idx] != 0) mpz_mul_2exp(out[idx], out[idx], static_cast<mp_bitcnt_t>(expo[idx] - emin));
  }
}

/// out = x*y - z*w
void cross2(mpz_t out, const mpz_t x, const mpz_t y, const mpz_t z, const mpz_t w, mpz_t tmp) {
  mpz_mul(out, x, y);
  mpz_mul(tmp, z, w);
  mpz_sub(out, out, tmp);
}

// ---- Fast exact stage: 64-bit integers and fixed-width products ----------------------------
//
// When the coordinate differences a predicate needs are exact in double (always true for
// points within a factor of 2 of each other, Sterbenz), and all of them are integer multiples
// of one power of two 2^lo with magnitude below 2^(lo + 62), each difference is an int64 x with
// |x| < 2^62 and the determinant is a polynomial in those integers, evaluated exactly below
// in fixed widths (mesher/delaunay/wide_int.h):
//   2x2 minors < 2^125 (__int128), 3x3 minors < 3 2^187 < 2^189 (3 limbs),
//   lifts < 3 2^124 < 2^126 (__int128), insphere's four lift x minor terms < 4 2^315 = 2^317
//   (5 limbs). Every width leaves at least 2 bits of headroom.
// The common scale 2^lo is positive, so signs are those of the determinants in the doubles'
// own values. Otherwise (an inexact difference, exponents spread over more than 62 bits,
// subnormal or non-finite values) the GMP path below computes from the coordinates.

/// d = a - b, exactly: false when the rounded difference is not exact (Knuth's TwoSum tail).
inline bool exact_diff(double a, double b, double& d) {
  const double x = a - b;
  const double bv = a - x;
  const double av = x + bv;
  const double tail = (a - av) + (bv - b);
  d = x;
  return tail == 0.0;
}

/// Converts n exact doubles to integers sharing a scale 2^lo (|out[i]| < 2^62); false if that
/// is impossible (see above).
bool scale_to_int64(const double* d, int n, std::int64_t* out) {
  std::uint64_t mant[12];
  int low[12];
  int lo = 1 << 20, hi = -(1 << 20);
  for (int i = 0; i < n; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, &d[i], sizeof bits);
    bits &= ~(std::uint64_t(1) << 63);
    if (bits == 0) {
      mant[i] = 0;
      continue;
    }
    const int e = int(bits >> 52);
    if (e == 0 || e == 0x7ff) return false;  // subnormal, inf or NaN
    const std::uint64_t m = (bits & ((std::uint64_t(1) << 52) - 1)) | (std::uint64_t(1) << 52);
    const int tz = __builtin_ctzll(m);
    mant[i] = m >> tz;
    low[i] = e - 1075 + tz;  // |d| = mant 2^low
    lo = std::min(lo, low[i]);
    hi = std::max(hi, e - 1075 + 53);  // |d| < 2^hi
  }
  if (hi - lo > 62) return false;
  for (int i = 0; i < n; ++i) {
    const std::int64_t v = mant[i] == 0 ? 0 : std::int64_t(mant[i] << (low[i] - lo));
    out[i] = d[i] < 0 ? -v : v;
  }
  return true;
}

/// rows[i] - base for nrows <= 4 rows, as integers of one scale; false when any difference is
/// inexact or the scale does not fit (see scale_to_int64).
bool int_rows(const double* const* rows, int nrows, const double* base, std::int64_t* out) {
  double d[12];
  for (int i = 0; i < nrows; ++i)
    for (int k = 0; k < 3; ++k)
      if (!exact_diff(rows[i][k], base[k], d[3 * i + k])) return false;
  return scale_to_int64(d, 3 * nrows, out);
}

inline __int128 minor2(std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d) {
  return __int128(a) * b - __int128(c) * d;
}

/// x * m for an int64 and a 2-limb minor: 3 limbs.
inline wide::Int<3> times(std::int64_t x, __int128 m) {
  return wide::mul(wide::from_i64(x), wide::from_i128(m));
}

}  // namespace

std::uint64_t exact_calls() { return t_exact_calls; }

/// Sign of det[b-a, c-a, d-a] in integers, or 2 when the fast stage does not apply.
int detail::orient3d_int(const double* a, const double* b, const double* c, const double* d) {
  const double* rows[3] = {b, c, d};
  std::int64_t v[9];
  if (!int_rows(rows, 3, a, v)) return 2;
  const std::int64_t *ba = v, *ca = v + 3, *da = v + 6;
  wide::Int<3> det = times(ba[0], minor2(ca[1], da[2], ca[2], da[1]));
  det = wide::add(det, times(ba[1], minor2(ca[2], da[0], ca[0], da[2])));
  det = wide::add(det, times(ba[2], minor2(ca[0], da[1], ca[1], da[0])));
  return wide::sign(det);
}

/// Sign of Shewchuk's insphere determinant (insphere_exact's convention applied), or 2.
int detail::insphere_int(const double* a, const double* b, const double* c, const double* d,
                         const double* e) {
  const double* rows[4] = {a, b, c, d};
  std::int64_t v[12];
  if (!int_rows(rows, 4, e, v)) return 2;
  const std::int64_t *ae = v, *be = v + 3, *ce = v + 6, *de = v + 9;
  const __int128 ab = minor2(ae[0], be[1], be[0], ae[1]);
  const __int128 bc = minor2(be[0], ce[1], ce[0], be[1]);
  const __int128 cd = minor2(ce[0], de[1], de[0], ce[1]);
  const __int128 da = minor2(de[0], ae[1], ae[0], de[1]);
  const __int128 ac = minor2(ae[0], ce[1], ce[0], ae[1]);
  const __int128 bd = minor2(be[0], de[1], de[0], be[1]);
  using wide::add;
  using wide::sub;
  const wide::Int<3> abc = add(sub(times(ae[2], bc), times(be[2], ac)), times(ce[2], ab));
  const wide::Int<3> bcd = add(sub(times(be[2], cd), times(ce[2], bd)), times(de[2], bc));
  const wide::Int<3> cda = add(add(times(ce[2], da), times(de[2], ac)), times(ae[2], cd));
  const wide::Int<3> dab = add(add(times(de[2], ab), times(ae[2], bd)), times(be[2], da));
  auto lift = [](const std::int64_t* r) {
    return wide::from_i128(__int128(r[0]) * r[0] + __int128(r[1]) * r[1] + __int128(r[2]) * r[2]);
  };
  // det = (dlift*abc - clift*dab) + (blift*cda - alift*bcd)
  wide::Int<5> det = sub(wide::mul(lift(de), abc), wide::mul(lift(ce), dab));
  det = add(det, sub(wide::mul(lift(be), cda), wide::mul(lift(ae), bcd)));
  return -wide::sign(det);  // Shewchuk's sign is opposite to kdmesh's orientation convention
}

int orient3d_permanent(const double* a, const double* b, const double* c, const double* d) {
  const detail::Eval r = detail::orient3d_eval<true>(a, b, c, d);
  const double bound = kOrient3dBound * r.permanent;
  if (r.det > bound) return 1;
  if (-r.det > bound) return -1;
  return orient3d_exact(a, b, c, d);
}

int insphere_permanent(const double* a, const double* b, const double* c, const double* d,
                       const double* e) {
  const detail::Eval r = detail::insphere_eval<true>(a, b, c, d, e);
  const double bound = kInsphereBound * r.permanent;
  if (r.det > bound) return -1;  // Shewchuk's sign is opposite to kdmesh's convention
  if (-r.det > bound) return 1;
  return insphere_exact(a, b, c, d, e);
}

int orient3d_exact(const double* a, const double* b, const double* c, const double* d) {
  ++t_exact_calls;
  const int fast = detail::orient3d_int(a, b, c, d);
  return fast != 2 ? fast : detail::orient3d_gmp(a, b, c, d);
}

int insphere_exact(const double* a, const double* b, const double* c, const double* d,
                   const double* e) {
  ++t_exact_calls;
  const int fast = detail::insphere_int(a, b, c, d, e);
  return fast != 2 ? fast : detail::insphere_gmp(a, b, c, d, e);
}

int detail::orient3d_gmp(const double* a, const double* b, const double* c, const double* d) {
  Scratch& s = scratch();
  mpz_t* r = s.r;
  const double* pts[4] = {a, b, c, d};
  load_scaled(pts, 4, r);  // r[0..11]
  // differences against a: r[12..20] = b-a, c-a, d-a
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) mpz_sub(r[12 + 3 * i + k], r[3 * (i + 1) + k], r[k]);
  mpz_t *ba = r + 12, *ca = r + 15, *da = r + 18;
  mpz_t& m = r[21];
  mpz_t& acc = r[22];
  mpz_t& tmp = r[23];
  mpz_t& t2 = r[24];
  // det = ba.x (ca.y da.z - ca.z da.y) + ba.y (ca.z da.x - ca.x da.z) + ba.z (ca.x da.y - ca.y da.x)
  cross2(m, ca[1], da[2], ca[2], da[1], tmp);
  mpz_mul(acc, ba[0], m);
  cross2(m, ca[2], da[0], ca[0], da[2], tmp);
  mpz_mul(t2, ba[1], m);
  mpz_add(acc, acc, t2);
  cross2(m, ca[0], da[1], ca[1], da[0], tmp);
  mpz_mul(t2, ba[2], m);
  mpz_add(acc, acc, t2);
  return mpz_sgn(acc);
}

int detail::insphere_gmp(const double* a, const double* b, const double* c, const double* d,
                         const double* e) {
  Scratch& s = scratch();
  mpz_t* r = s.r;
  const double* pts[5] = {a, b, c, d, e};
  load_scaled(pts, 5, r);  // r[0..14]
  // rows: r[15..26] = (a-e), (b-e), (c-e), (d-e)
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) mpz_sub(r[15 + 3 * i + k], r[3 * i + k], r[12 + k]);
  mpz_t *ae = r + 15, *be = r + 18, *ce = r + 21, *de = r + 24;
  mpz_t &ab = r[27], &bc = r[28], &cd = r[29], &da = r[30], &ac = r[31], &bd = r[32];
  mpz_t& tmp = r[33];
  cross2(ab, ae[0], be[1], be[0], ae[1], tmp);
  cross2(bc, be[0], ce[1], ce[0], be[1], tmp);
  cross2(cd, ce[0], de[1], de[0], ce[1], tmp);
  cross2(da, de[0], ae[1], ae[0], de[1], tmp);
  cross2(ac, ae[0], ce[1], ce[0], ae[1], tmp);
  cross2(bd, be[0], de[1], de[0], be[1], tmp);
  mpz_t &abc = r[34], &bcd = r[35], &cda = r[36], &dab = r[37];
  // abc = aez*bc - bez*ac + cez*ab
  mpz_mul(abc, ae[2], bc);
  mpz_mul(tmp, be[2], ac);
  mpz_sub(abc, abc, tmp);
  mpz_mul(tmp, ce[2], ab);
  mpz_add(abc, abc, tmp);
  // bcd = bez*cd - cez*bd + dez*bc
  mpz_mul(bcd, be[2], cd);
  mpz_mul(tmp, ce[2], bd);
  mpz_sub(bcd, bcd, tmp);
  mpz_mul(tmp, de[2], bc);
  mpz_add(bcd, bcd, tmp);
  // cda = cez*da + dez*ac + aez*cd
  mpz_mul(cda, ce[2], da);
  mpz_mul(tmp, de[2], ac);
  mpz_add(cda, cda, tmp);
  mpz_mul(tmp, ae[2], cd);
  mpz_add(cda, cda, tmp);
  // dab = dez*ab + aez*bd + bez*da
  mpz_mul(dab, de[2], ab);
  mpz_mul(tmp, ae[2], bd);
  mpz_add(dab, dab, tmp);
  mpz_mul(tmp, be[2], da);
  mpz_add(dab, dab, tmp);
  // lifts
  mpz_t* lift = r + 38;  // 4 registers
  mpz_t* rows[4] = {ae, be, ce, de};
  for (int i = 0; i < 4; ++i) {
    mpz_mul(lift[i], rows[i][0], rows[i][0]);
    mpz_addmul(lift[i], rows[i][1], rows[i][1]);
    mpz_addmul(lift[i], rows[i][2], rows[i][2]);
  }
  mpz_t& det = r[42];
  // det = (dlift*abc - clift*dab) + (blift*cda - alift*bcd)
  mpz_mul(det, lift[3], abc);
  mpz_submul(det, lift[2], dab);
  mpz_addmul(det, lift[1], cda);
  mpz_submul(det, lift[0], bcd);
  return -mpz_sgn(det);  // Shewchuk's sign is opposite to kdmesh's orientation convention
}

bool collinear(const double* a, const double* b, const double* c) {
  ++t_exact_calls;
  Scratch& s = scratch();
  mpz_t* r = s.r;
  const double* pts[3] = {a, b, c};
  load_scaled(pts, 3, r);  // r[0..8]
  mpz_t *u = r + 9, *v = r + 12;
  for (int k = 0; k < 3; ++k) {
    mpz_sub(u[k], r[3 + k], r[k]);
    mpz_sub(v[k], r[6 + k], r[k]);
  }
  mpz_t &m = r[15], &tmp = r[16];
  // (b-a) x (c-a) == 0 componentwise
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    cross2(m, u[i], v[j], u[j], v[i], tmp);
    if (mpz_sgn(m) != 0) return false;
  }
  return true;
}

namespace {

/// Moves the point of highest perturbation priority (lexicographically largest) among
/// p[k..N) to p[k]: called for k = 0, 1, ... it visits the points in decreasing priority, the
/// order of a sort, but the tie-breaks mostly stop at the first or second point, and a sort of
/// all of them took most of insphere_tiebreak's time (its comparisons are coin tosses).
template <int N>
const double* next_by_priority(const double* (&p)[N], int k) {
  for (int j = k + 1; j < N; ++j)
    if (lex_less(p[k], p[j])) std::swap(p[k], p[j]);
  return p[k];
}

}  // namespace

int insphere_tiebreak(const double* a, const double* b, const double* c, const double* d,
                      const double* e) {
  // e is exactly on the sphere. Perturb the lifted coordinate of point i by eps^(rank), the
  // lexicographically largest point getting the dominant term. The coefficient of point X's
  // term is (up to sign) the orientation of the other four with e in X's place.
  const double* p[5] = {a, b, c, d, e};
  for (int k = 0; k < 5; ++k) {
    const double* x = next_by_priority(p, k);
    if (x == e) return -1;  // (a,b,c,d) positively oriented: e's own term says "outside"
    int o = 0;
    if (x == d) o = orient3d(a, b, c, e);
    else if (x == c) o = orient3d(a, b, e, d);
    else if (x == b) o = orient3d(a, e, c, d);
    else o = orient3d(e, b, c, d);
    if (o != 0) return o;
  }
  assert(false && "insphere_perturbed: (a,b,c,d) must be positively oriented");
  return -1;
}

int incircle_coplanar_perturbed(const double* a, const double* b, const double* c,
                                const double* e, const double* q) {
  const int side = orient3d(a, b, c, q);  // orientation of (a,b,c) seen from q; never 0
  assert(side != 0);
  // The sphere through a, b, c, q cuts the plane of (a,b,c) in their circumcircle.
  const int s = side > 0 ? insphere(a, b, c, q, e) : insphere(b, a, c, q, e);
  if (s != 0) return s;
  const double* p[4] = {a, b, c, e};
  for (int k = 0; k < 4; ++k) {
    const double* x = next_by_priority(p, k);
    if (x == e) return -1;
    int o = 0;
    if (x == c) o = orient3d(a, b, e, q);
    else if (x == b) o = orient3d(a, e, c, q);
    else o = orient3d(e, b, c, q);
    if (o != 0) return o * side;
  }
  assert(false && "incircle_coplanar_perturbed: (a,b,c) must not be collinear");
  return -1;
}

}  // namespace kdmesh::pred
