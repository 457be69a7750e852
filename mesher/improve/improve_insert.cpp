// kdmesh — node insertion of the quality-improvement pass (mesher/improve/improve_insert.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_insert.h"

#include <algorithm>
#include <cmath>

#include "mesher/improve/improve_quality.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

namespace {

constexpr std::size_t kMaxCavity = 64;  // tets

/// The worst tet_sine of the fan of x over `faces` (3 ids per face, outward of the cavity),
/// -1 if a tet of it is not valid.
double fan_quality(const ImproveTets& m, const std::vector<std::uint32_t>& faces, const double* x) {
  double worst = 1;
  for (std::size_t k = 0; k < faces.size(); k += 3) {
    // The outward face (p, q, r) with x inside: the tet (p, r, q, x) is positive.
    const std::uint32_t ids[4] = {faces[k], faces[k + 2], faces[k + 1], faces[k + 1]};
    const double* p[4] = {m.p(faces[k]), m.p(faces[k + 2]), m.p(faces[k + 1]), x};
    // inside_ok counts surface vertices by id: the face's own vertex stands for x (interior
    // x can only make that test be asked less often).
    if (!tet_valid(p[0], p[1], p[2], p[3]) || !m.inside_ok(ids, p)) return -1;
    worst = std::min(worst, tet_sine(p));
  }
  return worst;
}

/// Replaces `cavity` (connected tets of one region) by the fan around a new interior node at
/// the best of `seeds` (3 coordinates each), the centroid of the cavity's vertices and the
/// centroids of its tets, moved by a pattern search; false (nothing changed) when a cavity
/// vertex would be lost or the fan's worst tet is not better than the cavity's.
bool insert_into(ImproveTets& m, const std::vector<std::uint32_t>& cavity,
                 const std::vector<double>& seeds, std::vector<std::uint32_t>* created) {
  static thread_local std::vector<std::uint32_t> faces, verts, fresh;
  faces.clear();
  verts.clear();
  double worst_old = 1;
  for (std::uint32_t c : cavity) {
    const std::uint32_t* v = m.v(c);
    worst_old = std::min(worst_old, tet_sine(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])));
    verts.insert(verts.end(), v, v + 4);
    for (int f = 0; f < 4; ++f) {
      const std::uint32_t r = m.adj(c, f);
      if (r != kImproveNone && std::find(cavity.begin(), cavity.end(), r >> 2) != cavity.end()) continue;
      faces.insert(faces.end(), {v[kTetFace[f][0]], v[kTetFace[f][1]], v[kTetFace[f][2]]});
    }
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  for (std::uint32_t w : verts)
    if (std::find(faces.begin(), faces.end(), w) == faces.end()) return false;  // it would be lost
  double best_x[3] = {0, 0, 0}, best_q = -1, scale = 0;
  auto consider = [&](const double* x) {
    const double q = fan_quality(m, faces, x);
    if (q > best_q) best_q = q, std::copy_n(x, 3, best_x);
  };
  for (std::size_t k = 0; k + 2 < seeds.size(); k += 3) consider(&seeds[k]);
  {
    double c[3] = {0, 0, 0};
    for (std::uint32_t w : verts)
      for (int k = 0; k < 3; ++k) c[k] += m.p(w)[k] / double(verts.size());
    for (std::uint32_t w : verts)
      for (int k = 0; k < 3; ++k) scale = std::max(scale, std::abs(m.p(w)[k] - c[k]));
    consider(c);
  }
  for (std::uint32_t cv : cavity) {
    const std::uint32_t* v = m.v(cv);
    const double* p[4] = {m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])};
    double c[3];
    ImproveTets::centroid(p, c);
    consider(c);
  }
  if (!(best_q > 0)) return false;
  // Pattern search over the 26 directions to the neighbours of a cube's centre (the six axis
  // moves alone stall on the ridges of a max-min), the step halved when none is better.
  int evaluations = 0;  // a bound on the work: the moves only ever raise best_q
  for (double step = 0.25 * scale; step > 1e-3 * scale && evaluations < 2000;) {
    bool moved = false;
    for (int k = 0; k < 27 && !moved; ++k) {
      if (k == 13) continue;  // (0, 0, 0)
      const double d[3] = {double(k % 3 - 1), double(k / 3 % 3 - 1), double(k / 9 - 1)};
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      double x[3];
      for (int i = 0; i < 3; ++i) x[i] = best_x[i] + step * d[i] / len;
      const double q = fan_quality(m, faces, x);
      ++evaluations;
      if (q > best_q) best_q = q, std::copy_n(x, 3, best_x), moved = true;
    }
    if (!moved) step /= 2;
  }
  if (!(best_q > worst_old)) return false;
  float h = 0;
  for (std::uint32_t w : verts) h += m.nodes().size[w] / float(verts.size());
  const std::uint32_t x = m.add_interior_node(best_x, h);
  fresh.clear();
  for (std::size_t k = 0; k < faces.size(); k += 3) fresh.insert(fresh.end(), {faces[k], faces[k + 2], faces[k + 1], x});
  return m.replace(cavity, fresh, created);  // on false the node stays unused; write_back drops it
}

