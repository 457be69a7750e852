// kdmesh — surface patches, feature curves, their transfer to the volume mesh's boundary and
// named boundary groups (CGAL AABB trees stay in this file).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/fe/boundary_groups.h"

#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "core/error.h"
#include "core/timer.h"
#include "core/triangle_distance.h"
#include "mesher/placement/edge_sampling.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

double dist(const double* a, const double* b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// Distance from x to the segment [a, b] (a == b allowed); *t receives the clamped parameter.
double segment_dist(const double* x, const double* a, const double* b, double* t = nullptr) {
  const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]};
  const double dd = dot(d, d);
  double s = dd > 0 ? std::clamp(dot(w, d) / dd, 0.0, 1.0) : 0.0;
  if (t) *t = s;
  const double p[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
  return dist(x, p);
}


std::string xyz(const double* p) {
  std::ostringstream s;
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return s.str();
}

/// Sorted (edge key, facet) pairs of a triangle list: the facets of each edge are one run.
std::vector<std::pair<std::uint64_t, std::uint32_t>> edge_face_pairs(
    const std::vector<std::uint32_t>& tris) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> ef;
  ef.reserve(tris.size());
  for (std::size_t f = 0; f < tris.size() / 3; ++f)
    for (int i = 0; i < 3; ++i)
      ef.emplace_back(edge_key(tris[3 * f + i], tris[3 * f + (i + 1) % 3]), std::uint32_t(f));
  std::sort(ef.begin(), ef.end());
  return ef;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
SurfacePatches segment_surface(const SurfaceMesh& surface, const FeatureEdges& features) {
  SurfacePatches out;
  const std::size_t nt = surface.num_tris();
  // Feature edges by key, with their index in `features`.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> fkeys(features.num_edges());
  for (std::size_t e = 0; e < features.num_edges(); ++e)
    fkeys[e] = {edge_key(features.edges[2 * e], features.edges[2 * e + 1]), std::uint32_t(e)};
  std::sort(fkeys.begin(), fkeys.end());
  auto feature_index = [&](std::uint64_t key) -> std::uint32_t {
    auto it = std::lower_bound(fkeys.begin(), fkeys.end(), std::make_pair(key, std::uint32_t(0)));
    return it != fkeys.end() && it->first == key ? it->second : kNoEntity;
  };

  // Patches: union-find across the non-feature edges.
  const auto ef = edge_face_pairs(surface.tris);
  std::vector<std::uint32_t> parent(nt);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t i = 0; i < ef.size();) {
    std::size_t j = i + 1;
    while (j < ef.size() && ef[j].first == ef[i].first) ++j;
    if (feature_index(ef[i].first) == kNoEntity)
      for (std::size_t k = i + 1; k < j; ++k) {
        const std::uint32_t a = find(ef[i].second), b = find(ef[k].second);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    i = j;
  }
  out.facet_patch.assign(nt, kNoEntity);
  std::vector<std::uint32_t> root_patch(nt, kNoEntity);
  for (std::size_t f = 0; f < nt; ++f) {
    std::uint32_t& p = root_patch[find(std::uint32_t(f))];
    if (p == kNoEntity) p = out.num_patches++;
    out.facet_patch[f] = p;
  }
  out.patch_area.assign(out.num_patches, 0.0);
  for (std::size_t f = 0; f < nt; ++f) {
    const double *a = surface.points.p(surface.tri(f)[0]), *b = surface.points.p(surface.tri(f)[1]),
                 *c = surface.points.p(surface.tri(f)[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    out.patch_area[out.facet_patch[f]] +=
        0.5 * std::hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]);
  }

  // Planar patches: every facet corner on the plane of the patch's first facet (exact).
  out.patch_planar.assign(out.num_patches, 1);
  {
    std::vector<std::uint32_t> first(out.num_patches, kNoEntity);
    for (std::size_t f = 0; f < nt; ++f) {
      std::uint32_t& f0 = first[out.facet_patch[f]];
      if (f0 == kNoEntity) f0 = std::uint32_t(f);
      std::uint8_t& planar = out.patch_planar[out.facet_patch[f]];
      const std::uint32_t* t0 = surface.tri(f0);
      for (int k = 0; k < 3 && planar; ++k)
        planar = pred::orient3d(surface.points.p(t0[0]), surface.points.p(t0[1]), surface.points.p(t0[2]),
                                surface.points.p(surface.tri(f)[k])) == 0;
    }
  }

  // Curves: the polylines of node placement.
  out.edge_curve.assign(features.num_edges(), kNoEntity);
  for (const FeaturePolyline& pl : chain_feature_edges(surface, features)) {
    const std::uint32_t c = std::uint32_t(out.num_curves());
    out.curve_points.insert(out.curve_points.end(), pl.points.begin(), pl.points.end());
    out.curve_start.push_back(std::uint32_t(out.curve_points.size()));
    out.curve_closed.push_back(pl.closed);
    double len = 0;
    for (std::size_t k = 0; k + 1 < pl.points.size(); ++k) {
      len += dist(surface.points.p(pl.points[k]), surface.points.p(pl.points[k + 1]));
      const std::uint32_t e = feature_index(edge_key(pl.points[k], pl.points[k + 1]));
      if (e == kNoEntity)
        throw UsageError("segment_surface: curve " + std::to_string(c) + " joins points " +
                         std::to_string(pl.points[k]) + " and " + std::to_string(pl.points[k + 1]) +
                         ", which is not a feature edge");
      out.edge_curve[e] = c;
    }
    out.curve_length.push_back(len);
    // The patches on both sides: those of the facets of its first segment.
    std::uint32_t p0 = kNoEntity, p1 = kNoEntity;
    if (pl.points.size() >= 2) {
      const std::uint64_t key = edge_key(pl.points[0], pl.points[1]);
      auto it = std::lower_bound(ef.begin(), ef.end(), std::make_pair(key, std::uint32_t(0)));
      if (it == ef.end() || it->first != key)
        throw UsageError("segment_surface: feature edge (" + std::to_string(pl.points[0]) + ", " +
                         std::to_string(pl.points[1]) + ") is not an edge of the surface");
      p0 = p1 = out.facet_patch[it->second];
      if (it + 1 != ef.end() && (it + 1)->first == key) p1 = out.facet_patch[(it + 1)->second];
    }
    out.curve_patches.push_back(std::min(p0, p1));
    out.curve_patches.push_back(std::max(p0, p1));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<K::Triangle_3>;
using TriPrimitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using TriTree = CGAL::AABB_tree<CGAL::AABB_traits<K, TriPrimitive>>;
using Segments = std::vector<K::Segment_3>;
using SegPrimitive = CGAL::AABB_segment_primitive<K, Segments::const_iterator>;
using SegTree = CGAL::AABB_tree<CGAL::AABB_traits<K, SegPrimitive>>;

struct PatchTree {
  Triangles tris;
  std::vector<std::uint32_t> facet;
  TriTree tree;
};
struct CurveTree {
  Segments segs;
  SegTree tree;
};
}  // namespace

struct PatchQuery::Impl {
  const SurfaceMesh* surface;
  const SurfacePatches* patches;
  std::vector<std::uint32_t> start, facets;  // CSR: the facets of each patch
  std::vector<std::unique_ptr<PatchTree>> patch_trees;
  std::vector<std::unique_ptr<CurveTree>> curve_trees;

  K::Point_3 P(std::uint32_t v) const {
    const double* p = surface->points.p(v);
    return K::Point_3(p[0], p[1], p[2]);
  }
};

PatchQuery::PatchQuery(const SurfaceMesh& surface, const SurfacePatches& patches)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.surface = &surface;
  m.patches = &patches;
  m.start.assign(patches.num_patches + 1, 0);
  for (std::uint32_t p : patches.facet_patch) ++m.start[p + 1];
  for (std::size_t p = 0; p < patches.num_patches; ++p) m.start[p + 1] += m.start[p];
  m.facets.resize(patches.facet_patch.size());
  std::vector<std::uint32_t> fill(m.start.begin(), m.start.end() - 1);
  for (std::size_t f = 0; f < patches.facet_patch.size(); ++f)
    m.facets[fill[patches.facet_patch[f]]++] = std::uint32_t(f);
  m.patch_trees.resize(patches.num_patches);
  m.curve_trees.resize(patches.num_curves());
}

