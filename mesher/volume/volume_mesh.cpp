// kdmesh — volume mesher: Delaunay of the nodes, keep the tets inside the solid, recover the
// boundary with surface Steiner points, label regions (NodeSet -> VolumeMesh).
//
// Per round: order + Delaunay of the current nodes; classify every finite tet inside/outside;
// extract the boundary faces (inside tet against outside or infinite tet), judge them (an
// interior-kind vertex, too far from the surface, or facing against the closest facet), and
// check the boundary is a closed 2-manifold. If anything is wrong, drop the offending interior
// nodes, add Steiner points on the surface and start the next round.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/volume_mesh.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <memory>
#include <numeric>
#include <span>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/page_warmer.h"
#include "core/timer.h"
#include "core/uninit_allocator.h"
#include "mesher/bucket_scatter.h"
#include "mesher/delaunay/canonical_order.h"
#include "mesher/volume/boundary_faces.h"
#include "mesher/volume/interface_faces.h"
#include "mesher/volume/point_grid.h"
#include "mesher/volume/tet_memo.h"
#include "mesher/surface/crease_points.h"
#include "core/parallel_for.h"
#include "mesher/tet_quality.h"

namespace kdmesh {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

// ---------------------------------------------------------------------------------------------
// Full triangulation of the current node set: the first round, and rounds after interior nodes
// were dropped. Rounds that only add Steiner points insert them into the existing triangulation
// (delaunay_insert, located from a vertex of the face that asked for them).
DelaunayResult triangulate(const NodeSet& nodes, const VolumeMeshOptions& options,
                           VolumeMeshStats& stats) {
  Stopwatch sw;
  const Ordering order = make_order(nodes.points, options.order);
  stats.order_seconds += sw.seconds();
  sw.reset();
  DelaunayOptions dopt;
  if (options.progress) dopt.progress = [&](double f) { options.progress("delaunay", f); };
  dopt.threads = options.threads;
  DelaunayResult r = delaunay(nodes.points, order, dopt);
  // The records in canonical order: the mesh then does not depend on the thread count.
  canonicalize_triangulation(r.tri, order, r.stats, options.threads);
  stats.delaunay_seconds += sw.seconds();
  return r;
}

/// True if the tet (4 point ids at v) is flat at rounding level (mesher/tet_quality.h).
bool flat_at_rounding(const PointSet& pts, const std::uint32_t* v) {
  return std::abs(volume_length(pts.p(v[0]), pts.p(v[1]), pts.p(v[2]), pts.p(v[3]))) <
         kZeroVolumeLength;
}

void centroid4(const PointSet& pts, const std::uint32_t* v, double* c) {
  for (int k = 0; k < 3; ++k)
    c[k] = (pts.p(v[0])[k] + pts.p(v[1])[k] + pts.p(v[2])[k] + pts.p(v[3])[k]) / 4;
}

// ---------------------------------------------------------------------------------------------
// Inside/outside classification of every tet of `tri` (infinite tets: outside). A centroid on
// the surface (side 0) counts as outside.
//
// A face with an interior-kind vertex cannot be a boundary face of a valid mesh, so the tets
// joined across such faces form components that share one class. Interior nodes lie strictly
// inside the solid, so each such component is taken to be inside, and only its rim is checked:
//  1. tets whose four vertices are all surface nodes get their own exact query;
//  2. every other tet next to a tet of the other class (it would own a boundary face) gets its
//     own query; a tet whose answer contradicts its component flips and exposes its unchecked
//     neighbours to the next wave, so a component that is really outside (or a tet that sticks
//     out of the solid because its interior vertex is too close to the surface) is corrected
//     tet by tet from its rim inwards.
// Every tet that ends up owning a boundary face, on either side, has had its own exact query;
// the components themselves are never materialised (no flood fill over all tets).
std::vector<std::uint8_t> classify(const Triangulation& tri, const NodeSet& nodes,
                                   const SurfaceQuery& query, const RegionQuery* regions,
                                   double on_surface, const TetMemo& memo,
                                   std::vector<TetMemo::Asked>& asked, VolumeMeshStats& stats) {
  const std::size_t n = tri.num_tets();
  // 0 outside / infinite, 1 inside; bit 1: class verified by the tet's own query.
  std::vector<std::uint8_t> inside(n, 0), verified(n, 0);
  std::vector<std::uint32_t> singles;  // all-surface tets
  parallel_for(n, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      bool infinite = false, interior = false;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t v = tri.v(t, i);
        if (v == kInfiniteVertex) infinite = true;
        else if (nodes.kind[v] == NodeKind::interior) interior = true;
      }
      inside[t] = !infinite && interior;
      verified[t] = infinite;  // infinite tets are outside by definition
    }
  });
  for (std::size_t t = 0; t < n; ++t)
    if (!verified[t] && !inside[t]) singles.push_back(std::uint32_t(t));

  // A flat all-surface tet whose centroid lies on an interface between touching bodies, inside
  // the solid and off its outer surface, is a sliver of four interface nodes (cocircular on a
  // planar interface facet, as the spacing grid places them on a cylinder's facet strips): it
  // is inside (taking it out would leave a hole inside the solid, its faces far from the outer
  // surface), and the recovery splits it with a Steiner point on the interface.
  auto interface_sliver = [&](const double* c) {
    return regions && query.side(c) > 0 && query.distance(c) > on_surface &&
           regions->interfaces().distance(c) <= on_surface;
  };
  auto side_of = [&](std::uint32_t t) {
    const std::uint32_t* v = &tri.data[8 * std::size_t(t)];
    bool all_surface = true;
    for (int i = 0; i < 4; ++i) all_surface = all_surface && nodes.kind[v[i]] != NodeKind::interior;
    double c[3];
    centroid4(nodes.points, v, c);
    if (all_surface && flat_at_rounding(nodes.points, v)) return interface_sliver(c);  // see below
    return query.side(c) > 0;
  };
  // An all-surface tet whose centroid lies on the surface (within `on_surface`, the distance
  // at which mesh_check counts a vertex as on the surface) is a flat sliver between surface
  // nodes that are coplanar only up to rounding: it is outside, like a centroid exactly on the
  // surface. Deciding such slivers by the sign of a 1e-17 offset would make the boundary zigzag
  // through the sheet of surface nodes (flipped faces, non-manifold edges). Likewise an
  // all-surface tet that is flat at rounding level (volume-length ratio < 1e-9; measured on
  // the gear box: 23 tets with radius ratio ~1e-16, two edge and two surface nodes on one
  // facet plane, whose centroid lay beyond `on_surface` from the facet polygon) is a zero-volume
  // sliver on the surface, never a part of the solid: dropping it exposes faces on the surface.
  // Each answer is a function of the tet's nodes: those of earlier rounds come from `memo`,
  // the tets asked go to `asked` with their answers.
  asked.clear();
  const bool recall = memo.size() > 0;  // (the first round's memo is empty: no lookups)
  auto remember = [&](const std::vector<std::uint32_t>& list, const std::vector<std::uint8_t>& fresh,
                      const auto& answer_at) {
    const std::size_t before = asked.size();
    for (std::size_t k = 0; k < list.size(); ++k)
      if (fresh[k]) asked.push_back({list[k], std::int32_t(answer_at(k))});
    return asked.size() - before;
  };
  for (std::uint32_t t : singles) verified[t] = 1;
  std::vector<std::uint8_t> fresh(singles.size(), 0);
  parallel_for(singles.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t k = b; k < e; ++k) {
      const std::uint32_t t = singles[k];
      const std::uint32_t* v = &tri.data[8 * std::size_t(t)];
      if (const std::int32_t known = recall ? memo.find(v) : TetMemo::kNone; known != TetMemo::kNone) {
        inside[t] = std::uint8_t(known);
        continue;
      }
      double c[3];
      centroid4(nodes.points, v, c);
      const bool flat = flat_at_rounding(nodes.points, v);
      inside[t] = flat ? interface_sliver(c) : query.side(c) > 0 && query.distance(c) > on_surface;
      fresh[k] = 1;
    }
  }, 256);
  std::size_t queries = remember(singles, fresh, [&](std::size_t k) { return inside[singles[k]]; });

  // The rim of the components, then waves of flips.
  std::vector<std::uint32_t> wave;
  {
    std::vector<std::vector<std::uint32_t>> part(64);
    parallel_for(n, [&](std::size_t b, std::size_t e, unsigned w) {
      for (std::size_t t = b; t < e; ++t) {
        if (verified[t]) continue;
        for (int i = 0; i < 4; ++i)
          if (inside[tri.adj(t, i) >> 2] != inside[t]) {
            part[w].push_back(std::uint32_t(t));
            break;
          }
      }
    }, 65536, 64);
    for (auto& p : part) wave.insert(wave.end(), p.begin(), p.end());
  }
  std::vector<std::uint8_t> answer;
  while (!wave.empty()) {
    for (std::uint32_t t : wave) verified[t] = 1;
    answer.assign(wave.size(), 0);
    fresh.assign(wave.size(), 0);
    parallel_for(wave.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t k = b; k < e; ++k) {
        const std::int32_t known = recall ? memo.find(&tri.data[8 * std::size_t(wave[k])]) : TetMemo::kNone;
        fresh[k] = known == TetMemo::kNone;
        answer[k] = fresh[k] ? side_of(wave[k]) : std::uint8_t(known);
      }
    }, 256);
    std::vector<std::uint32_t> next;
    for (std::size_t k = 0; k < wave.size(); ++k) {
      const std::uint32_t t = wave[k];
      if (answer[k] == inside[t]) continue;
      inside[t] = answer[k];
      ++stats.rim_flips;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t u = tri.adj(t, i) >> 2;
        if (!verified[u]) {
          verified[u] = 1;  // queued once
          next.push_back(u);
        }
      }
    }
    queries += remember(wave, fresh, [&](std::size_t k) { return answer[k]; });
    wave.swap(next);
  }
  stats.side_queries += queries;
  stats.classified_tets += n;
  return inside;
}

