// kdmesh — boundary faces of the inside tets, their distance/orientation judgement against the
// surface, and the closed-2-manifold test.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/boundary_faces.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/face_samples.h"
#include "core/parallel_for.h"

namespace kdmesh {

BoundaryFaces boundary_faces(const Triangulation& tri, const std::vector<std::uint8_t>& inside) {
  BoundaryFaces bf;
  const std::size_t n = tri.num_tets();
  for (std::size_t t = 0; t < n; ++t) {
    if (!inside[t]) continue;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t u = tri.adj(t, i) >> 2;
      if (inside[u]) continue;
      for (int j = 0; j < 3; ++j) bf.verts.push_back(tri.v(t, kTetFace[i][j]));
      bf.tet.push_back(std::uint32_t(t));
      bf.face.push_back(std::uint8_t(i));
    }
  }
  return bf;
}

bool triangle_circumcentre(const double* a, const double* b, const double* c, double* out) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  if (!(w2 > 0)) return false;
  const double u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  const double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  // a + (|u|^2 (v x w) + |v|^2 (w x u)) / (2 |w|^2), w = u x v
  const double vw[3] = {v[1] * w[2] - v[2] * w[1], v[2] * w[0] - v[0] * w[2], v[0] * w[1] - v[1] * w[0]};
  const double wu[3] = {w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]};
  for (int k = 0; k < 3; ++k) out[k] = a[k] + (u2 * vw[k] + v2 * wu[k]) / (2 * w2);
  return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
}

ManifoldDefects manifold_defects(const std::vector<std::uint32_t>& verts) {
  ManifoldDefects d;
  const std::size_t nf = verts.size() / 3;
  // Edges: (key, face), sorted; runs of equal keys.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
  edges.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) {
      std::uint32_t a = verts[3 * f + j], b = verts[3 * f + (j + 1) % 3];
      if (a > b) std::swap(a, b);
      edges.push_back({(std::uint64_t(a) << 32) | b, std::uint32_t(f)});
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i != 2) {
      d.bad_edges.push_back(std::uint32_t(edges[i].first >> 32));
      d.bad_edges.push_back(std::uint32_t(edges[i].first));
      for (std::size_t k = i; k < j; ++k) d.faces_at_bad_edges.push_back(edges[k].second);
    }
    i = j;
  }
  // Vertices: the link of v (the edges opposite v in its faces) must be one cycle.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> vf;
  vf.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 3; ++j) vf.push_back({verts[3 * f + j], std::uint32_t(f)});
  std::sort(vf.begin(), vf.end());
  std::vector<std::uint32_t> ids, parent;
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto local = [&](std::uint32_t p) {
    for (std::size_t k = 0; k < ids.size(); ++k)
      if (ids[k] == p) return std::uint32_t(k);
    ids.push_back(p);
    parent.push_back(std::uint32_t(ids.size() - 1));
    return std::uint32_t(ids.size() - 1);
  };
  for (std::size_t i = 0; i < vf.size();) {
    std::size_t j = i;
    while (j < vf.size() && vf[j].first == vf[i].first) ++j;
    const std::uint32_t v = vf[i].first;
    ids.clear();
    parent.clear();
    for (std::size_t k = i; k < j; ++k) {
      const std::uint32_t* t = &verts[3 * std::size_t(vf[k].second)];
      std::uint32_t o[2], m = 0;
      for (int q = 0; q < 3; ++q)
        if (t[q] != v) o[m++] = t[q];
      const std::uint32_t x = find(local(o[0])), y = find(local(o[1]));
      if (x != y) parent[x] = y;
    }
    std::size_t roots = 0;
    for (std::size_t k = 0; k < ids.size(); ++k) roots += find(std::uint32_t(k)) == k;
    if (roots > 1) {
      d.bad_vertices.push_back(v);
      for (std::size_t k = i; k < j; ++k) d.faces_at_bad_vertices.push_back(vf[k].second);
    }
    i = j;
  }
  return d;
}