PatchQuery::~PatchQuery() = default;

double PatchQuery::closest_in_patch(const double* p, std::uint32_t patch, double* out,
                                    std::uint32_t* facet) {
  Impl& m = *impl_;
  if (patch >= m.patch_trees.size())
    throw UsageError("PatchQuery: patch " + std::to_string(patch) + " does not exist");
  if (!m.patch_trees[patch]) {
    auto t = std::make_unique<PatchTree>();
    for (std::uint32_t k = m.start[patch]; k < m.start[patch + 1]; ++k) {
      const std::uint32_t* v = m.surface->tri(m.facets[k]);
      t->tris.emplace_back(m.P(v[0]), m.P(v[1]), m.P(v[2]));
      t->facet.push_back(m.facets[k]);
    }
    t->tree.insert(t->tris.cbegin(), t->tris.cend());
    t->tree.build();
    t->tree.accelerate_distance_queries();
    m.patch_trees[patch] = std::move(t);
  }
  const PatchTree& t = *m.patch_trees[patch];
  const K::Point_3 q(p[0], p[1], p[2]);
  const auto r = t.tree.closest_point_and_primitive(q);
  out[0] = r.first.x(), out[1] = r.first.y(), out[2] = r.first.z();
  if (facet) *facet = t.facet[std::size_t(r.second - t.tris.cbegin())];
  return dist(p, out);
}

double PatchQuery::closest_on_curve(const double* p, std::uint32_t curve, double* out) {
  Impl& m = *impl_;
  if (curve >= m.curve_trees.size())
    throw UsageError("PatchQuery: curve " + std::to_string(curve) + " does not exist");
  if (!m.curve_trees[curve]) {
    auto t = std::make_unique<CurveTree>();
    const std::uint32_t* c = m.patches->curve(curve);
    for (std::size_t k = 0; k + 1 < m.patches->curve_size(curve); ++k)
      t->segs.emplace_back(m.P(c[k]), m.P(c[k + 1]));
    t->tree.insert(t->segs.cbegin(), t->segs.cend());
    t->tree.build();
    t->tree.accelerate_distance_queries();
    m.curve_trees[curve] = std::move(t);
  }
  const K::Point_3 r = m.curve_trees[curve]->tree.closest_point(K::Point_3(p[0], p[1], p[2]));
  out[0] = r.x(), out[1] = r.y(), out[2] = r.z();
  return dist(p, out);
}