/// Directed edges (link[2k], link[2k+1]) form one cycle: each vertex starts exactly one edge
/// and ends exactly one, and walking from the first edge visits them all.
bool one_cycle(const std::vector<std::uint32_t>& link) {
  const std::size_t m = link.size() / 2;
  for (std::size_t a = 0; a < m; ++a) {
    int starts = 0, ends = 0;
    for (std::size_t b = 0; b < m; ++b) {
      starts += link[2 * b] == link[2 * a];
      ends += link[2 * b + 1] == link[2 * a];
    }
    if (starts != 1 || ends != 1) return false;
  }
  std::size_t steps = 0, e = 0;
  do {
    std::size_t b = 0;
    while (link[2 * b] != link[2 * e + 1]) ++b;
    e = b;
    ++steps;
  } while (e != 0 && steps <= m);
  return steps == m;
}

/// The boundary faces at each vertex, as references 4 t + i of their inside tets: bf's faces
/// grouped by vertex with a stable counting sort (each vertex's faces in bf's order, which is
/// tet order, then face order), and a copy of each vertex's list that was edited since. On
/// t13_data.stl at 1.5M tets, a std::unordered_map of vectors filled face by face took 46 ms
/// of each recovery round, for the few vertices a peel looks at.
class FacesAtVertices {
 public:
  FacesAtVertices(const BoundaryFaces& bf, std::size_t num_nodes) : refs_(bf.verts.size()) {
    start_ = bucket_scatter(
        bf.verts.size(), num_nodes, [&](std::size_t k) { return bf.verts[k]; },
        [&](std::size_t k, std::size_t at) { refs_[at] = 4 * bf.tet[k / 3] + bf.face[k / 3]; });
  }
  /// v's faces as they stand.
  std::span<const std::uint32_t> of(std::uint32_t v) const {
    if (const auto it = edited_.find(v); it != edited_.end()) return it->second;
    return {refs_.data() + start_[v], refs_.data() + start_[v + 1]};
  }
  /// v's faces, to change.
  std::vector<std::uint32_t>& edit(std::uint32_t v) {
    const auto [it, fresh] = edited_.try_emplace(v);
    if (fresh) it->second.assign(refs_.begin() + std::ptrdiff_t(start_[v]), refs_.begin() + std::ptrdiff_t(start_[v + 1]));
    return it->second;
  }

