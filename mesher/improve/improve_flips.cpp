// kdmesh — edge removal and face removal (mesher/improve/improve_flips.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_flips.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mesher/improve/improve_quality.h"

namespace kdmesh {

double sine_of(const ImproveTets& m, std::uint32_t t) {
  const std::uint32_t* v = m.v(t);
  return tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3]));
}

double min_sine(const ImproveTets& m, const std::vector<std::uint32_t>& ids) {
  double q = std::numeric_limits<double>::infinity();
  for (std::uint32_t t : ids) q = std::min(q, sine_of(m, t));
  return q;
}

bool flip_valid(const ImproveTets& m, const FlipCandidate& c) {
  const std::vector<std::uint32_t>& fresh = c.fresh;
  for (std::size_t k = 0; k < fresh.size(); k += 4) {
    const double* p[4] = {m.p(fresh[k]), m.p(fresh[k + 1]), m.p(fresh[k + 2]), m.p(fresh[k + 3])};
    if (!tet_valid(p[0], p[1], p[2], p[3]) || !m.inside_ok_replacing(&fresh[k], p, c.old)) return false;
  }
  return true;
}

namespace {

constexpr int kMaxRing = 16;

/// The triangulation of the polygon ring[0..n-1] (closed by the edge (r_0, r_{n-1})) that
/// maximises the smallest tet_sine of the tets (r_i r_j r_k a) and (r_i r_k r_j b), above
/// `cut` (dynamic programme over sub-polygons): its tets go to out.fresh (the first two hold
/// the edge (r_0, r_{n-1})), its worst to out.q_new. False if none beats `cut` with positive
/// tets.
bool best_triangulation(const ImproveTets& m, const std::vector<std::uint32_t>& ring,
                        std::uint32_t a, std::uint32_t b, double cut, FlipCandidate& out) {
  const int n = int(ring.size());
  if (n < 3 || n > kMaxRing) return false;
  // Triangle (r_i, r_k, r_j), i < k < j, of the ring polygon: the tets (r_i r_j r_k a) and
  // (r_i r_k r_j b). With the ring ordered so that (a, b, r_i, r_{i+1}) is positive, the ring
  // turns clockwise seen from a, so those two are the positive orders (checked exactly later).
  double best[kMaxRing][kMaxRing];
  int arg[kMaxRing][kMaxRing];
  const double inf = std::numeric_limits<double>::infinity();
  const double* pa = m.p(a);
  const double* pb = m.p(b);
  // The second tet only when the first is above `above`: otherwise the split loses anyway.
  auto tri_q = [&](int i, int k, int j, double above) {
    const double *ri = m.p(ring[i]), *rk = m.p(ring[k]), *rj = m.p(ring[j]);
    const double qa = tet_sine(ri, rj, rk, pa);
    if (!(qa > above)) return qa;
    return std::min(qa, tet_sine(ri, rk, rj, pb));
  };
  for (int i = 0; i + 1 < n; ++i) best[i][i + 1] = inf, arg[i][i + 1] = -1;
  for (int len = 2; len < n; ++len)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      double bq = cut;
      int bk = -1;
      for (int k = i + 1; k < j; ++k) {
        double q = std::min(best[i][k], best[k][j]);
        if (q <= bq) continue;  // this split cannot beat the best one
        q = std::min(q, tri_q(i, k, j, bq));
        if (q > bq) bq = q, bk = k;
      }
      best[i][j] = bk >= 0 ? bq : -inf;
      arg[i][j] = bk;
    }
  out.q_new = best[0][n - 1];
  if (arg[0][n - 1] < 0 || !(out.q_new > 0)) return false;
  // Reconstruct, the root triangle first.
  int stack[2 * kMaxRing][2], sp = 0;
  stack[sp][0] = 0, stack[sp][1] = n - 1, ++sp;
  while (sp > 0) {
    --sp;
    const int i = stack[sp][0], j = stack[sp][1];
    if (j - i < 2) continue;
    const int k = arg[i][j];
    out.fresh.insert(out.fresh.end(), {ring[i], ring[j], ring[k], a, ring[i], ring[k], ring[j], b});
    stack[sp][0] = i, stack[sp][1] = k, ++sp;
    stack[sp][0] = k, stack[sp][1] = j, ++sp;
  }
  return true;
}