// ---------------------------------------------------------------------------------------------
namespace {

/// Where a boundary node lies on the input surface.
struct NodeLoc {
  enum Type : std::uint8_t { none, patch, curve, vertex } type = none;
  std::uint32_t id = kNoEntity;  ///< patch, curve or surface vertex id
};

/// A node on a curve at arc length s.
struct CurveEntry {
  std::uint32_t curve;
  double s;
  std::uint32_t node;
  bool operator<(const CurveEntry& o) const {
    return curve != o.curve ? curve < o.curve : s != o.s ? s < o.s : node < o.node;
  }
};

constexpr std::size_t kShown = 20;  // problems described per kind

/// Records a problem of one kind while fewer than kShown of that kind were described.
void note(BoundaryGroups& g, std::size_t& shown, const std::string& s) {
  if (shown++ < kShown) g.problems.push_back(s);
}

/// Lookups on the input surface: feature edge -> (curve, segment), surface vertex -> the
/// curves through it with its arc length on each, surface vertex -> its facets.
struct SurfaceIndex {
  std::vector<double> cum;  ///< per curve point: arc length from the curve's start
  std::unordered_map<std::uint64_t, std::uint64_t> seg_of_edge;  ///< edge key -> curve << 32 | k
  /// {vertex id, arc length, curve id} (CurveEntry's fields in that order), sorted by vertex:
  /// both ends of an open curve.
  std::vector<CurveEntry> vertex_curves;
  std::vector<std::uint32_t> vstart, vfacets;  ///< facets around each surface vertex (CSR)

  SurfaceIndex(const SurfaceMesh& surface, const SurfacePatches& patches) {
    cum.assign(patches.curve_points.size(), 0.0);
    for (std::uint32_t c = 0; c < patches.num_curves(); ++c) {
      const std::uint32_t* pts = patches.curve(c);
      const std::size_t n = patches.curve_size(c), o = patches.curve_start[c];
      for (std::size_t k = 0; k + 1 < n; ++k) {
        cum[o + k + 1] = cum[o + k] + dist(surface.points.p(pts[k]), surface.points.p(pts[k + 1]));
        seg_of_edge[edge_key(pts[k], pts[k + 1])] = (std::uint64_t(c) << 32) | k;
      }
      const std::size_t last = patches.curve_closed[c] ? n - 1 : n;  // a loop's end repeats its start
      for (std::size_t k = 0; k < last; ++k) vertex_curves.push_back({pts[k], cum[o + k], c});
    }
    std::sort(vertex_curves.begin(), vertex_curves.end());  // by vertex id (the `curve` field)
    const std::size_t np = surface.points.size(), nt = surface.num_tris();
    vstart.assign(np + 1, 0);
    vfacets.resize(surface.tris.size());
    for (std::uint32_t v : surface.tris) ++vstart[v + 1];
    for (std::size_t v = 0; v < np; ++v) vstart[v + 1] += vstart[v];
    std::vector<std::uint32_t> fill(vstart.begin(), vstart.end() - 1);
    for (std::size_t f = 0; f < nt; ++f)
      for (int i = 0; i < 3; ++i) vfacets[fill[surface.tri(f)[i]]++] = std::uint32_t(f);
  }
  /// The curves through surface vertex v.
  auto curves_at(std::uint32_t v) const {
    return std::equal_range(vertex_curves.begin(), vertex_curves.end(), CurveEntry{v, 0, 0},
                            [](const CurveEntry& a, const CurveEntry& b) { return a.curve < b.curve; });
  }
};

/// Where each boundary node lies (NodeLoc), and the nodes on curves with their arc lengths.
struct Located {
  std::vector<NodeLoc> loc;
  std::vector<CurveEntry> entries;
};

/// Locates every boundary node: on the facet its node records when within a rounding
/// tolerance of it, else on the nearest facet (a relocated node; a problem if it is off the
/// surface); then at a facet corner on a curve, on a feature edge, or inside the patch.
Located locate_nodes(const VolumeMesh& mesh, const SurfaceMesh& surface, const SurfacePatches& patches,
                     const SurfaceQuery& query, const SurfaceIndex& index, BoundaryGroups& g) {
  const NodeSet& nodes = mesh.nodes;
  const std::size_t nt = surface.num_tris();
  std::size_t shown = 0;
  std::vector<char> on_boundary(nodes.points.size(), 0);
  for (std::uint32_t v : mesh.boundary) on_boundary[v] = 1;
  Located out;
  out.loc.resize(nodes.points.size());
  auto facet_tol = [&](std::uint32_t fc) {
    const std::uint32_t* t = surface.tri(fc);
    double l = 0, m = 0;
    for (int k = 0; k < 3; ++k) {
      l = std::max(l, dist(surface.points.p(t[k]), surface.points.p(t[(k + 1) % 3])));
      for (int q = 0; q < 3; ++q) m = std::max(m, std::fabs(surface.points.p(t[k])[q]));
    }
    return 1e-9 * l + 1e-14 * m;
  };
  for (std::uint32_t i = 0; i < nodes.points.size(); ++i) {
    if (!on_boundary[i]) continue;
    const double* x = nodes.points.p(i);
    std::uint32_t f = i < nodes.facet.size() ? nodes.facet[i] : kNoFacet;
    double tol = 0;
    if (f < nt) {
      tol = facet_tol(f);
      const std::uint32_t* t = surface.tri(f);
      if (triangle_distance(x, surface.points.p(t[0]), surface.points.p(t[1]), surface.points.p(t[2])) > tol)
        f = kNoFacet;
    }
    if (f >= nt) {
      double cp[3];
      const double d = query.closest(x, cp, &f);
      if (f >= nt) continue;
      tol = facet_tol(f);
      ++g.relocated_nodes;
      if (d > tol)
        note(g, shown, "boundary node " + std::to_string(i) + " at " + xyz(x) + " is " + std::to_string(d) +
                           " off the surface (nearest facet " + std::to_string(f) + ")");
    }
    const std::uint32_t* t = surface.tri(f);
    NodeLoc l{NodeLoc::patch, patches.facet_patch[f]};
    // The nearest vertex within tol, else the nearest edge within tol: not the first one. In
    // a sliver facet a node on one edge (e.g. a crease Steiner point next to a polyline vertex
    // that edge sampling skipped) can be within tol of another edge too (the gear box: a
    // feature edge and a fan diagonal 6 degrees apart); it lies on the one it is nearest to.
    int at_vertex = -1, on_edge = -1;
    double best = tol;
    for (int k = 0; k < 3; ++k) {
      const double d = dist(x, surface.points.p(t[k]));
      if (d <= best) best = d, at_vertex = k;
    }
    best = tol;
    if (at_vertex < 0)
      for (int k = 0; k < 3; ++k) {
        const double d = segment_dist(x, surface.points.p(t[k]), surface.points.p(t[(k + 1) % 3]));
        if (d <= best) best = d, on_edge = k;
      }
    if (at_vertex >= 0) {
      const auto [b, e] = index.curves_at(t[at_vertex]);
      if (b != e) {
        l = {NodeLoc::vertex, t[at_vertex]};
        for (auto it = b; it != e; ++it) out.entries.push_back({it->node, it->s, i});
      }
    } else if (on_edge >= 0) {
      const std::uint32_t a = t[on_edge], b = t[(on_edge + 1) % 3];
      const auto it = index.seg_of_edge.find(edge_key(a, b));
      if (it != index.seg_of_edge.end()) {
        const std::uint32_t c = std::uint32_t(it->second >> 32), k = std::uint32_t(it->second);
        const std::size_t o = patches.curve_start[c];
        const double* s0 = surface.points.p(patches.curve_points[o + k]);
        const double* s1 = surface.points.p(patches.curve_points[o + k + 1]);
        const double s = std::min(index.cum[o + k] + dist(x, s0), index.cum[o + k] + dist(s0, s1));
        l = {NodeLoc::curve, c};
        out.entries.push_back({c, s, i});
      }
    }
    out.loc[i] = l;
  }
  return out;
}

/// Gives each boundary face a patch: the one patch its located nodes share (topological),
/// else the nearest of their candidate patches (geometric; ambiguous unless clearly the
/// nearest). Faces without a node inside their patch are verified against the closest facet
/// of the whole surface.
class FacePatches {
 public:
  FacePatches(const VolumeMesh& mesh, const SurfaceMesh& surface, const SurfacePatches& patches,
              const SurfaceQuery& query, const SurfaceIndex& index, const std::vector<NodeLoc>& loc,
              BoundaryGroups& g)
      : mesh_(mesh), surface_(surface), patches_(patches), query_(query), index_(index), loc_(loc), g_(g),
        pq_(surface, patches) {}