 private:
  std::vector<std::uint32_t> refs_;
  std::vector<std::size_t> start_;
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> edited_;
};

// ---------------------------------------------------------------------------------------------
// Folds. A tet whose four vertices are surface nodes is classified by the side of its centroid
// alone. Where the surface bends or wiggles within one node spacing (the saddle-shaped inner
// half of a torus near the top and bottom of the tube; rough scanned surfaces) such tets lie
// across the surface, their centroids within the surface's own deviation from their faces, so
// neighbouring ones fall on either side: the boundary folds, and the fold's faces point into the
// solid (judge_boundary: "faces against the closest facet") or meet at non-manifold edges and
// vertices. Steiner points do not undo a fold: its faces are caps (three surface nodes nearly
// in a row), the closest surface point to such a face lies next to the middle node, so no
// candidate is admissible, and every surface node added makes more tets of the same kind
// (measured on a 400x200-quad torus at size 1: 188 folded faces before the first Steiner round,
// 76 still there when no admissible point was left after 11 rounds; a rough one: 3734, 4134
// after 12 rounds).
//
// A fold is undone by taking all-surface tets out of the solid (never by adding one: every kept
// tet keeps its centroid strictly inside). Starting from an all-surface tet that owns a bad face
// or a face at a non-manifold vertex, the cluster grows through every bad face it exposes and
// through the all-surface tets at the non-manifold vertices it leaves, up to kMaxCluster tets;
// a tet with an interior-kind vertex behind a bad exposed face stops it. The cluster is kept if
// every face it exposes is good (judge_face: on the surface within tolerance, facing out) and
// its vertices have fewer non-manifold ones than before (no more, if it started from a bad
// face, which is gone); else it is undone. Sequential in tet order (deterministic); tets next to
// a kept cluster are retried until nothing changes. Returns the number of tets taken out.
std::size_t peel_folds(const Triangulation& tri, const NodeSet& nodes, const Domain& domain,
                       double tolerance,
                       const BoundaryFaces& bf, const BoundaryJudgement& judge,
                       std::vector<std::uint8_t>& inside) {
  auto all_surface = [&](std::uint32_t t) {
    for (int i = 0; i < 4; ++i)
      if (nodes.kind[tri.v(t, i)] == NodeKind::interior) return false;
    return true;
  };
  auto face_verts = [&](std::uint32_t t, int i, std::uint32_t* fv) {
    for (int j = 0; j < 3; ++j) fv[j] = tri.v(t, kTetFace[i][j]);
  };
  auto bad_face = [&](std::uint32_t t, int i) {
    std::uint32_t fv[3];
    face_verts(t, i, fv);
    return judge_face(fv, nodes, domain, tolerance) != 0;
  };
  // Candidates: the all-surface tets owning a bad face or a face at a non-manifold edge or
  // vertex.
  std::vector<std::uint32_t> work;
  for (const std::vector<std::uint32_t>* list :
       {&judge.bad_faces, &judge.faces_at_bad_edges, &judge.faces_at_bad_vertices})
    for (std::uint32_t f : *list)
      if (all_surface(bf.tet[f])) work.push_back(bf.tet[f]);
  if (work.empty()) return 0;
  // The boundary faces at each vertex (face reference 4 t + i of the inside tet), kept up to
  // date while peeling, for the manifold test.
  FacesAtVertices at_vertex(bf, nodes.size_count());
  auto count_face = [&](std::uint32_t ref, int d) {
    std::uint32_t fv[3];
    face_verts(ref >> 2, int(ref & 3), fv);
    for (std::uint32_t v : fv) {
      std::vector<std::uint32_t>& l = at_vertex.edit(v);
      if (d > 0) {
        l.push_back(ref);
      } else {
        auto it = std::find(l.begin(), l.end(), ref);
        *it = l.back();
        l.pop_back();
      }
    }
  };
  // The boundary is a 2-manifold at v: the edges opposite v in its faces form one cycle.
  std::vector<std::uint32_t> link;
  auto manifold_at = [&](std::uint32_t v) {
    const std::span<const std::uint32_t> faces = at_vertex.of(v);
    if (faces.empty()) return true;
    link.clear();
    for (std::uint32_t ref : faces) {
      std::uint32_t fv[3];
      face_verts(ref >> 2, int(ref & 3), fv);
      const int j = fv[0] == v ? 0 : fv[1] == v ? 1 : 2;
      link.push_back(fv[(j + 1) % 3]);  // directed link edge
      link.push_back(fv[(j + 2) % 3]);
    }
    return one_cycle(link);
  };
  auto peel_one = [&](std::uint32_t t, int d) {  // d = -1 peel, +1 undo
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t a = tri.adj(t, i);
      if (!inside[a >> 2]) count_face(std::uint32_t(4 * t + i), d);
      else count_face(a, -d);
    }
    inside[t] = d < 0 ? 0 : 1;
  };
  // Peels the all-surface tet t0 and, where that exposes a bad face of another all-surface tet
  // (a fold more than one tet thick) or leaves a vertex non-manifold, the all-surface tets there
  // too, up to kMaxCluster tets. Kept if every face it exposes is good and its vertices have
  // fewer non-manifold ones than before (no more, if t0 owned a bad face: that face is gone);
  // otherwise undone.
  constexpr std::size_t kMaxCluster = 24;
  std::vector<std::uint32_t> removed, stack;
  std::vector<std::pair<std::uint32_t, bool>> was_manifold;  // vertices touched, before
  auto touch = [&](std::uint32_t t) {
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t v = tri.v(t, i);
      bool seen = false;
      for (const auto& p : was_manifold) seen = seen || p.first == v;
      if (!seen) was_manifold.push_back({v, manifold_at(v)});
    }
  };
  auto try_peel = [&](std::uint32_t t0, bool owns_bad) {
    removed.clear();
    was_manifold.clear();
    stack.assign(1, t0);
    for (;;) {
      bool ok = true;
      while (ok && !stack.empty()) {
        const std::uint32_t t = stack.back();
        stack.pop_back();
        if (!inside[t]) continue;
        if (removed.size() == kMaxCluster) {
          ok = false;
          break;
        }
        touch(t);
        peel_one(t, -1);
        removed.push_back(t);
        for (int i = 0; i < 4 && ok; ++i) {
          const std::uint32_t a = tri.adj(t, i);
          if (!inside[a >> 2] || !bad_face(a >> 2, int(a & 3))) continue;
          ok = all_surface(a >> 2);  // a bad face of a tet that cannot be peeled
          stack.push_back(a >> 2);
        }
      }
      if (!ok) break;
      std::size_t before = 0, after = 0;
      for (const auto& [v, m] : was_manifold) {
        before += !m;
        after += !manifold_at(v);
      }
      if (owns_bad ? after <= before : after < before) return true;
      for (const auto& [v, m] : was_manifold) {
        if (manifold_at(v)) continue;
        for (std::uint32_t ref : at_vertex.of(v))
          if (all_surface(ref >> 2)) stack.push_back(ref >> 2);
      }
      if (stack.empty()) break;
    }
    for (std::size_t r = removed.size(); r-- > 0;) peel_one(removed[r], +1);
    return false;
  };
  std::size_t peeled = 0;
  while (!work.empty()) {
    std::sort(work.begin(), work.end());
    work.erase(std::unique(work.begin(), work.end()), work.end());
    std::vector<std::uint32_t> next;
    for (std::uint32_t t : work) {
      if (!inside[t]) continue;
      bool has_bad = false, at_defect = false;
      for (int i = 0; i < 4 && !has_bad; ++i)
        if (!inside[tri.adj(t, i) >> 2]) {
          has_bad = bad_face(t, i);
          for (int j = 0; j < 3 && !at_defect; ++j) at_defect = !manifold_at(tri.v(t, kTetFace[i][j]));
        }
      if (!(has_bad || at_defect) || !try_peel(t, has_bad)) continue;
      peeled += removed.size();
      for (std::uint32_t r : removed)
        for (int i = 0; i < 4; ++i) {
          const std::uint32_t u = tri.adj(r, i) >> 2;
          if (inside[u] && all_surface(u)) next.push_back(u);  // may be peelable now
        }
    }
    work.swap(next);
  }
  return peeled;
}

