// kdmesh — boundary faces of the inside tets, their distance/orientation judgement against the
// surface, and the closed-2-manifold test.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/boundary_faces.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/face_samples.h"
#include "core/parallel_collect.h"
#include "core/parallel_for.h"
#include "core/uninit_allocator.h"
#include "mesher/bucket_scatter.h"

namespace kdmesh {

BoundaryFaces boundary_faces(const Triangulation& tri, const std::vector<std::uint8_t>& inside) {
  BoundaryFaces bf;
  // The inside tets with a face on the boundary, found on both cores (1M of 26M on the paper
  // gear box), then their faces in tet order.
  const std::vector<std::uint32_t> rim = parallel_collect(tri.num_tets(), [&](std::size_t t) {
    if (!inside[t]) return false;
    for (int i = 0; i < 4; ++i)
      if (!inside[tri.adj(t, i) >> 2]) return true;
    return false;
  });
  for (const std::uint32_t t : rim) {
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

ManifoldDefects manifold_defects(const std::vector<std::uint32_t>& input) {
  ManifoldDefects d;
  const std::size_t nf = input.size() / 3;
  if (nf == 0) return d;
  if (3 * nf >= (std::size_t(1) << 32)) throw UsageError("manifold_defects: too many faces");
  std::size_t np = std::size_t(*std::max_element(input.begin(), input.begin() + std::ptrdiff_t(3 * nf))) + 1;
  // The groups below take O(largest id) memory: sparse ids (not a mesher's, whose nodes are
  // numbered densely) are first renamed to their ranks, which keeps their order.
  std::vector<std::uint32_t> id_of, ranked;  // rank -> id; the faces by ranks
  if (np > 12 * nf + 1024) {
    id_of.assign(input.begin(), input.begin() + std::ptrdiff_t(3 * nf));
    std::sort(id_of.begin(), id_of.end());
    id_of.erase(std::unique(id_of.begin(), id_of.end()), id_of.end());
    ranked.resize(3 * nf);
    for (std::size_t k = 0; k < 3 * nf; ++k)
      ranked[k] = std::uint32_t(std::lower_bound(id_of.begin(), id_of.end(), input[k]) - id_of.begin());
    np = id_of.size();
  }
  const std::vector<std::uint32_t>& verts = id_of.empty() ? input : ranked;
  auto id = [&](std::uint32_t v) { return id_of.empty() ? v : id_of[v]; };
  // Edge k (0 <= k < 3 nf): the edge of face k / 3 from its vertex k % 3 to the next.
  auto edge = [&](std::size_t k) {
    const std::uint32_t a = verts[k], b = verts[3 * (k / 3) + (k % 3 + 1) % 3];
    return std::pair{std::min(a, b), std::max(a, b)};
  };
  // The edges grouped by their smaller end, each as (larger end, face); and the faces grouped
  // by vertex. Stable counting sorts on both cores: each group is in face order, so each sorted
  // group holds what the sorted list of all (edge, face) or (vertex, face) pairs held there.
  std::vector<std::uint64_t, UninitAllocator<std::uint64_t>> ends(3 * nf);
  const std::vector<std::size_t> edge_start = bucket_scatter(
      3 * nf, np, [&](std::size_t k) { return edge(k).first; },
      [&](std::size_t k, std::size_t at) { ends[at] = (std::uint64_t(edge(k).second) << 32) | (k / 3); });
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> faces(3 * nf);
  const std::vector<std::size_t> vertex_start = bucket_scatter(
      3 * nf, np, [&](std::size_t k) { return verts[k]; },
      [&](std::size_t k, std::size_t at) { faces[at] = std::uint32_t(k / 3); });
  // Fixed blocks of vertices, their findings joined in vertex order: the one-loop result on any
  // number of threads.
  constexpr std::size_t kBlock = 1 << 14;
  std::vector<ManifoldDefects> part((np + kBlock - 1) / kBlock);
  parallel_for(part.size(), [&](std::size_t pb, std::size_t pe, unsigned) {
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
    for (std::size_t q = pb; q < pe; ++q) {
      ManifoldDefects& out = part[q];
      for (std::size_t vi = q * kBlock; vi < std::min(np, (q + 1) * kBlock); ++vi) {
        const std::uint32_t v = std::uint32_t(vi);
        // Edges (v, w), v < w: each must be in exactly 2 faces.
        const auto first = ends.begin() + std::ptrdiff_t(edge_start[v]), last = ends.begin() + std::ptrdiff_t(edge_start[v + 1]);
        std::sort(first, last);
        for (auto i = first; i != last;) {
          auto j = i;
          while (j != last && (*j >> 32) == (*i >> 32)) ++j;
          if (j - i != 2) {
            out.bad_edges.push_back(id(v));
            out.bad_edges.push_back(id(std::uint32_t(*i >> 32)));
            for (auto k = i; k != j; ++k) out.faces_at_bad_edges.push_back(std::uint32_t(*k));
          }
          i = j;
        }
        // The link of v (the edges opposite v in its faces) must be one cycle.
        if (vertex_start[v] == vertex_start[v + 1]) continue;
        ids.clear();
        parent.clear();
        for (std::size_t k = vertex_start[v]; k < vertex_start[v + 1]; ++k) {
          const std::uint32_t* t = &verts[3 * std::size_t(faces[k])];
          std::uint32_t o[2], m = 0;
          for (int c = 0; c < 3; ++c)
            if (t[c] != v) o[m++] = t[c];
          const std::uint32_t x = find(local(o[0])), y = find(local(o[1]));
          if (x != y) parent[x] = y;
        }
        std::size_t roots = 0;
        for (std::size_t k = 0; k < ids.size(); ++k) roots += find(std::uint32_t(k)) == k;
        if (roots > 1) {
          out.bad_vertices.push_back(id(v));
          for (std::size_t k = vertex_start[v]; k < vertex_start[v + 1]; ++k) out.faces_at_bad_vertices.push_back(faces[k]);
        }
      }
    }
  }, 1);
  auto join = [](std::vector<std::uint32_t>& to, const std::vector<std::uint32_t>& from) {
    to.insert(to.end(), from.begin(), from.end());
  };
  for (const ManifoldDefects& p : part) {
    join(d.bad_edges, p.bad_edges);
    join(d.faces_at_bad_edges, p.faces_at_bad_edges);
    join(d.bad_vertices, p.bad_vertices);
    join(d.faces_at_bad_vertices, p.faces_at_bad_vertices);
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
  // The faces not in the cache (looked up on both cores: find only reads).
  const std::vector<std::uint32_t> todo = parallel_collect(nf, [&](std::size_t f) {
    const FaceVerdicts::Verdict* v = cache ? cache->find(&faces.verts[3 * f]) : nullptr;
    if (v) why[f] = v->why, how_far[f] = v->how_far;
    return v == nullptr;
  });
  parallel_for(todo.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      const std::size_t f = todo[k];
      why[f] = judge_face(&faces.verts[3 * f], nodes, domain, tolerance, &how_far[f]);
    }
  }, 256);
  if (cache) {
    cache->reserve(cache->size() + todo.size());
    for (std::uint32_t f : todo) cache->put(&faces.verts[3 * std::size_t(f)], {why[f], how_far[f]});
  }
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

std::size_t FaceVerdicts::hash(const Key& k) {
  std::uint64_t h = k[0];
  h = h * 0x9E3779B97F4A7C15ull ^ k[1];
  h = h * 0x9E3779B97F4A7C15ull ^ k[2];
  return std::size_t(h ^ (h >> 29));
}

const FaceVerdicts::Verdict* FaceVerdicts::find(const std::uint32_t* fv) const {
  if (slots_.empty()) return nullptr;
  const Key key = oriented_key(fv);
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = hash(key) & mask;; i = (i + 1) & mask) {
    const Slot& s = slots_[i];
    if (s.key == key) return &s.v;
    if (s.key[0] == kFree) return nullptr;
  }
}

void FaceVerdicts::rehash(std::size_t slots) {
  std::vector<Slot> old(slots, Slot{{kFree, 0, 0}, {0, 0.0f}});
  old.swap(slots_);
  const std::size_t mask = slots - 1;
  for (const Slot& s : old) {
    if (s.key[0] == kFree) continue;
    std::size_t i = hash(s.key) & mask;
    while (slots_[i].key[0] != kFree) i = (i + 1) & mask;
    slots_[i] = s;
  }
}

void FaceVerdicts::reserve(std::size_t count) {
  if (2 * count <= slots_.size()) return;
  rehash(std::bit_ceil(std::max<std::size_t>(16, 2 * count)));
}

void FaceVerdicts::put(const std::uint32_t* fv, Verdict v) {
  if (fv[0] == kFree || fv[1] == kFree || fv[2] == kFree)
    throw UsageError("FaceVerdicts: point id " + std::to_string(kFree) + " is reserved");
  reserve(size_ + 1);
  const Key key = oriented_key(fv);
  const std::size_t mask = slots_.size() - 1;
  std::size_t i = hash(key) & mask;
  while (slots_[i].key[0] != kFree && slots_[i].key != key) i = (i + 1) & mask;
  if (slots_[i].key[0] == kFree) ++size_;
  slots_[i] = {key, v};
}

}  // namespace kdmesh