  void run() {
    const std::size_t nb = mesh_.boundary.size() / 3;
    g_.face_patch.assign(nb, kNoEntity);
    for (std::size_t fb = 0; fb < nb; ++fb) assign(fb);
    g_.patch_faces.assign(patches_.num_patches, 0);
    for (std::uint32_t p : g_.face_patch)
      if (p < patches_.num_patches) ++g_.patch_faces[p];
  }

 private:
  /// The patches a located node may lie in; false for an unconstrained node.
  bool node_patches(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    out.clear();
    const NodeLoc& l = loc_[v];
    switch (l.type) {
      case NodeLoc::none: return false;  // unconstrained (interior or unlocated node)
      case NodeLoc::patch: out.push_back(l.id); break;
      case NodeLoc::curve:
        out.push_back(patches_.curve_patches[2 * l.id]);
        if (patches_.curve_patches[2 * l.id + 1] != out[0]) out.push_back(patches_.curve_patches[2 * l.id + 1]);
        break;
      case NodeLoc::vertex:
        for (std::uint32_t k = index_.vstart[l.id]; k < index_.vstart[l.id + 1]; ++k)
          out.push_back(patches_.facet_patch[index_.vfacets[k]]);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        break;
    }
    return true;
  }

  void assign(std::size_t fb) {
    const std::uint32_t* v = &mesh_.boundary[3 * fb];
    const PointSet& P = mesh_.nodes.points;
    const double *a = P.p(v[0]), *b = P.p(v[1]), *c = P.p(v[2]);
    const double m[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
    const double len = std::max({dist(a, b), dist(b, c), dist(c, a)});
    bool constrained = false, empty = false, inside = false;
    std::vector<std::uint32_t> all;  // union, for faces whose nodes share no patch
    cand_.clear();
    for (int k = 0; k < 3; ++k) {
      inside |= loc_[v[k]].type == NodeLoc::patch;
      if (!node_patches(v[k], other_)) continue;
      all.insert(all.end(), other_.begin(), other_.end());
      if (!constrained) {
        cand_ = other_, constrained = true;
        continue;
      }
      both_.clear();
      std::set_intersection(cand_.begin(), cand_.end(), other_.begin(), other_.end(), std::back_inserter(both_));
      cand_.swap(both_);
      empty = cand_.empty();
    }
    std::uint32_t chosen = kNoEntity;
    if (constrained && cand_.size() == 1) {
      chosen = cand_[0];
      ++g_.topological_faces;
    } else {
      chosen = nearest_candidate(fb, m, len, constrained, empty, all);
    }
    g_.face_patch[fb] = chosen;
    if (!(inside && constrained && cand_.size() == 1)) verify(fb, m, len, chosen);
  }

  /// The nearest of the candidate patches (all the nodes' patches when they share none, or
  /// the closest facet's when none is located); ambiguous unless at most half as far as the next.
  std::uint32_t nearest_candidate(std::size_t fb, const double* m, double len, bool constrained, bool empty,
                                  std::vector<std::uint32_t>& all) {
    ++g_.geometric_faces;
    if (empty || !constrained) {
      std::sort(all.begin(), all.end());
      all.erase(std::unique(all.begin(), all.end()), all.end());
      cand_ = all;
    }
    std::uint32_t chosen = kNoEntity;
    double best = 1e300, second = 1e300, cp[3];
    if (cand_.empty()) {
      std::uint32_t f = kNoFacet;
      best = query_.closest(m, cp, &f);
      chosen = patches_.facet_patch[f];
    }
    for (std::uint32_t p : cand_) {
      const double d = pq_.closest_in_patch(m, p, cp);
      if (d < best) second = best, best = d, chosen = p;
      else if (d < second) second = d;
    }
    if (empty || !constrained || !(best <= 0.5 * second && second > 1e-9 * len)) {
      g_.ambiguous_faces.push_back(std::uint32_t(fb));
      std::ostringstream s;
      s << "boundary face " << fb << " at " << xyz(m) << ": patch " << chosen << " is not certain ("
        << (empty ? "its nodes share no patch; " : !constrained ? "no node on the surface; " : "")
        << "distance to it " << best << ", to the next candidate " << second << ")";
      note(g_, shown_, s.str());
    }
    return chosen;
  }

  /// Verification against the closest facet of the whole surface, for faces without a node
  /// inside their patch (a face with one touches its patch there, and check_volume_mesh bounds
  /// its distance to the surface).
  void verify(std::size_t fb, const double* m, double len, std::uint32_t chosen) {
    ++g_.verified_faces;
    std::uint32_t f = kNoFacet;
    double cp[3];
    const double dg = query_.closest(m, cp, &f);
    if (f >= surface_.num_tris() || patches_.facet_patch[f] == chosen) return;
    const double da = pq_.closest_in_patch(m, chosen, cp);
    if (da > dg + 0.05 * len && (g_.ambiguous_faces.empty() || g_.ambiguous_faces.back() != fb)) {
      g_.ambiguous_faces.push_back(std::uint32_t(fb));
      std::ostringstream s;
      s << "boundary face " << fb << " at " << xyz(m) << " was given patch " << chosen << " but lies " << da
        << " from it and " << dg << " from patch " << patches_.facet_patch[f];
      note(g_, shown_, s.str());
    }
  }

  const VolumeMesh& mesh_;
  const SurfaceMesh& surface_;
  const SurfacePatches& patches_;
  const SurfaceQuery& query_;
  const SurfaceIndex& index_;
  const std::vector<NodeLoc>& loc_;
  BoundaryGroups& g_;
  PatchQuery pq_;
  std::vector<std::uint32_t> cand_, other_, both_;
  std::size_t shown_ = 0;  // ambiguous faces described
};

/// The mesh's feature edges: consecutive nodes along each curve, each of which must be a
/// boundary edge; a closed curve needs three nodes, an open one nodes at both its corners.
/// Returns the edges' keys, sorted.
std::vector<std::uint64_t> curve_edges(std::vector<CurveEntry> entries, const SurfacePatches& patches,
                                       const NodeSet& nodes,
                                       const std::vector<std::pair<std::uint64_t, std::uint32_t>>& bef,
                                       BoundaryGroups& g) {
  std::sort(entries.begin(), entries.end());
  entries.erase(std::unique(entries.begin(), entries.end(),
                            [](const CurveEntry& x, const CurveEntry& y) {
                              return x.curve == y.curve && x.node == y.node && x.s == y.s;
                            }),
                entries.end());
  g.curve_edges.assign(patches.num_curves(), 0);
  std::vector<std::uint64_t> feature_keys;
  std::size_t shown = 0;
  auto has_boundary_edge = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t key = edge_key(a, b);
    auto it = std::lower_bound(bef.begin(), bef.end(), std::make_pair(key, std::uint32_t(0)));
    return it != bef.end() && it->first == key;
  };
  auto add_edge = [&](const CurveEntry& x, const CurveEntry& y, double sy) {
    if (x.node == y.node) return;
    if (!has_boundary_edge(x.node, y.node)) {
      ++g.missing_curve_edges;
      note(g, shown, "curve " + std::to_string(x.curve) + ": consecutive nodes " + std::to_string(x.node) + " " +
                         xyz(nodes.points.p(x.node)) + " and " + std::to_string(y.node) + " " +
                         xyz(nodes.points.p(y.node)) + " are not joined by a boundary edge");
      return;
    }
    g.edges.push_back(x.node), g.edges.push_back(y.node);
    g.edge_curve.push_back(x.curve);
    g.edge_arclength.push_back(x.s), g.edge_arclength.push_back(sy);
    feature_keys.push_back(edge_key(x.node, y.node));
    ++g.curve_edges[x.curve];
  };
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i;
    while (j < entries.size() && entries[j].curve == entries[i].curve) ++j;
    const std::uint32_t c = entries[i].curve;
    for (std::size_t k = i; k + 1 < j; ++k) add_edge(entries[k], entries[k + 1], entries[k + 1].s);
    if (patches.curve_closed[c] && j - i >= 3)
      add_edge(entries[j - 1], entries[i], entries[i].s + patches.curve_length[c]);
    if (patches.curve_closed[c] && j - i == 2) {  // one edge cannot close a loop
      ++g.missing_curve_edges;
      note(g, shown, "closed curve " + std::to_string(c) + " has only 2 mesh nodes");
    }
    if (!patches.curve_closed[c] && (entries[i].s != 0 || entries[j - 1].s != patches.curve_length[c])) {
      ++g.missing_curve_edges;
      note(g, shown, "curve " + std::to_string(c) + ": no mesh node at " +
                         (entries[i].s != 0 ? "its start" : "its end") + " corner");
    }
    i = j;
  }
  std::sort(feature_keys.begin(), feature_keys.end());
  return feature_keys;
}