std::string xyz(const double* p) {
  std::ostringstream s;
  s.precision(9);
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

/// Node ids kept after dropping `drop`, compacted in order; Steiner points appended.
NodeSet rebuild_nodes(const NodeSet& nodes, const std::vector<std::uint8_t>& drop,
                      const NodeSet& steiner) {
  NodeSet out;
  // Sized first (at most every node is kept): grown by doubling, the arrays were copied ~22
  // times (the paper gear box's 4.2M nodes: ~300 MB of copies into fresh pages on one core).
  out.reserve(nodes.size_count() + steiner.size_count());
  for (std::size_t i = 0; i < nodes.size_count(); ++i)
    if (!drop[i]) out.push_back(nodes.points.p(std::uint32_t(i)), nodes.kind[i], nodes.facet[i], nodes.size[i]);
  for (std::size_t i = 0; i < steiner.size_count(); ++i)
    out.push_back(steiner.points.p(std::uint32_t(i)), steiner.kind[i], steiner.facet[i], steiner.size[i]);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Recovery. What one round asks for: interior nodes to drop (those on bad faces and in flat
// tets), and candidate places for Steiner points on the surface or an interface.
struct RecoveryPlan {
  std::vector<std::uint8_t> drop;
  std::size_t dropped = 0;
  std::vector<std::array<double, 3>> candidates;  // points whose closest surface point to add
  std::vector<std::array<double, 3>> fallbacks;   // circumcentres, tried if the first is too close
  std::vector<std::array<std::uint32_t, 3>> facets;  // the face vertices' facets
  std::vector<std::uint32_t> hint;                    // a vertex of the face
  std::vector<std::uint8_t> on_interface;             // the point goes on an interface

  /// Drops the interior-kind nodes among v[0..n); true if there was one.
  bool drop_interior(const NodeSet& nodes, const std::uint32_t* v, int n) {
    bool had = false;
    for (int j = 0; j < n; ++j) {
      if (nodes.kind[v[j]] != NodeKind::interior) continue;
      had = true;
      if (!drop[v[j]]) drop[v[j]] = 1, ++dropped;
    }
    return had;
  }
  /// A candidate at the centroid of face fv (fallback: its circumcentre).
  void add(const NodeSet& nodes, const std::uint32_t* fv, bool interface) {
    const double *a = nodes.points.p(fv[0]), *b = nodes.points.p(fv[1]), *c = nodes.points.p(fv[2]);
    candidates.push_back({(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3});
    double cc[3];
    if (triangle_circumcentre(a, b, c, cc)) fallbacks.push_back({cc[0], cc[1], cc[2]});
    else fallbacks.push_back(candidates.back());
    hint.push_back(fv[0]);
    facets.push_back({nodes.facet[fv[0]], nodes.facet[fv[1]], nodes.facet[fv[2]]});
    on_interface.push_back(interface ? 1 : 0);
  }
};

/// The bad places of one round: boundary faces against the surface, non-manifold edges and
/// vertices, flat kept tets, faces between regions against the interfaces.
struct RoundFaults {
  BoundaryJudgement judge;
  std::vector<std::uint32_t> flat;
  InterfaceFaces ifaces;
  InterfaceJudgement ij;
  bool empty() const {
    return judge.bad_faces.empty() && judge.bad_edges.empty() && judge.bad_vertices.empty() &&
           flat.empty() && ij.bad_faces.empty();
  }
};

// Kept tets that are flat at rounding level (4 nodes coplanar up to rounding, e.g. lattice
// nodes next to surface nodes; all-surface ones are outside unless they lie on an interface,
// classify): their interior nodes are dropped, like interior nodes on boundary faces (measured:
// 1 such tet among 21M on the paper-size gear box).
std::vector<std::uint32_t> flat_inside_tets(const Triangulation& tri, const NodeSet& nodes,
                                            const std::vector<std::uint8_t>& inside) {
  std::vector<std::uint32_t> flat;
  std::vector<std::vector<std::uint32_t>> part(64);
  parallel_for(tri.num_tets(), [&](std::size_t b, std::size_t e, unsigned w) {
    for (std::size_t t = b; t < e; ++t)
      if (inside[t] && flat_at_rounding(nodes.points, &tri.data[8 * t])) part[w].push_back(std::uint32_t(t));
  }, 65536, 64);
  for (auto& p : part) flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

// Drop interior nodes on bad faces and in flat tets; Steiner candidates near the other bad
// faces, around non-manifold edges and vertices, and in slivers of interface nodes.
RecoveryPlan plan_recovery(const Triangulation& tri, const NodeSet& nodes, const Domain& domain,
                           const BoundaryFaces& bf, const RoundFaults& rf, VolumeMeshStats& st) {
  RecoveryPlan plan;
  plan.drop.assign(nodes.size_count(), 0);
  for (std::uint32_t f : rf.judge.bad_faces)
    if (!plan.drop_interior(nodes, &bf.verts[3 * std::size_t(f)], 3)) plan.add(nodes, &bf.verts[3 * std::size_t(f)], false);
  for (std::uint32_t t : rf.flat) {
    const std::uint32_t* tv = &tri.data[8 * std::size_t(t)];
    // A sliver of four interface nodes (classify): split it with a point on the interface, in
    // the circle of its four nodes (any convex combination of them). Not the centroid: on a
    // square lattice of nodes the centres of two neighbouring squares and the two nodes they
    // share are cocircular again, and each round would make new slivers (measured: 60 slivers,
    // 28 left after 12 rounds); unequal weights put the points off such symmetric places.
    if (!plan.drop_interior(nodes, tv, 4) && domain.regions) {
      plan.add(nodes, tv, true);
      ++st.interface_slivers;
      constexpr double w[4] = {0.35, 0.28, 0.21, 0.16};
      std::array<double, 3>& c = plan.candidates.back();
      c = {0, 0, 0};
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 3; ++k) c[k] += w[j] * nodes.points.p(tv[j])[k];
      centroid4(nodes.points, tv, plan.fallbacks.back().data());
    }
  }
  for (std::uint32_t f : rf.ij.bad_faces)
    if (!plan.drop_interior(nodes, &rf.ifaces.verts[3 * std::size_t(f)], 3))
      plan.add(nodes, &rf.ifaces.verts[3 * std::size_t(f)], true);
  for (std::uint32_t f : rf.judge.faces_at_bad_edges) plan.add(nodes, &bf.verts[3 * std::size_t(f)], false);
  for (std::uint32_t f : rf.judge.faces_at_bad_vertices) plan.add(nodes, &bf.verts[3 * std::size_t(f)], false);
  return plan;
}

// Each candidate: the closest surface point to the face centroid; if that is within 0.2 h of a
// node, the closest point on a nearby crease (edge kind: faces that cut across a re-entrant
// edge are only recovered by points on it); then the closest surface point to the face's
// circumcentre. Candidates on an interface take the closest interface point instead.
void choose_steiner(const RecoveryPlan& plan, const NodeSet& nodes, const Domain& domain,
                    std::unique_ptr<CreaseFinder>& creases, NodeSet& steiner, std::vector<std::uint32_t>& hints) {
  if (plan.candidates.empty()) return;
  if (!creases) creases = std::make_unique<CreaseFinder>(domain.surface.mesh);
  // Cells of 0.2 x the largest node size: the search radius 0.2 h is about one cell.
  float hmax = 0;
  for (float x : nodes.size) hmax = std::max(hmax, x);
  const double cell = hmax > 0 ? 0.2 * double(hmax) : 0.2 * domain.sizing.max_size();
  const double* bmin = domain.surface.bbox_min;
  const double* bmax = domain.surface.bbox_max;
  const double diag = std::hypot(bmax[0] - bmin[0], bmax[1] - bmin[1], bmax[2] - bmin[2]);
  PointGrid grid(cell > 0 ? cell : 1e-3 * diag, bmin, nodes.points, plan.drop);
  // The admissible gap starts at 0.2 h and halves (down to 0.0125 h) while no candidate is
  // admissible: parts thinner than h (real scans and CAD at a coarse size) need Steiner points
  // closer than 0.2 h to the nodes already on the other side.
  for (double gap = 0.2; steiner.size_count() == 0 && gap >= 0.0125; gap /= 2)
    for (std::size_t k = 0; k < plan.candidates.size(); ++k)
      for (int attempt = 0; attempt < 3; ++attempt) {
        const double* from = attempt == 0 ? plan.candidates[k].data() : plan.fallbacks[k].data();
        double p[3];
        std::uint32_t facet = kNoFacet;
        NodeKind kind = NodeKind::surface;
        if (plan.on_interface[k]) {
          if (attempt == 1) continue;  // interfaces have no creases here
          domain.regions->interfaces().closest(from, p);
        } else if (attempt == 1) {
          if (!creases->closest_crease_point(plan.candidates[k].data(), plan.facets[k].data(), 3, p, &facet))
            continue;
          kind = NodeKind::edge;
        } else {
          domain.query.closest(from, p, &facet);
        }
        const double h = domain.sizing(p);
        if (grid.any_within(p, gap * h)) continue;
        grid.add(p);
        steiner.push_back(p, kind, facet, float(h));
        hints.push_back(plan.hint[k]);
        break;
      }
}

// The boundary could not be recovered: a BoundaryRecoveryError naming up to five bad places
// and carrying all of them (for a caller that refines there).
[[noreturn]] void throw_unrecovered(int round, bool progress_made, std::size_t folds_peeled, const Triangulation& tri,
                                    const BoundaryFaces& bf, const RoundFaults& rf, const NodeSet& nodes) {
  const BoundaryJudgement& judge = rf.judge;
  auto mid = [&](const std::uint32_t* v, int n, double* m) {
    for (int q = 0; q < 3; ++q) {
      m[q] = 0;
      for (int j = 0; j < n; ++j) m[q] += nodes.points.p(v[j])[q] / n;
    }
  };
  std::ostringstream msg;
  msg << "mesh_volume: the boundary could not be recovered after " << round << " Steiner round(s)"
      << (progress_made ? "" : " (no admissible Steiner point left)") << " and " << folds_peeled
      << " folded surface tet(s) taken out"
      << ": " << judge.bad_faces.size() << " bad boundary face(s), "
      << (rf.ij.bad_faces.empty() ? std::string() : std::to_string(rf.ij.bad_faces.size()) + " bad interface face(s), ")
      << judge.bad_edges.size() / 2 << " non-manifold edge(s), " << judge.bad_vertices.size()
      << " non-manifold vertex(es)"
      << (rf.flat.empty() ? std::string() : ", " + std::to_string(rf.flat.size()) + " flat tet(s)");
  std::size_t shown = 0;
  double m[3];
  for (std::size_t k = 0; k < judge.bad_faces.size() && shown < 5; ++k, ++shown) {
    mid(&bf.verts[3 * std::size_t(judge.bad_faces[k])], 3, m);
    msg << (shown ? "; " : "; e.g. ") << "face at " << xyz(m) << " (" << judge.reasons[k] << ")";
  }
  for (std::size_t k = 0; k < rf.ij.bad_faces.size() && shown < 5; ++k, ++shown) {
    mid(&rf.ifaces.verts[3 * std::size_t(rf.ij.bad_faces[k])], 3, m);
    msg << (shown ? "; " : "; e.g. ") << "face at " << xyz(m) << " (" << rf.ij.reasons[k] << ")";
  }
  for (std::size_t k = 0; k + 1 < judge.bad_edges.size() && shown < 5; k += 2, ++shown)
    msg << "; non-manifold edge " << xyz(nodes.points.p(judge.bad_edges[k])) << "-"
        << xyz(nodes.points.p(judge.bad_edges[k + 1]));
  for (std::size_t k = 0; k < judge.bad_vertices.size() && shown < 5; ++k, ++shown)
    msg << "; non-manifold vertex " << xyz(nodes.points.p(judge.bad_vertices[k]));
  std::vector<double> where;  // every bad place
  auto add_mid = [&](const std::uint32_t* v, int n) {
    mid(v, n, m);
    where.insert(where.end(), m, m + 3);
  };
  for (std::uint32_t f : judge.bad_faces) add_mid(&bf.verts[3 * std::size_t(f)], 3);
  for (std::uint32_t f : rf.ij.bad_faces) add_mid(&rf.ifaces.verts[3 * std::size_t(f)], 3);
  for (std::size_t k = 0; k + 1 < judge.bad_edges.size(); k += 2) add_mid(&judge.bad_edges[k], 2);
  for (std::uint32_t v : judge.bad_vertices) add_mid(&v, 1);
  for (std::uint32_t t : rf.flat) add_mid(&tri.data[8 * std::size_t(t)], 4);
  throw BoundaryRecoveryError(msg.str(), std::move(where));
}

// ---------------------------------------------------------------------------------------------
// Regions of disjoint bodies (no interfaces): components of the inside tets through shared
// faces (union-find in one sequential pass); each takes the body of the shell of the facet
// closest to one of its boundary faces. Empty (all body 0) with a single body.
std::vector<std::uint32_t> component_bodies(const Triangulation& tri, const std::vector<std::uint8_t>& inside,
                                            const BoundaryFaces& bf, const NodeSet& nodes, const Domain& domain) {
  const PreparedSurface& surface = domain.surface;
  const std::size_t nt = tri.num_tets();
  std::vector<std::uint32_t> region_of;
  if (surface.num_bodies <= 1) return region_of;
  std::vector<std::uint32_t> parent(nt);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t t = 0; t < nt; ++t) {
    if (!inside[t]) continue;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t u = tri.adj(t, i) >> 2;
      if (u >= t || !inside[u]) continue;
      const std::uint32_t a = find(std::uint32_t(t)), b = find(u);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::uint32_t> root_body(nt, kNone);
  for (std::size_t f = 0; f < bf.size(); ++f) {
    const std::uint32_t r = find(bf.tet[f]);
    if (root_body[r] != kNone) continue;
    const std::uint32_t* fv = &bf.verts[3 * f];
    double m[3], p[3];
    for (int k = 0; k < 3; ++k)
      m[k] = (nodes.points.p(fv[0])[k] + nodes.points.p(fv[1])[k] + nodes.points.p(fv[2])[k]) / 3;
    std::uint32_t facet = 0;
    domain.query.closest(m, p, &facet);
    const std::uint32_t shell = facet < surface.tri_shell.size() ? surface.tri_shell[facet] : 0;
    root_body[r] = shell < surface.shell_body.size() ? surface.shell_body[shell] : 0;
  }
  region_of.assign(nt, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (inside[t]) {
      const std::uint32_t b = root_body[find(std::uint32_t(t))];
      region_of[t] = b == kNone ? 0 : b;  // every finite component has a boundary face
    }
  return region_of;
}

// The result: the inside tets with their regions, the boundary; nodes no inside tet uses are
// removed, and surface-kind nodes on no boundary or interface face become interior ones.
void compact_result(const Triangulation& tri, const std::vector<std::uint8_t>& inside,
                    const std::vector<std::uint32_t>& region_of, const BoundaryFaces& bf, const NodeSet& nodes,
                    bool interfaces, VolumeMesh& out) {
  VolumeMeshStats& st = out.stats;
  const std::size_t nt = tri.num_tets();
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> new_tet(nt);  // written whole below
  std::uint32_t count = 0;
  for (std::size_t t = 0; t < nt; ++t) new_tet[t] = inside[t] ? count++ : kNone;
  if (count == 0)
    throw GeometryError("mesh_volume: no tetrahedron of the " + std::to_string(nodes.size_count()) +
                        " nodes lies inside the solid");
  std::vector<std::uint32_t> new_id(nodes.size_count(), kNone);
  std::uint32_t nn = 0;
  out.tets.reserve(4 * std::size_t(count));
  out.tet_region.reserve(count);
  out.tet_adj.reserve(4 * std::size_t(count));
  // The loop below numbers the nodes in order of first use: one core. Meanwhile the other
  // makes the output's pages resident, ahead of the loop's writes, then the adjacency's
  // (written after it): the paper gear box's 23.6M tets write ~850 MB of fresh pages here.
  PageWarmer warmer({{out.tets.data(), out.tets.data() + 4 * std::size_t(count)},
                     {out.tet_region.data(), out.tet_region.data() + count},
                     {out.tet_adj.data(), out.tet_adj.data() + 4 * std::size_t(count)}});
  for (std::size_t t = 0; t < nt; ++t) {
    if (!inside[t]) continue;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t v = tri.v(t, i);
      if (new_id[v] == kNone) new_id[v] = nn++;
      out.tets.push_back(new_id[v]);
    }
    out.tet_region.push_back(region_of.empty() ? 0 : region_of[t]);
  }
  warmer.stop();
  out.tet_adj.resize(4 * std::size_t(count));
  parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      if (new_tet[t] == kNone) continue;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t a = tri.adj(t, i), u = new_tet[a >> 2];
        out.tet_adj[4 * std::size_t(new_tet[t]) + i] = u == kNone ? kNoAdjacentTet : 4 * u + (a & 3);
      }
    }
  }, 1 << 16);
  st.unused_nodes = nodes.size_count() - nn;
  out.nodes.points.xyz.resize(3 * std::size_t(nn));
  out.nodes.kind.resize(nn);
  out.nodes.facet.resize(nn);
  out.nodes.size.resize(nn);
  for (std::size_t i = 0; i < nodes.size_count(); ++i) {
    const std::uint32_t j = new_id[i];
    if (j == kNone) continue;
    std::copy_n(nodes.points.p(std::uint32_t(i)), 3, &out.nodes.points.xyz[3 * std::size_t(j)]);
    out.nodes.kind[j] = nodes.kind[i];
    out.nodes.facet[j] = nodes.facet[i];
    out.nodes.size[j] = nodes.size[i];
  }
  out.boundary.resize(bf.verts.size());
  for (std::size_t k = 0; k < bf.verts.size(); ++k) out.boundary[k] = new_id[bf.verts[k]];
  std::vector<char> on_boundary(nn, 0);
  for (std::uint32_t v : out.boundary) on_boundary[v] = 1;
  if (interfaces)  // nodes on the faces between bodies are on an interface (on both cores:
    // one took 0.25 s of the paper gear box's 1.0 s here; the marks are idempotent stores)
    parallel_for(nt, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t t = b; t < e; ++t) {
        if (!inside[t]) continue;
        for (int i = 0; i < 4; ++i) {
          const std::uint32_t u = tri.adj(t, i) >> 2;
          if (!inside[u] || region_of[u] == region_of[t]) continue;
          for (int j = 0; j < 3; ++j)
            std::atomic_ref<char>(on_boundary[new_id[tri.v(t, kTetFace[i][j])]]).store(1, std::memory_order_relaxed);
        }
      }
    }, 1 << 16);
  for (std::uint32_t v = 0; v < nn; ++v)
    if (!on_boundary[v] && out.nodes.kind[v] != NodeKind::interior) {
      out.nodes.kind[v] = NodeKind::interior;
      out.nodes.facet[v] = kNoFacet;
      ++st.buried_nodes;
    }
  out.boundary_tet.resize(bf.tet.size());
  for (std::size_t f = 0; f < bf.tet.size(); ++f) out.boundary_tet[f] = new_tet[bf.tet[f]];
}