/// The Delaunay cavity of x from t: t and the tets of its region reachable over interior faces
/// whose circumsphere holds x strictly (exact insphere), at most kMaxCavity.
void delaunay_cavity(const ImproveTets& m, std::uint32_t t, const double* x, std::vector<std::uint32_t>& cavity) {
  cavity.assign(1, t);
  for (std::size_t i = 0; i < cavity.size() && cavity.size() < kMaxCavity; ++i)
    for (int f = 0; f < 4; ++f) {
      const std::uint32_t r = m.adj(cavity[i], f);
      if (r == kImproveNone || m.region(r >> 2) != m.region(t)) continue;
      const std::uint32_t u = r >> 2;
      if (std::find(cavity.begin(), cavity.end(), u) != cavity.end()) continue;
      const std::uint32_t* v = m.v(u);
      if (pred::insphere(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3]), x) > 0) cavity.push_back(u);
    }
}

}  // namespace

bool insert_in_cavity(ImproveTets& m, std::uint32_t t, std::vector<std::uint32_t>* created) {
  if (!m.alive(t)) return false;
  static thread_local std::vector<std::uint32_t> cavity;
  static thread_local std::vector<double> seeds, one;
  // Layers: t and its face neighbours; and theirs (same region, across interior faces).
  cavity.assign(1, t);
  seeds.clear();
  for (int layer = 0; layer < 2; ++layer) {
    const std::size_t n = cavity.size();
    for (std::size_t i = 0; i < n; ++i)
      for (int f = 0; f < 4; ++f) {
        const std::uint32_t r = m.adj(cavity[i], f);
        if (r == kImproveNone || m.region(r >> 2) != m.region(t)) continue;
        if (std::find(cavity.begin(), cavity.end(), r >> 2) == cavity.end()) cavity.push_back(r >> 2);
      }
    if (insert_into(m, cavity, seeds, created)) return true;
  }
  // Delaunay cavities of points under t's boundary faces (a cap folded along a feature edge
  // wants a node beneath the fold): each face's centroid moved inward by 0.4 and 0.7 x its
  // mean edge, and t's centroid.
  const std::uint32_t* v = m.v(t);
  const double* p[4] = {m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])};
  double c[3];
  ImproveTets::centroid(p, c);
  seeds.assign(c, c + 3);
  for (int f = 0; f < 4; ++f) {
    if (m.adj(t, f) != kImproveNone) continue;
    const double *a = p[kTetFace[f][0]], *b = p[kTetFace[f][1]], *d = p[kTetFace[f][2]];
    double n[3];
    tri_normal(a, b, d, n);  // outward
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0)) continue;
    auto dist = [](const double* u, const double* w) {
      double d[3];
      improve_detail::sub(u, w, d);
      return improve_detail::len(d);
    };
    const double edge = (dist(a, b) + dist(b, d) + dist(d, a)) / 3;
    for (double depth : {0.4, 0.7})
      for (int k = 0; k < 3; ++k) seeds.push_back((a[k] + b[k] + d[k]) / 3 - depth * edge * n[k] / nl);
  }
  for (std::size_t k = 0; k + 2 < seeds.size(); k += 3) {
    delaunay_cavity(m, t, &seeds[k], cavity);
    one.assign(seeds.begin() + std::ptrdiff_t(k), seeds.begin() + std::ptrdiff_t(k) + 3);
    if (insert_into(m, cavity, one, created)) return true;
  }
  return false;
}

}  // namespace kdmesh
