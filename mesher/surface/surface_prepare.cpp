// kdmesh — surface validation and orientation (SurfaceMesh -> PreparedSurface).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The topology checks work on flat arrays: half-edge h = 3f + k runs from corner k of facet f to
// corner k+1; sorting the half-edges by their undirected key groups every edge's uses in
// O(n log n). Non-manifold vertices are found by a union-find over corners (two corners at the
// same point are in one fan when their facets share an edge through that point), shells by a
// union-find over facets. Geometry is decided by exact predicates only: CGAL Epick's
// collinear() for degenerate facets, PMP::self_intersections for intersections, and
// SurfaceQuery::side (segment parity with exact predicates, mesher/surface/surface_query.cpp) for nesting. Shell volumes are
// floating-point sums and are used only for their sign and the reported volumes; a closed
// oriented 2-manifold without self-intersections encloses a region of positive measure, so
// the sign is only at risk for shells of near-zero volume relative to their coordinates.
#include "mesher/surface/surface_prepare.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "mesher/surface/surface_query.h"

namespace kdmesh {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

constexpr std::size_t kMaxNamed = 10;
constexpr std::uint32_t kNone = 0xFFFFFFFFu;

std::string num(double v) {
  char b[32];
  return std::string(b, std::to_chars(b, b + sizeof b, v).ptr);
}

std::string coords(const PointSet& ps, std::uint32_t i) {
  const double* p = ps.p(i);
  std::string s(1, '(');  // appended piecewise: GCC 12 warns (-Wrestrict) on "(" + string
  for (int d = 0; d < 3; ++d) {
    s += num(p[d]);
    s += d < 2 ? ' ' : ')';
  }
  return s;
}

/// "facets 3, 5, 9" (up to kMaxNamed) and the facet list for the exception.
std::string list_facets(const std::vector<std::uint32_t>& facets) {
  std::string s = facets.size() == 1 ? "facet " : "facets ";
  for (std::size_t i = 0; i < facets.size() && i < kMaxNamed; ++i)
    s += (i ? ", " : "") + std::to_string(facets[i]);
  if (facets.size() > kMaxNamed) s += ", ...";
  return s;
}

[[noreturn]] void fail(const std::string& source, const std::string& what, std::vector<std::uint32_t> facets,
                       SurfaceError::Defect defect = SurfaceError::Defect::other) {
  if (facets.size() > kMaxNamed) facets.resize(kMaxNamed);
  throw SurfaceError(source + ": " + what, std::move(facets), defect);
}

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Appends f to `out` unless it is already its last element (keeps lists short and ordered).
void add_unique(std::vector<std::uint32_t>& out, std::uint32_t f) {
  if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
}

/// The surface being prepared (its points already scaled), as the phases below see it.
struct Work {
  const std::string& source;
  SurfaceMesh& mesh;
  std::size_t nf = 0, np = 0;  ///< facets, points (set by check_ids_and_coordinates)
};

/// The shells (facets connected through shared edges), numbered in order of first facet.
struct Shells {
  std::vector<std::uint32_t> first, size;  ///< per shell: its first facet, its facet count
  std::size_t count() const { return first.size(); }
};

/// Empty, malformed or non-finite input: a facet count of zero, ids beyond the points, points
/// with non-finite coordinates (after scaling by `scale`).
void check_ids_and_coordinates(Work& w, double scale) {
  const std::string& source = w.source;
  const SurfaceMesh& mesh = w.mesh;
  const PointSet& pts = mesh.points;
  const std::vector<std::uint32_t>& tris = mesh.tris;
  if (tris.size() % 3 != 0)
    throw UsageError(source + ": surface has " + std::to_string(tris.size()) +
                     " corner ids, not a multiple of 3");
  w.nf = mesh.num_tris();
  w.np = pts.size();
  const std::size_t nf = w.nf, np = w.np;
  if (nf == 0) fail(source, "empty surface: it has no facets", {});
  if (nf > (kNone - 1) / 3) throw UsageError(source + ": too many facets (" + std::to_string(nf) + ")");
  {
    std::vector<std::uint32_t> bad;
    for (std::size_t i = 0; i < tris.size(); ++i)
      if (tris[i] >= np) add_unique(bad, std::uint32_t(i / 3));
    if (!bad.empty())
      fail(source, std::to_string(bad.size()) + " facet(s) refer to point ids beyond the " +
                       std::to_string(np) + " points: " + list_facets(bad), bad);
  }
  {
    std::vector<char> used(np, 0);
    for (std::uint32_t v : tris) used[v] = 1;
    std::vector<std::uint32_t> bad_pts, bad;
    for (std::size_t i = 0; i < np; ++i)
      if (used[i] && !(std::isfinite(pts.xyz[3 * i]) && std::isfinite(pts.xyz[3 * i + 1]) &&
                       std::isfinite(pts.xyz[3 * i + 2])))
        bad_pts.push_back(std::uint32_t(i));
    if (!bad_pts.empty()) {
      for (std::size_t f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k)
          if (std::binary_search(bad_pts.begin(), bad_pts.end(), tris[3 * f + k]))
            add_unique(bad, std::uint32_t(f));
      fail(source, std::to_string(bad_pts.size()) + " point(s) have non-finite coordinates" +
                       (scale != 1 ? " after scaling by " + num(scale) : "") +
                       ", first point " + std::to_string(bad_pts[0]) + " " + coords(pts, bad_pts[0]) +
                       "; used by " + std::to_string(bad.size()) + " facet(s): " + list_facets(bad),
           bad);
    }
  }
}

/// Degenerate facets: exactly collinear corners, including repeated corners.
void check_degenerate(const Work& w) {
  const std::string& source = w.source;
  const SurfaceMesh& mesh = w.mesh;
  const PointSet& pts = mesh.points;
  const std::size_t nf = w.nf;
  auto P = [&](std::uint32_t i) {
    const double* p = pts.p(i);
    return Point(p[0], p[1], p[2]);
  };
  std::vector<std::uint32_t> bad;
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* t = mesh.tri(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || CGAL::collinear(P(t[0]), P(t[1]), P(t[2])))
      bad.push_back(std::uint32_t(f));
  }
  if (!bad.empty()) {
    std::string what = std::to_string(bad.size()) + " degenerate (zero-area) facet(s): ";
    for (std::size_t i = 0; i < bad.size() && i < 3; ++i) {
      const std::uint32_t* t = mesh.tri(bad[i]);
      what += (i ? "; " : "") + std::string("facet ") + std::to_string(bad[i]) + " " +
              coords(pts, t[0]) + " " + coords(pts, t[1]) + " " + coords(pts, t[2]);
    }
    fail(source, what + "; " + list_facets(bad), bad, SurfaceError::Defect::degenerate);
  }
}