/// Boundary edges between two patches must lie on a feature curve; every patch must receive
/// a face and every curve an edge.
void check_coverage(const SurfacePatches& patches, const NodeSet& nodes,
                    const std::vector<std::pair<std::uint64_t, std::uint32_t>>& bef,
                    const std::vector<std::uint64_t>& feature_keys, BoundaryGroups& g) {
  std::size_t shown_stray = 0, shown_empty = 0;
  for (std::size_t i = 0; i < bef.size();) {
    std::size_t j = i + 1;
    while (j < bef.size() && bef[j].first == bef[i].first) ++j;
    bool mixed = false;
    for (std::size_t k = i + 1; k < j; ++k) mixed |= g.face_patch[bef[k].second] != g.face_patch[bef[i].second];
    if (mixed && !std::binary_search(feature_keys.begin(), feature_keys.end(), bef[i].first)) {
      ++g.stray_patch_edges;
      const std::uint32_t a = std::uint32_t(bef[i].first >> 32), b = std::uint32_t(bef[i].first);
      note(g, shown_stray, "boundary edge (" + std::to_string(a) + " " + xyz(nodes.points.p(a)) + ", " +
                               std::to_string(b) + " " + xyz(nodes.points.p(b)) + ") separates patches " +
                               std::to_string(g.face_patch[bef[i].second]) + " and " +
                               std::to_string(g.face_patch[bef[i + 1].second]) + " but lies on no feature curve");
    }
    i = j;
  }
  for (std::size_t p = 0; p < patches.num_patches; ++p)
    if (g.patch_faces[p] == 0) {
      ++g.empty_patches;
      note(g, shown_empty, "patch " + std::to_string(p) + " (area " + std::to_string(patches.patch_area[p]) +
                               ") received no boundary face");
    }
  for (std::size_t c = 0; c < patches.num_curves(); ++c)
    if (g.curve_edges[c] == 0) {
      ++g.empty_curves;
      note(g, shown_empty, "curve " + std::to_string(c) + " (length " + std::to_string(patches.curve_length[c]) +
                               ") received no mesh edge");
    }
}

}  // namespace