std::uint8_t judge_face(const std::uint32_t* fv, const NodeSet& nodes, const Domain& domain,
                        double tolerance, float* how_far) {
  const PreparedSurface& surface = domain.surface;
  const SurfaceQuery& query = domain.query;
  const SizingField& sizing = domain.sizing;
  std::uint8_t w = 0;
  for (int j = 0; j < 3; ++j)
    if (nodes.kind[fv[j]] == NodeKind::interior) w |= kFaceInterior;
  if (how_far) *how_far = 0;
  if (w) return w;
  const double *p0 = nodes.points.p(fv[0]), *p1 = nodes.points.p(fv[1]), *p2 = nodes.points.p(fv[2]);
  const double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
  const double fn[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  double c[3];
  for (int k = 0; k < 3; ++k) c[k] = (p0[k] + p1[k] + p2[k]) / 3;
  std::uint32_t facet = nodes.facet[fv[0]];
  double dmax = 0;
  const bool one_facet = facet != kNoFacet && nodes.facet[fv[1]] == facet && nodes.facet[fv[2]] == facet;
  if (!one_facet) {
    // The three vertices are not on one facet (a convex set): measure the distances at the
    // mesh check's samples (a face passing here passes there), the centroid's closest facet
    // for the normal.
    double cp[3];
    dmax = query.closest(c, cp, &facet);
    for (int k = 1; k < 7; ++k) {
      double s[3];
      face_sample(p0, p1, p2, k, s);
      dmax = std::max(dmax, query.distance(s));
    }
  }
  const double h = sizing(c);
  if (dmax > tolerance * h) w |= kFaceFar;
  if (how_far) *how_far = float(dmax / h);
  // Normal of the facet.
  const SurfaceMesh& sm = surface.mesh;
  const std::uint32_t* t = sm.tri(facet);
  const double *a = sm.points.p(t[0]), *b = sm.points.p(t[1]), *cc = sm.points.p(t[2]);
  const double fu[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double fw[3] = {cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]};
  const double n[3] = {fu[1] * fw[2] - fu[2] * fw[1], fu[2] * fw[0] - fu[0] * fw[2], fu[0] * fw[1] - fu[1] * fw[0]};
  if (fn[0] * n[0] + fn[1] * n[1] + fn[2] * n[2] < 0) w |= kFaceAgainst;
  return w;
}

BoundaryJudgement judge_boundary(const BoundaryFaces& faces, const NodeSet& nodes,
                                 const Domain& domain, double tolerance, FaceVerdicts* cache) {
  const std::size_t nf = faces.size();
  std::vector<std::uint8_t> why(nf, 0);  // kFace* bits
  std::vector<float> how_far(nf, 0);
  std::vector<std::uint32_t> todo;  // faces not in the cache
  todo.reserve(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const FaceVerdicts::Verdict* v = cache ? cache->find(&faces.verts[3 * f]) : nullptr;
    if (v) why[f] = v->why, how_far[f] = v->how_far;
    else todo.push_back(std::uint32_t(f));
  }
  parallel_for(todo.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      const std::size_t f = todo[k];
      why[f] = judge_face(&faces.verts[3 * f], nodes, domain, tolerance, &how_far[f]);
    }
  }, 256);
  if (cache)
    for (std::uint32_t f : todo) cache->put(&faces.verts[3 * std::size_t(f)], {why[f], how_far[f]});
  BoundaryJudgement j;
  for (std::size_t f = 0; f < nf; ++f) {
    if (!why[f]) continue;
    j.bad_faces.push_back(std::uint32_t(f));
    std::ostringstream r;
    if (why[f] & kFaceInterior) r << "interior-kind vertex on the boundary";
    if (why[f] & kFaceFar) r << (r.tellp() ? ", " : "") << "distance " << how_far[f] << " h from the surface";
    if (why[f] & kFaceAgainst) r << (r.tellp() ? ", " : "") << "faces against the closest facet";
    j.reasons.push_back(r.str());
  }
  ManifoldDefects d = manifold_defects(faces.verts);
  j.bad_edges = std::move(d.bad_edges);
  j.bad_vertices = std::move(d.bad_vertices);
  j.faces_at_bad_edges = std::move(d.faces_at_bad_edges);
  j.faces_at_bad_vertices = std::move(d.faces_at_bad_vertices);
  return j;
}

namespace {
std::array<std::uint32_t, 3> oriented_key(const std::uint32_t* fv) {
  const int m = fv[0] < fv[1] ? (fv[0] < fv[2] ? 0 : 2) : (fv[1] < fv[2] ? 1 : 2);
  return {fv[m], fv[(m + 1) % 3], fv[(m + 2) % 3]};
}
}  // namespace

std::size_t FaceVerdicts::Hash::operator()(const std::array<std::uint32_t, 3>& k) const {
  std::uint64_t h = k[0];
  h = h * 0x9E3779B97F4A7C15ull ^ k[1];
  h = h * 0x9E3779B97F4A7C15ull ^ k[2];
  return std::size_t(h ^ (h >> 29));
}

const FaceVerdicts::Verdict* FaceVerdicts::find(const std::uint32_t* fv) const {
  const auto it = map_.find(oriented_key(fv));
  return it == map_.end() ? nullptr : &it->second;
}

void FaceVerdicts::put(const std::uint32_t* fv, Verdict v) { map_[oriented_key(fv)] = v; }

}  // namespace kdmesh