/// Duplicated facets: the same 3 points in any order.
void check_duplicates(const Work& w) {
  const std::string& source = w.source;
  const SurfaceMesh& mesh = w.mesh;
  const std::size_t nf = w.nf;
  struct Key {
    std::uint32_t v[3], f;
  };
  std::vector<Key> keys(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    Key& k = keys[f];
    std::copy(mesh.tri(f), mesh.tri(f) + 3, k.v);
    std::sort(k.v, k.v + 3);
    k.f = std::uint32_t(f);
  }
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    return std::tie(a.v[0], a.v[1], a.v[2], a.f) < std::tie(b.v[0], b.v[1], b.v[2], b.f);
  });
  // A facet's orientation: whether its corners are an even permutation of the sorted ones.
  auto even = [&](std::uint32_t f) {
    const std::uint32_t* t = mesh.tri(f);
    const std::size_t lo = std::size_t(std::min_element(t, t + 3) - t);
    return t[(lo + 1) % 3] < t[(lo + 2) % 3];
  };
  std::vector<std::uint32_t> bad;
  std::size_t groups = 0, opposite = 0;  // opposite: groups with copies facing both ways
  for (std::size_t i = 0; i < nf;) {
    std::size_t j = i + 1;
    while (j < nf && std::equal(keys[j].v, keys[j].v + 3, keys[i].v)) ++j;
    if (j - i > 1) {
      ++groups;
      bool both = false;
      for (std::size_t k = i; k < j; ++k) {
        bad.push_back(keys[k].f);
        both |= even(keys[k].f) != even(keys[i].f);
      }
      opposite += both;
    }
    i = j;
  }
  if (!bad.empty()) {
    // Name the duplicates grouped, in order of each group's first facet. The duplicates
    // repair removes same-way copies only: it is hinted at only when that fixes every group.
    fail(source, "duplicated facets: " + std::to_string(groups) +
                     " group(s) of facets with the same 3 points, " + std::to_string(bad.size()) +
                     " facets in all: " + list_facets(bad) +
                     (opposite ? "; " + std::to_string(opposite) +
                                     " group(s) face both ways (solids touching along a face, or a "
                                     "two-sided sheet): no repair applies, separate or merge the solids"
                               : std::string()),
         bad, opposite ? SurfaceError::Defect::other : SurfaceError::Defect::duplicates);
  }
}