BoundaryGroups assign_boundary(const VolumeMesh& mesh, const SurfaceMesh& surface,
                               const SurfacePatches& patches, const SurfaceQuery& query) {
  Stopwatch clock;
  BoundaryGroups g;
  const std::size_t nt = surface.num_tris();
  if (patches.facet_patch.size() != nt)
    throw UsageError("assign_boundary: the patches are of another surface (" +
                     std::to_string(patches.facet_patch.size()) + " facets, surface has " +
                     std::to_string(nt) + ")");
  const SurfaceIndex index(surface, patches);
  Located located = locate_nodes(mesh, surface, patches, query, index, g);
  const auto bef = edge_face_pairs(mesh.boundary);  // mesh boundary edges -> their faces
  FacePatches(mesh, surface, patches, query, index, located.loc, g).run();
  const std::vector<std::uint64_t> feature_keys =
      curve_edges(std::move(located.entries), patches, mesh.nodes, bef, g);
  check_coverage(patches, mesh.nodes, bef, feature_keys, g);
  g.seconds = clock.seconds();
  return g;
}

// ---------------------------------------------------------------------------------------------
namespace {

bool valid_group_name(const std::string& s) {
  if (s.empty()) return false;
  for (char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-')) return false;
  return true;
}

/// Distance from x to a zone's geometry (segment, polyline, plane; box / ball: 0 inside,
/// +inf outside; point: the distance to it).
double zone_distance(const SizingZone& z, const double* x) {
  const std::vector<double>& c = z.coords;
  switch (z.kind) {
    case SizingZone::Kind::segment: return segment_dist(x, &c[0], &c[3]);
    case SizingZone::Kind::polyline: {
      double d = 1e300;
      for (std::size_t k = 0; k + 5 < c.size(); k += 3) d = std::min(d, segment_dist(x, &c[k], &c[k + 3]));
      return d;
    }
    case SizingZone::Kind::plane: {
      const double n = std::hypot(c[3], c[4], c[5]);
      return std::fabs((x[0] - c[0]) * c[3] + (x[1] - c[1]) * c[4] + (x[2] - c[2]) * c[5]) / n;
    }
    case SizingZone::Kind::box:
      for (int k = 0; k < 3; ++k)
        if (x[k] < c[k] || x[k] > c[3 + k]) return 1e300;
      return 0;
    case SizingZone::Kind::ball: return dist(x, &c[0]) <= c[3] ? 0 : 1e300;
    case SizingZone::Kind::point: return dist(x, &c[0]);
    case SizingZone::Kind::sharp_edges: break;
  }
  return 1e300;
}

}  // namespace

namespace {

/// Selections of patches and curves by where they lie on the input surface.
struct Selector {
  const SurfaceMesh& surface;
  const SurfacePatches& patches;
  double diag = 0;  ///< the surface's bounding-box diagonal