/// Smallest tet_sine of the tets `old`, from `sines` if given.
double old_sine(const ImproveTets& m, const std::vector<std::uint32_t>& old, const double* sines) {
  if (!sines) return min_sine(m, old);
  double q = std::numeric_limits<double>::infinity();
  for (std::uint32_t o : old) q = std::min(q, sines[o]);
  return q;
}

}  // namespace

bool edge_removal(const ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                  int max_ring, FlipCandidate& out, double floor, const double* sines,
                  bool validate) {
  static thread_local std::vector<std::uint32_t> ring;
  out.old.clear();
  out.fresh.clear();
  out.q_new = -1;
  if (!m.edge_ring(t, a, b, ring, out.old)) return false;
  const int n = int(ring.size());
  if (n < 3 || n > max_ring) return false;
  out.q_old = old_sine(m, out.old, sines);
  // Only triangulations better than `floor` and than the ring's own tets are of interest:
  // sub-polygons that cannot beat it are cut off without evaluating their tets.
  if (!best_triangulation(m, ring, a, b, std::max(floor, out.q_old), out)) return false;
  return !validate || flip_valid(m, out);
}

bool boundary_edge_removal(const ImproveTets& m, std::uint32_t t, std::uint32_t a, std::uint32_t b,
                           int max_ring, const BoundaryContext& ctx, FlipCandidate& out,
                           double floor, const double* sines, std::uint32_t* star_read,
                           const StarAccess& access) {
  static thread_local std::vector<std::uint32_t> ring, star;
  out.old.clear();
  out.fresh.clear();
  out.q_new = -1;
  const NodeSet& nodes = m.nodes();
  if (nodes.kind[a] == NodeKind::interior || nodes.kind[b] == NodeKind::interior) return false;
  if (!m.open_edge_ring(t, a, b, max_ring - 1, ring, out.old)) return false;
  const std::size_t n = ring.size();
  if (n < 3) return false;  // one tet: a cap (mesher/improve/improve_caps.h)
  if (nodes.kind[a] != NodeKind::surface && nodes.kind[b] != NodeKind::surface &&
      keeps_feature(m, a, b, ctx))
    return false;  // a feature edge stays
  // The new boundary edge (r_0, r_m) must not be an edge already.
  const std::uint32_t r0 = ring.front(), rm = ring.back();
  if (star_read) *star_read = r0;
  if (!access.ok(r0)) return false;
  m.star(r0, star);
  for (std::uint32_t s : star)
    if (index_in(m.v(s), rm) >= 0) return false;
  out.q_old = old_sine(m, out.old, sines);
  if (!best_triangulation(m, ring, a, b, std::max(floor, out.q_old), out)) return false;
  if (!flip_valid(m, out)) return false;
  // The new boundary faces, outward: of the root tets (r_0 r_m r_k a) and (r_0 r_k r_m b), the
  // faces opposite r_k, (r_0, r_m, a) and (r_0, b, r_m).
  return face_on_surface(m.p(r0), m.p(rm), m.p(a), ctx) &&
         face_on_surface(m.p(r0), m.p(b), m.p(rm), ctx);
}

bool face_removal(const ImproveTets& m, std::uint32_t t, int i, FlipCandidate& out,
                  const double* sines, bool validate, double floor) {
  out.old.clear();
  out.fresh.clear();
  out.q_new = -1;
  const std::uint32_t r = m.adj(t, i);
  if (r == kImproveNone) return false;
  const std::uint32_t* v = m.v(t);
  const std::uint32_t u = r >> 2;
  const std::uint32_t p = v[i], q = m.v(u)[r & 3];
  // kTetFace is outward from t (p on its negative side); reversed, p is on the positive side.
  const std::uint32_t x = v[kTetFace[i][0]], y = v[kTetFace[i][2]], z = v[kTetFace[i][1]];
  out.old = {t, u};
  out.q_old = sines ? std::min(sines[t], sines[u]) : std::min(sine_of(m, t), sine_of(m, u));
  out.fresh = {x, y, q, p, y, z, q, p, z, x, q, p};
  double qn = std::numeric_limits<double>::infinity();
  const double cut = std::max(floor, 0.0);
  for (std::size_t k = 0; k < out.fresh.size(); k += 4) {
    qn = std::min(qn, tet_sine(m.p(out.fresh[k]), m.p(out.fresh[k + 1]), m.p(out.fresh[k + 2]),
                               m.p(out.fresh[k + 3])));
    if (!(qn > cut)) {
      out.q_new = qn;
      return false;
    }
  }
  out.q_new = qn;
  return !validate || flip_valid(m, out);
}

}  // namespace kdmesh