/// The twin of each half-edge (h = 3f + k), grouping the half-edges by undirected edge; refuses
/// boundary edges (an open surface) and edges of more than two facets.
std::vector<std::uint32_t> match_edges(const Work& w) {
  const std::string& source = w.source;
  const PointSet& pts = w.mesh.points;
  const std::vector<std::uint32_t>& tris = w.mesh.tris;
  const std::size_t nf = w.nf;
  struct HalfEdge {
    std::uint64_t key;  // min << 32 | max
    std::uint32_t h;    // 3f + k
  };
  std::vector<std::uint32_t> twin(3 * nf, kNone);
  std::vector<HalfEdge> hes(3 * nf);
  for (std::uint32_t h = 0; h < 3 * nf; ++h) {
    const std::uint32_t a = tris[h], b = tris[h - h % 3 + (h % 3 + 1) % 3];
    hes[h] = {std::uint64_t(std::min(a, b)) << 32 | std::max(a, b), h};
  }
  std::sort(hes.begin(), hes.end(),
            [](const HalfEdge& a, const HalfEdge& b) { return a.key != b.key ? a.key < b.key : a.h < b.h; });
  std::vector<std::pair<std::uint64_t, std::uint32_t>> boundary, nonmanifold;  // key, first h
  for (std::size_t i = 0; i < hes.size();) {
    std::size_t j = i + 1;
    while (j < hes.size() && hes[j].key == hes[i].key) ++j;
    if (j - i == 1) {
      boundary.push_back({hes[i].key, hes[i].h});
    } else if (j - i == 2) {
      twin[hes[i].h] = hes[i + 1].h;
      twin[hes[i + 1].h] = hes[i].h;
    } else {
      nonmanifold.push_back({hes[i].key, hes[i].h});
    }
    i = j;
  }
  auto edge_name = [&](std::uint64_t key) {
    const std::uint32_t a = std::uint32_t(key >> 32), b = std::uint32_t(key);
    return "edge " + std::to_string(a) + "-" + std::to_string(b) + " " + coords(pts, a) + "-" +
           coords(pts, b);
  };
  auto facets_of_edge = [&](std::uint64_t key) {
    std::vector<std::uint32_t> fs;
    auto it = std::lower_bound(hes.begin(), hes.end(), key,
                               [](const HalfEdge& e, std::uint64_t k) { return e.key < k; });
    for (; it != hes.end() && it->key == key; ++it) fs.push_back(it->h / 3);
    return fs;
  };
  if (!boundary.empty()) {
    std::sort(boundary.begin(), boundary.end(),
              [](const auto& a, const auto& b) { return a.second < b.second; });
    std::string what = "surface is open: " + std::to_string(boundary.size()) +
                       " boundary edge(s) used by one facet only: ";
    std::vector<std::uint32_t> facets;
    for (std::size_t i = 0; i < boundary.size(); ++i) {
      add_unique(facets, boundary[i].second / 3);
      if (i < kMaxNamed)
        what += (i ? "; " : "") + edge_name(boundary[i].first) + " in facet " +
                std::to_string(boundary[i].second / 3);
    }
    if (boundary.size() > kMaxNamed) what += "; ...";
    fail(source, what + " (" + list_facets(facets) + ")", facets);
  }
  if (!nonmanifold.empty()) {
    std::sort(nonmanifold.begin(), nonmanifold.end(),
              [](const auto& a, const auto& b) { return a.second < b.second; });
    std::string what = std::to_string(nonmanifold.size()) +
                       " non-manifold edge(s) shared by more than 2 facets: ";
    std::vector<std::uint32_t> facets;
    for (std::size_t i = 0; i < nonmanifold.size(); ++i) {
      const std::vector<std::uint32_t> fs = facets_of_edge(nonmanifold[i].first);
      for (std::uint32_t f : fs) add_unique(facets, f);
      if (i < kMaxNamed) what += (i ? "; " : "") + edge_name(nonmanifold[i].first) + " in " + list_facets(fs);
    }
    if (nonmanifold.size() > kMaxNamed) what += "; ...";
    fail(source, what, facets);
  }
  return twin;
}