  Selector(const SurfaceMesh& s, const SurfacePatches& p) : surface(s), patches(p) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < surface.points.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], surface.points.p(std::uint32_t(i))[k]);
        hi[k] = std::max(hi[k], surface.points.p(std::uint32_t(i))[k]);
      }
    if (surface.points.size()) diag = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  }

  /// The patches (dim 2) or curves (dim 1) every point of which satisfies `inside`
  /// (vertices, and edge midpoints).
  template <class Inside>
  std::vector<std::uint32_t> where(int dim, const Inside& inside) const {
    auto mid_inside = [&](const double* a, const double* b) {
      const double m[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
      return inside(m);
    };
    std::vector<std::uint32_t> sel;
    if (dim == 2) {
      std::vector<char> ok(patches.num_patches, 1);
      for (std::size_t f = 0; f < surface.num_tris(); ++f) {
        const std::uint32_t p = patches.facet_patch[f];
        const std::uint32_t* t = surface.tri(f);
        for (int k = 0; k < 3 && ok[p]; ++k) {
          const double *a = surface.points.p(t[k]), *b = surface.points.p(t[(k + 1) % 3]);
          ok[p] = inside(a) && mid_inside(a, b);
        }
      }
      for (std::uint32_t p = 0; p < patches.num_patches; ++p)
        if (ok[p]) sel.push_back(p);
      return sel;
    }
    for (std::uint32_t c = 0; c < patches.num_curves(); ++c) {
      const std::uint32_t* pts = patches.curve(c);
      bool ok = true;
      for (std::size_t k = 0; k < patches.curve_size(c) && ok; ++k) {
        const double* a = surface.points.p(pts[k]);
        ok = inside(a) && (k + 1 == patches.curve_size(c) || mid_inside(a, surface.points.p(pts[k + 1])));
      }
      if (ok) sel.push_back(c);
    }
    return sel;
  }

  /// The patch (dim 2) or curve (dim 1) nearest to x; throws when two are equally near.
  std::vector<std::uint32_t> nearest(const double* x, int dim, const std::string& what) const {
    const std::size_t n = dim == 2 ? patches.num_patches : patches.num_curves();
    std::vector<double> d(n, 1e300);
    if (dim == 2) {
      for (std::size_t f = 0; f < surface.num_tris(); ++f) {
        const std::uint32_t* t = surface.tri(f);
        double& dp = d[patches.facet_patch[f]];
        dp = std::min(dp, triangle_distance(x, surface.points.p(t[0]), surface.points.p(t[1]), surface.points.p(t[2])));
      }
    } else {
      for (std::uint32_t c = 0; c < patches.num_curves(); ++c)
        for (std::size_t k = 0; k + 1 < patches.curve_size(c); ++k)
          d[c] = std::min(d[c], segment_dist(x, surface.points.p(patches.curve(c)[k]),
                                             surface.points.p(patches.curve(c)[k + 1])));
    }
    std::uint32_t best = kNoEntity, second = kNoEntity;
    for (std::uint32_t i = 0; i < n; ++i)
      if (best == kNoEntity || d[i] < d[best]) second = best, best = i;
      else if (second == kNoEntity || d[i] < d[second]) second = i;
    std::vector<std::uint32_t> sel;
    if (best == kNoEntity) return sel;
    if (second != kNoEntity && d[second] - d[best] <= 1e-9 * diag)
      throw UsageError(what + ": the point " + xyz(x) + " is equally near " +
                       (dim == 2 ? "patches " : "curves ") + std::to_string(best) + " and " +
                       std::to_string(second) + " (distance " + std::to_string(d[best]) +
                       "); move it towards the one meant");
    sel.push_back(best);
    return sel;
  }
};