/// Puts the answers `asked` about tets of `tri` into `memo`, and empties `asked`.
void remember(const Triangulation& tri, std::vector<TetMemo::Asked>& asked, TetMemo& memo) {
  memo.put(asked.size(), [&](std::size_t k) { return &tri.data[8 * std::size_t(asked[k].tet)]; },
           [&](std::size_t k) { return asked[k].answer; });
  std::vector<TetMemo::Asked>().swap(asked);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

VolumeMesh mesh_volume(const Domain& domain, NodeSet nodes, const VolumeMeshOptions& options) {
  const PreparedSurface& surface = domain.surface;
  const SurfaceQuery& query = domain.query;
  const std::size_t n0 = nodes.points.size();
  if (nodes.kind.size() != n0 || nodes.facet.size() != n0 || nodes.size.size() != n0)
    throw UsageError("mesh_volume: the node set's kind/facet/size arrays (" +
                     std::to_string(nodes.kind.size()) + "/" + std::to_string(nodes.facet.size()) +
                     "/" + std::to_string(nodes.size.size()) + ") do not match its " +
                     std::to_string(n0) + " points");
  if (const std::size_t bad = first_non_finite(nodes.points); bad < n0)
    throw GeometryError("mesh_volume: node " + std::to_string(bad) + " has a non-finite coordinate");
  if (options.max_steiner_rounds < 0)
    throw UsageError("mesh_volume: max_steiner_rounds must be >= 0");
  if (!(options.hausdorff_tolerance > 0))
    throw UsageError("mesh_volume: hausdorff_tolerance must be > 0");
  for (std::size_t i = 0; i < n0; ++i)
    if (nodes.facet[i] != kNoFacet && nodes.facet[i] >= surface.mesh.num_tris())
      throw UsageError("mesh_volume: node " + std::to_string(i) + " names facet " +
                       std::to_string(nodes.facet[i]) + ", but the surface has " +
                       std::to_string(surface.mesh.num_tris()));

  Stopwatch total;
  VolumeMesh out;
  VolumeMeshStats& st = out.stats;
  st.input_nodes = n0;
  const double* bmin = surface.bbox_min;
  const double* bmax = surface.bbox_max;
  double diag = 0;
  for (int k = 0; k < 3; ++k) diag += (bmax[k] - bmin[k]) * (bmax[k] - bmin[k]);
  diag = std::sqrt(diag);

  DelaunayResult dr;
  std::unique_ptr<CreaseFinder> creases;  // built on the first recovery round
  bool rebuild = false;                    // nodes were dropped: triangulate from scratch
  std::vector<std::uint32_t> pending_ids, pending_hints;  // Steiner points to insert, hints
  std::vector<std::uint8_t> inside;
  std::vector<std::uint32_t> label;  // touching bodies: the region of each tet (kNoRegion outside)
  BoundaryFaces bf;
  std::size_t folds_peeled = 0;  // all-surface tets taken out of the solid (peel_folds)
  FaceVerdicts verdicts;         // boundary faces judged in earlier rounds (same node ids)
  // The side and region answers of earlier rounds, and the interior nodes' regions (same
  // node ids). A Steiner round changes few tets: on the paper gear box its classification and
  // region labels took 0.56 and 0.66 s asking again what the first round had asked. A round's
  // answers go into the memos only when another round follows.
  TetMemo sides, tet_regions;
  std::vector<TetMemo::Asked> sides_asked, regions_asked;
  std::vector<std::int32_t> node_regions;
  for (int round = 0;; ++round) {
    if (round == 0 || rebuild) {
      dr = triangulate(nodes, options, st);
      if (round == 0) st.delaunay = dr.stats;
    } else {
      Stopwatch si;  // only Steiner points were added: insert them into the triangulation
      DelaunayStats ds;
      delaunay_insert(dr.tri, nodes.points, pending_ids, pending_hints, ds);
      st.delaunay_seconds += si.seconds();
      ++st.insert_rounds;
    }
    Stopwatch sw;
    if (options.progress) options.progress("classify", 0);
    inside = classify(dr.tri, nodes, query, domain.regions, kOnSurfaceDistance * diag, sides, sides_asked, st);
    st.classify_seconds += sw.seconds();
    if (options.progress) options.progress("classify", 1);

    sw.reset();
    // 0.8 x the tolerance: the mesher samples each face at its centroid and edge midpoints,
    // the independent check more densely, so the margin keeps its verdict the same.
    const double tolerance = 0.8 * options.hausdorff_tolerance;
    bf = boundary_faces(dr.tri, inside);
    RoundFaults rf;
    BoundaryJudgement& judge = rf.judge;
    judge = judge_boundary(bf, nodes, domain, tolerance, &verdicts);
    if (!judge.bad_faces.empty() || !judge.bad_vertices.empty() || !judge.bad_edges.empty()) {
      const std::size_t peeled = peel_folds(dr.tri, nodes, domain, tolerance, bf, judge, inside);
      if (peeled > 0) {
        folds_peeled += peeled;
        bf = boundary_faces(dr.tri, inside);
        judge = judge_boundary(bf, nodes, domain, tolerance, &verdicts);
      }
    }
    rf.flat = flat_inside_tets(dr.tri, nodes, inside);
    // Touching bodies: each tet's body, and the faces between bodies against the interfaces.
    if (domain.regions) {
      Stopwatch ic;
      label = label_regions(dr.tri, nodes, domain, inside, &st.side_queries, &tet_regions, &regions_asked,
                            &node_regions);
      rf.ifaces = interface_faces(dr.tri, label);
      rf.ij = judge_interfaces(rf.ifaces, dr.tri, label, nodes, domain, tolerance);
      st.interface_seconds += ic.seconds();
    }
    if (rf.empty()) {
      st.recover_seconds += sw.seconds();
      break;
    }

    RecoveryPlan plan = plan_recovery(dr.tri, nodes, domain, bf, rf, st);
    NodeSet steiner;
    std::vector<std::uint32_t> steiner_hint;
    choose_steiner(plan, nodes, domain, creases, steiner, steiner_hint);
    st.recover_seconds += sw.seconds();

    const bool progress_made = plan.dropped > 0 || steiner.size_count() > 0;
    if (round >= options.max_steiner_rounds || !progress_made)
      throw_unrecovered(round, progress_made, folds_peeled, dr.tri, bf, rf, nodes);
    const std::size_t dropped = plan.dropped;
    const std::vector<std::uint8_t>& drop = plan.drop;
    st.dropped_nodes += dropped;
    st.steiner_points += steiner.size_count();
    st.rounds = round + 1;
    rebuild = dropped > 0;
    pending_ids.clear();
    pending_hints.clear();
    if (!rebuild) {  // ids of the existing nodes are unchanged; the new ones follow
      for (std::size_t k = 0; k < steiner.size_count(); ++k) {
        pending_ids.push_back(std::uint32_t(nodes.size_count() + k));
        pending_hints.push_back(steiner_hint[k]);
      }
    }
    nodes = rebuild_nodes(nodes, drop, steiner);
    if (rebuild) {  // the ids changed
      verdicts.clear();
      sides.clear();
      tet_regions.clear();
      node_regions.clear();
    } else {  // (before the Steiner points change the tets)
      remember(dr.tri, sides_asked, sides);
      remember(dr.tri, regions_asked, tet_regions);
    }
  }

  // ---- result: inside tets, boundary, regions; nodes no inside tet uses are removed ----
  Stopwatch sw;
  const std::vector<std::uint32_t> region_of =
      domain.regions ? std::move(label) : component_bodies(dr.tri, inside, bf, nodes, domain);
  compact_result(dr.tri, inside, region_of, bf, nodes, domain.regions != nullptr, out);
  st.region_seconds = sw.seconds();
  st.total_seconds = total.seconds();
  return out;
}

TetMesh to_tet_mesh(const VolumeMesh& mesh, QualitySummary* summary, const TetQualityVisitor& each) {
  TetMesh m;
  m.points = mesh.nodes.points;
  m.tets = mesh.tets;
  const std::size_t n = mesh.nodes.size_count(), nt = mesh.num_tets();
  DataArray kind{"node_kind", {}, {}}, size{"target_size", {}, {}};
  kind.ints.resize(n);
  size.floats.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    kind.ints[i] = std::int32_t(mesh.nodes.kind[i]);
    size.floats[i] = mesh.nodes.size[i];  // the nodes' own floats
  }
  m.point_data.push_back(std::move(kind));
  m.point_data.push_back(std::move(size));
  DataArray region{"region", {}, {}}, dih{"min_dihedral", {}, {}}, rr{"radius_ratio", {}, {}};
  region.ints.resize(nt);
  for (std::size_t t = 0; t < nt; ++t)
    region.ints[t] = t < mesh.tet_region.size() ? std::int32_t(mesh.tet_region[t]) : 0;
  // Per-tet measures to look at, not to compute with: Float32 (the summary's figures come from
  // the doubles). The paper gear box's VTU: 508 -> 348 MB, its write 4.1 -> 2.9 s.
  dih.floats.resize(nt);
  rr.floats.resize(nt);
  const QualitySummary s = summarize_quality(m.points, m.tets, [&](std::size_t t, const TetQuality& q) {
    dih.floats[t] = float(q.min_dihedral);
    rr.floats[t] = float(q.radius_ratio);
    if (each) each(t, q);
  });
  if (summary) *summary = s;
  m.cell_data.push_back(std::move(region));
  m.cell_data.push_back(std::move(dih));
  m.cell_data.push_back(std::move(rr));
  return m;
}

}  // namespace kdmesh