/// Non-manifold vertices: the corners around a point must form a single fan.
void check_vertex_fans(const Work& w, const std::vector<std::uint32_t>& twin) {
  const std::string& source = w.source;
  const PointSet& pts = w.mesh.points;
  const std::vector<std::uint32_t>& tris = w.mesh.tris;
  const std::size_t nf = w.nf, np = w.np;
  UnionFind fans(3 * nf);
  for (std::uint32_t h = 0; h < 3 * nf; ++h) {
    const std::uint32_t t = twin[h];
    if (t < h) continue;
    const std::uint32_t hn = h - h % 3 + (h % 3 + 1) % 3, tn = t - t % 3 + (t % 3 + 1) % 3;
    // Corners h and hn of facet h/3 sit at the edge's two points; match them with t's.
    if (tris[t] == tris[h]) {
      fans.unite(h, t);
      fans.unite(hn, tn);
    } else {
      fans.unite(h, tn);
      fans.unite(hn, t);
    }
  }
  std::vector<std::uint32_t> fan_of(np, kNone);
  std::vector<std::uint32_t> bad_pts;
  std::vector<char> is_bad(np, 0);
  for (std::uint32_t c = 0; c < 3 * nf; ++c) {
    const std::uint32_t v = tris[c], r = fans.find(c);
    if (fan_of[v] == kNone)
      fan_of[v] = r;
    else if (fan_of[v] != r && !is_bad[v]) {
      is_bad[v] = 1;
      bad_pts.push_back(v);
    }
  }
  if (!bad_pts.empty()) {
    std::string what = std::to_string(bad_pts.size()) +
                       " non-manifold vertex(es) where separate fans of facets meet: ";
    std::vector<std::uint32_t> facets;
    for (std::size_t i = 0; i < bad_pts.size() && i < kMaxNamed; ++i) {
      std::vector<std::uint32_t> fs;
      for (std::uint32_t c = 0; c < 3 * nf; ++c)
        if (tris[c] == bad_pts[i]) fs.push_back(c / 3);
      for (std::uint32_t f : fs) add_unique(facets, f);
      what += (i ? "; " : "") + std::string("vertex ") + std::to_string(bad_pts[i]) + " " +
              coords(pts, bad_pts[i]) + " in " + list_facets(fs);
    }
    if (bad_pts.size() > kMaxNamed) what += "; ...";
    fail(source, what, facets);
  }
}