/// The patches or curves of a group selected by the sizing zones named spec.zone; sets dim
/// from the zones' kind when the spec leaves it 0.
std::vector<std::uint32_t> select_by_zone(const GroupSpec& spec, const std::vector<SizingZone>& zones,
                                          const Selector& selector, const GroupOptions& options,
                                          const std::string& what, const std::string& how, int& dim) {
  std::vector<const SizingZone*> zs;
  std::vector<std::string> names;
  for (const SizingZone& z : zones) {
    if (z.name == spec.zone) zs.push_back(&z);
    if (!z.name.empty() && std::find(names.begin(), names.end(), z.name) == names.end()) names.push_back(z.name);
  }
  if (zs.empty()) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw UsageError(what + ": no sizing zone is named '" + spec.zone + "' (named zones: " +
                     (list.empty() ? "none" : list) + ")");
  }
  std::vector<std::uint32_t> sel;
  for (const SizingZone* z : zs) {
    int zdim = 0;
    if (z->kind == SizingZone::Kind::segment || z->kind == SizingZone::Kind::polyline) zdim = 1;
    if (z->kind == SizingZone::Kind::plane) zdim = 2;
    if (z->kind == SizingZone::Kind::sharp_edges)
      throw UsageError(what + ": " + how + " is a sharp-edge zone, which selects no geometry");
    if (dim == 0) dim = zdim;
    if (dim == 0) throw UsageError(what + ": " + how + " is a box, ball or point zone: give 'dim' (1 or 2)");
    if (dim == 2 && zdim == 1)
      throw UsageError(what + ": " + how + " is a line, on which no surface patch lies (use dim 1)");
    if (dim != 1 && dim != 2)
      throw UsageError(what + ": dim must be 1 (curves) or 2 (patches), got " + std::to_string(dim));
    std::vector<std::uint32_t> s;
    if (z->kind == SizingZone::Kind::point) {
      s = selector.nearest(z->coords.data(), dim, what);
    } else {
      const double tol = options.zone_tolerance * z->size;
      s = selector.where(dim, [&](const double* x) { return zone_distance(*z, x) <= tol; });
    }
    sel.insert(sel.end(), s.begin(), s.end());
  }
  return sel;
}

}  // namespace

std::vector<FeGroup> make_groups(const std::vector<GroupSpec>& specs, const SurfaceMesh& surface,
                                 const SurfacePatches& patches,
                                 const std::vector<SizingZone>& zones, std::uint32_t num_bodies,
                                 const GroupOptions& options) {
  std::vector<FeGroup> out;
  if (!options.body_names.empty() && options.body_names.size() != num_bodies)
    throw UsageError("make_groups: " + std::to_string(options.body_names.size()) + " body names for " +
                     std::to_string(num_bodies) + " bodies");
  for (std::uint32_t b = 0; b < num_bodies; ++b)
    out.push_back({options.body_names.empty() ? "body_" + std::to_string(b + 1) : options.body_names[b], 3, {b}});
  const Selector selector(surface, patches);
  auto add = [&](FeGroup grp, const std::string& what) {
    if (!valid_group_name(grp.name))
      throw UsageError(what + ": the name must be non-empty and use only [A-Za-z0-9_-]");
    for (const FeGroup& o : out)
      if (o.dim == grp.dim && o.name == grp.name)
        throw UsageError(what + ": a dim " + std::to_string(grp.dim) + " group '" + grp.name +
                         "' already exists");
    out.push_back(std::move(grp));
  };
  for (const GroupSpec& spec : specs) {
    const std::string what =
        "group '" + spec.name + "'" + (spec.origin.empty() ? "" : " (" + spec.origin + ")");
    int dim = spec.dim;
    std::vector<std::uint32_t> sel;
    std::string how;
    if (spec.by == GroupSpec::Select::zone) {
      how = "zone '" + spec.zone + "'";
      sel = select_by_zone(spec, zones, selector, options, what, how, dim);
    } else {
      if (dim != 1 && dim != 2)
        throw UsageError(what + ": dim must be 1 (curves) or 2 (patches), got " + std::to_string(dim));
      if (spec.by == GroupSpec::Select::point) {
        how = "point " + xyz(spec.point);
        sel = selector.nearest(spec.point, dim, what);
      } else {
        how = "box " + xyz(spec.box_min) + " .. " + xyz(spec.box_max);
        sel = selector.where(dim, [&](const double* x) {
          for (int k = 0; k < 3; ++k)
            if (x[k] < spec.box_min[k] || x[k] > spec.box_max[k]) return false;
          return true;
        });
      }
    }
    std::sort(sel.begin(), sel.end());
    sel.erase(std::unique(sel.begin(), sel.end()), sel.end());
    if (sel.empty())
      throw UsageError(what + ": " + how + " selects no " +
                       (dim == 2 ? "surface patch" : "feature curve") +
                       (dim == 1 ? " (a curve is selected when it lies entirely on / in it)" : ""));
    add({spec.name, dim, std::move(sel)}, what);
  }
  if (options.patch_groups)
    for (std::uint32_t p = 0; p < patches.num_patches; ++p)
      add({"patch_" + std::to_string(p + 1), 2, {p}}, "automatic group patch_" + std::to_string(p + 1));
  if (options.curve_groups)
    for (std::uint32_t c = 0; c < patches.num_curves(); ++c)
      add({"curve_" + std::to_string(c + 1), 1, {c}}, "automatic group curve_" + std::to_string(c + 1));
  return out;
}

}  // namespace kdmesh