/// The shells; tri_shell gets each facet's shell.
Shells find_shells(const Work& w, const std::vector<std::uint32_t>& twin,
                   std::vector<std::uint32_t>& tri_shell) {
  const std::size_t nf = w.nf;
  Shells sh;
  tri_shell.assign(nf, kNone);
  UnionFind uf(nf);
  for (std::uint32_t h = 0; h < 3 * nf; ++h) uf.unite(h / 3, twin[h] / 3);
  std::vector<std::uint32_t> id_of_root(nf, kNone);
  for (std::uint32_t f = 0; f < nf; ++f) {
    const std::uint32_t r = uf.find(f);
    if (id_of_root[r] == kNone) {
      id_of_root[r] = std::uint32_t(sh.first.size());
      sh.first.push_back(f);
      sh.size.push_back(0);
    }
    tri_shell[f] = id_of_root[r];
    ++sh.size[tri_shell[f]];
  }
  return sh;
}

/// Orientation within each shell, propagated from the shell's first facet: refuses
/// non-orientable shells, and facets facing against the rest of their shell.
void check_orientation(const Work& w, const std::vector<std::uint32_t>& twin,
                       const std::vector<std::uint32_t>& tri_shell, const Shells& shells) {
  const std::string& source = w.source;
  const std::vector<std::uint32_t>& tris = w.mesh.tris;
  const std::size_t nf = w.nf, ns = shells.count();
  const std::vector<std::uint32_t>& shell_first = shells.first;
  const std::vector<std::uint32_t>& shell_size = shells.size;
  std::vector<std::int8_t> flip(nf, -1);
  std::vector<std::uint32_t> stack, conflict_facets;
  std::vector<std::uint32_t> nonorientable_shells;
  for (std::size_t s = 0; s < ns; ++s) {
    bool conflict = false;
    flip[shell_first[s]] = 0;
    stack.assign(1, shell_first[s]);
    while (!stack.empty()) {
      const std::uint32_t f = stack.back();
      stack.pop_back();
      for (std::uint32_t h = 3 * f; h < 3 * f + 3; ++h) {
        const std::uint32_t t = twin[h], g = t / 3;
        const std::int8_t want = std::int8_t(flip[f] ^ (tris[t] == tris[h] ? 1 : 0));
        if (flip[g] < 0) {
          flip[g] = want;
          stack.push_back(g);
        } else if (flip[g] != want) {
          conflict = true;
          add_unique(conflict_facets, std::min(f, g));
          add_unique(conflict_facets, std::max(f, g));
        }
      }
    }
    if (conflict) nonorientable_shells.push_back(std::uint32_t(s));
  }
  if (!nonorientable_shells.empty())
    fail(source, std::to_string(nonorientable_shells.size()) +
                     " shell(s) are non-orientable (like a Moebius strip or Klein bottle), first shell " +
                     std::to_string(nonorientable_shells[0]) + " (first facet " +
                     std::to_string(shell_first[nonorientable_shells[0]]) +
                     "); facets across the orientation seam: " + list_facets(conflict_facets),
         conflict_facets);
  // Orientable: the facets that disagree with their shell's majority are the defect.
  std::vector<std::size_t> flipped(ns, 0);
  for (std::uint32_t f = 0; f < nf; ++f) flipped[tri_shell[f]] += std::size_t(flip[f]);
  std::vector<std::uint32_t> bad;
  std::string shells_text;
  std::size_t total = 0, bad_shells = 0;
  for (std::uint32_t f = 0; f < nf; ++f) {
    const std::uint32_t s = tri_shell[f];
    if (flipped[s] == 0) continue;
    const int minority = 2 * flipped[s] <= shell_size[s] ? 1 : 0;
    if (flip[f] == minority) bad.push_back(f);
  }
  for (std::size_t s = 0; s < ns; ++s)
    if (flipped[s] > 0) {
      const std::size_t m = std::min(flipped[s], shell_size[s] - flipped[s]);
      total += m;
      if (bad_shells++ < 3)
        shells_text += (shells_text.empty() ? "" : ", ") + std::string("shell ") + std::to_string(s) + ": " +
                       std::to_string(m) + " of " + std::to_string(shell_size[s]);
    }
  if (!bad.empty())
    fail(source, "inconsistent orientation: " + std::to_string(total) +
                     " facet(s) face the opposite way from the rest of their shell (" + shells_text +
                     "), they share edges traversed in the same direction: " + list_facets(bad),
         bad, SurfaceError::Defect::orientation);
}

/// Self-intersections (CGAL PMP; facets sharing an edge or a vertex do not count).
void check_self_intersections(const Work& w) {
  const std::string& source = w.source;
  const SurfaceMesh& mesh = w.mesh;
  const PointSet& pts = mesh.points;
  auto P = [&](std::uint32_t i) {
    const double* p = pts.p(i);
    return Point(p[0], p[1], p[2]);
  };
  Mesh m;  // face index == facet id
  std::vector<Mesh::Vertex_index> vid(w.np);
  std::vector<char> used(w.np, 0);
  for (std::uint32_t v : mesh.tris) used[v] = 1;
  for (std::uint32_t i = 0; i < w.np; ++i)
    if (used[i]) vid[i] = m.add_vertex(P(i));
  for (std::uint32_t f = 0; f < w.nf; ++f) {
    const std::uint32_t* t = mesh.tri(f);
    if (m.add_face(vid[t[0]], vid[t[1]], vid[t[2]]) == Mesh::null_face())
      throw Error(source + ": internal error: facet " + std::to_string(f) +
                  " rejected by CGAL::Surface_mesh after the manifold checks passed");
  }
  constexpr unsigned kMaxPairs = 1000;
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Sequential_tag>(
      m, std::back_inserter(pairs), CGAL::parameters::maximum_number(kMaxPairs));
  if (pairs.empty()) return;
  for (auto& pr : pairs)
    if (pr.second < pr.first) std::swap(pr.first, pr.second);
  std::sort(pairs.begin(), pairs.end());
  std::vector<std::uint32_t> facets;
  std::string what = (pairs.size() >= kMaxPairs ? "at least " : "") + std::to_string(pairs.size()) +
                     " pair(s) of facets intersect: ";
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::uint32_t a = std::uint32_t(pairs[i].first.idx()), b = std::uint32_t(pairs[i].second.idx());
    if (i < kMaxNamed) what += (i ? ", " : "") + std::to_string(a) + "/" + std::to_string(b);
    add_unique(facets, a);
    add_unique(facets, b);
  }
  if (pairs.size() > kMaxNamed) what += ", ...";
  fail(source, what + " (" + list_facets(facets) + ")", facets);
}

/// The signed volume each shell encloses (relative to the shell's first point, for accuracy).
std::vector<double> shell_volumes(const Work& w, const std::vector<std::uint32_t>& tri_shell,
                                  const Shells& shells) {
  const PointSet& pts = w.mesh.points;
  const std::vector<std::uint32_t>& tris = w.mesh.tris;
  std::vector<double> vol(shells.count(), 0.0);
  for (std::size_t f = 0; f < w.nf; ++f) {
    const std::uint32_t s = tri_shell[f];
    const double* o = pts.p(tris[3 * shells.first[s]]);
    const double* a = pts.p(tris[3 * f]);
    const double* b = pts.p(tris[3 * f + 1]);
    const double* c = pts.p(tris[3 * f + 2]);
    const double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2];
    const double bx = b[0] - o[0], by = b[1] - o[1], bz = b[2] - o[2];
    const double cx = c[0] - o[0], cy = c[1] - o[1], cz = c[2] - o[2];
    vol[s] += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  for (double& v : vol) v /= 6;
  return vol;
}

/// Nesting: each shell's parent is the innermost shell whose region contains a point of it
/// (kNone if none); returns each shell's depth (the number of shells containing it). Refuses
/// shells that touch.
std::vector<std::uint32_t> nest_shells(const Work& w, const std::vector<std::uint32_t>& tri_shell,
                                       const Shells& shells, const std::vector<double>& vol,
                                       std::vector<std::uint32_t>& parent) {
  const std::string& source = w.source;
  const PointSet& pts = w.mesh.points;
  const std::vector<std::uint32_t>& tris = w.mesh.tris;
  const std::size_t nf = w.nf, ns = shells.count();
  const std::vector<std::uint32_t>& shell_first = shells.first;
  auto P = [&](std::uint32_t i) {
    const double* p = pts.p(i);
    return Point(p[0], p[1], p[2]);
  };
  parent.assign(ns, kNone);
  std::vector<std::uint32_t> depth(ns, 0);
  if (ns < 2) return depth;
  std::vector<CGAL::Bbox_3> box(ns);
  for (std::uint32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) box[tri_shell[f]] += P(tris[3 * f + k]).bbox();
  auto inside_box = [](const CGAL::Bbox_3& in, const CGAL::Bbox_3& out_box) {
    for (int d = 0; d < 3; ++d)
      if (in.min(d) < out_box.min(d) || in.max(d) > out_box.max(d)) return false;
    return true;
  };
  // Per shell, built when first needed: a SurfaceQuery over its facets alone (its side()
  // is the exact segment parity, mesher/surface/surface_query.cpp).
  std::vector<std::unique_ptr<SurfaceQuery>> side(ns);
  for (std::uint32_t a = 0; a < ns; ++a) {
    const double* q = pts.p(tris[3 * shell_first[a]]);
    for (std::uint32_t b = 0; b < ns; ++b) {
      if (a == b || !inside_box(box[a], box[b])) continue;
      if (!side[b]) {
        SurfaceMesh shell;  // shell b, its points renumbered
        std::vector<std::uint32_t> id(pts.size(), std::uint32_t(-1));
        for (std::uint32_t f = 0; f < nf; ++f) {
          if (tri_shell[f] != b) continue;
          for (int k = 0; k < 3; ++k) {
            std::uint32_t& v = id[tris[3 * f + k]];
            if (v == std::uint32_t(-1)) {
              v = std::uint32_t(shell.points.size());
              const double* x = pts.p(tris[3 * f + k]);
              shell.points.push_back(x[0], x[1], x[2]);
            }
            shell.tris.push_back(v);
          }
        }
        side[b] = std::make_unique<SurfaceQuery>(shell);
      }
      const int s = side[b]->side(q);
      const CGAL::Bounded_side where = s > 0 ? CGAL::ON_BOUNDED_SIDE : s < 0 ? CGAL::ON_UNBOUNDED_SIDE : CGAL::ON_BOUNDARY;
      if (where == CGAL::ON_BOUNDARY)
        fail(source, "shell " + std::to_string(a) + " touches shell " + std::to_string(b) +
                         " at point " + std::to_string(tris[3 * shell_first[a]]) + " " +
                         coords(pts, tris[3 * shell_first[a]]) + " (" +
                         list_facets({shell_first[a], shell_first[b]}) + ")",
             {shell_first[a], shell_first[b]});
      if (where == CGAL::ON_BOUNDED_SIDE) {
        ++depth[a];
        const std::uint32_t p = parent[a];
        if (p == kNone || std::abs(vol[b]) < std::abs(vol[p])) parent[a] = b;
      }
    }
  }
  return depth;
}

/// Drops the points no facet uses (keeping the others' order); returns how many.
std::size_t drop_unused_points(SurfaceMesh& mesh) {
  PointSet& pts = mesh.points;
  const std::size_t np = pts.size();
  std::vector<std::uint32_t> remap(np, kNone);
  for (std::uint32_t v : mesh.tris) remap[v] = 0;
  std::uint32_t kept = 0;
  for (std::size_t i = 0; i < np; ++i)
    if (remap[i] == 0) {
      remap[i] = kept;
      if (kept != i)
        for (int d = 0; d < 3; ++d) pts.xyz[3 * std::size_t(kept) + d] = pts.xyz[3 * i + d];
      ++kept;
    }
  if (kept == np) return 0;
  pts.xyz.resize(3 * std::size_t(kept));
  for (std::uint32_t& v : mesh.tris) v = remap[v];
  return np - kept;
}

}  // namespace

PreparedSurface prepare_surface(SurfaceMesh mesh, const std::string& source,
                                const SurfaceOptions& options) {
  if (!(std::isfinite(options.scale) && options.scale > 0))
    throw UsageError("surface scale " + num(options.scale) + " must be finite and > 0");
  PreparedSurface out;
  auto notice = [&](const std::string& s) {
    out.notices.push_back(s);
    if (options.notice) options.notice(s);
  };
  if (options.scale != 1)
    for (double& v : mesh.points.xyz) v *= options.scale;
  Work w{source, mesh};
  // Topology, then geometry; each check refuses with the facets at fault (SurfaceError).
  check_ids_and_coordinates(w, options.scale);
  check_degenerate(w);
  check_duplicates(w);
  const std::vector<std::uint32_t> twin = match_edges(w);
  check_vertex_fans(w, twin);
  const Shells shells = find_shells(w, twin, out.tri_shell);
  check_orientation(w, twin, out.tri_shell, shells);
  if (options.check_self_intersections) check_self_intersections(w);
  std::vector<double> vol = shell_volumes(w, out.tri_shell, shells);
  const std::vector<std::uint32_t> depth = nest_shells(w, out.tri_shell, shells, vol, out.shell_parent);
  const std::size_t ns = shells.count();
  std::vector<std::uint32_t>& tris = mesh.tris;

  // Each shell oriented by its depth: even = outer boundary (> 0), odd = void (< 0).
  std::vector<char> flip_shell(ns, 0);
  for (std::uint32_t s = 0; s < ns; ++s) {
    const bool outer = depth[s] % 2 == 0;
    if ((vol[s] > 0) == outer) continue;
    flip_shell[s] = 1;
    vol[s] = -vol[s];
    notice("shell " + std::to_string(s) + " (" + std::to_string(shells.size[s]) + " facets, first facet " +
           std::to_string(shells.first[s]) + ") " +
           (outer ? "faced inward: flipped" : "bounds a void but faced into the solid: flipped"));
  }
  for (std::uint32_t f = 0; f < w.nf; ++f)
    if (flip_shell[out.tri_shell[f]]) std::swap(tris[3 * f + 1], tris[3 * f + 2]);

  // Bodies: even-depth shells start one (in shell order), odd-depth ones join their parent.
  out.shell_body.assign(ns, kNone);
  for (std::uint32_t s = 0; s < ns; ++s)
    if (depth[s] % 2 == 0) out.shell_body[s] = out.num_bodies++;
  for (std::uint32_t s = 0; s < ns; ++s)
    if (depth[s] % 2 == 1) out.shell_body[s] = out.shell_body[out.shell_parent[s]];
  out.shell_volume = vol;
  out.volume = std::accumulate(vol.begin(), vol.end(), 0.0);

  // Points no facet uses are dropped (the others keep their order); the bounding box.
  if (const std::size_t dropped = drop_unused_points(mesh))
    notice(std::to_string(dropped) + " point(s) used by no facet were dropped");
  const PointSet& pts = mesh.points;
  for (int d = 0; d < 3; ++d) {
    out.bbox_min[d] = out.bbox_max[d] = pts.xyz[d];
    for (std::size_t i = 0; i < pts.size(); ++i) {
      out.bbox_min[d] = std::min(out.bbox_min[d], pts.xyz[3 * i + d]);
      out.bbox_max[d] = std::max(out.bbox_max[d], pts.xyz[3 * i + d]);
    }
  }
  out.mesh = std::move(mesh);
  return out;
}

}  // namespace kdmesh
