// kdmesh — opt-in safe repairs of a triangle surface.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface/surface_repair.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <unordered_map>

#include "core/error.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

namespace {

constexpr std::size_t kMaxNamed = 10;

std::string facet_list(const std::vector<std::uint32_t>& ids) {
  std::string s;
  for (std::size_t i = 0; i < ids.size() && i < kMaxNamed; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  if (ids.size() > kMaxNamed) s += ", ...";
  return s;
}

std::uint64_t directed(std::uint32_t a, std::uint32_t b) { return std::uint64_t(a) << 32 | b; }

/// The working surface: facets with a removed flag and the input id each came from.
struct Work {
  PointSet& pts;
  std::vector<std::uint32_t>& tris;
  std::vector<std::uint32_t> origin;
  std::vector<char> removed;
  std::uint32_t* tri(std::uint32_t f) { return tris.data() + 3 * std::size_t(f); }
  std::uint32_t count() const { return std::uint32_t(tris.size() / 3); }
};

/// Index of the corner of the collinear facet t that lies strictly between the other two.
int middle_corner(const PointSet& pts, const std::uint32_t* t) {
  for (int axis = 0; axis < 3; ++axis) {
    const double x[3] = {pts.p(t[0])[axis], pts.p(t[1])[axis], pts.p(t[2])[axis]};
    if (x[0] == x[1] && x[1] == x[2]) continue;  // the line is orthogonal to this axis
    for (int k = 0; k < 3; ++k) {
      const double u = x[(k + 1) % 3], v = x[(k + 2) % 3];
      if ((u < x[k] && x[k] < v) || (v < x[k] && x[k] < u)) return k;
    }
  }
  return -1;  // cannot happen for three distinct collinear points
}

void repair_degenerate(Work& w, SurfaceRepairReport& report) {
  std::vector<std::uint32_t> collapsed, caps;
  for (std::uint32_t f = 0; f < w.count(); ++f) {
    const std::uint32_t* t = w.tri(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      w.removed[f] = 1;
      collapsed.push_back(w.origin[f]);
    } else if (pred::collinear(w.pts.p(t[0]), w.pts.p(t[1]), w.pts.p(t[2]))) {
      caps.push_back(f);
    }
  }
  report.removed_collapsed = collapsed.size();
  if (!collapsed.empty())
    report.notes.push_back("repair: removed " + std::to_string(collapsed.size()) +
                           " facet(s) with a repeated corner: facets " + facet_list(collapsed));
  if (caps.empty()) return;

  std::unordered_multimap<std::uint64_t, std::uint32_t> edges;  // directed edge -> facet
  auto add_edges = [&](std::uint32_t f) {
    const std::uint32_t* t = w.tri(f);
    for (int k = 0; k < 3; ++k) edges.emplace(directed(t[k], t[(k + 1) % 3]), f);
  };
  auto remove_edges = [&](std::uint32_t f) {
    const std::uint32_t* t = w.tri(f);
    for (int k = 0; k < 3; ++k) {
      auto [lo, hi] = edges.equal_range(directed(t[k], t[(k + 1) % 3]));
      for (auto it = lo; it != hi; ++it)
        if (it->second == f) {
          edges.erase(it);
          break;
        }
    }
  };
  for (std::uint32_t f = 0; f < w.count(); ++f)
    if (!w.removed[f]) add_edges(f);
  std::vector<char> is_cap(w.count(), 0);
  for (std::uint32_t f : caps) is_cap[f] = 1;

  std::vector<std::uint32_t> fixed;
  for (bool progress = true; progress;) {  // a cap whose neighbour is a cap waits for it
    progress = false;
    for (std::uint32_t& f : caps) {
      if (f == kNoFacet) continue;
      std::uint32_t* t = w.tri(f);
      const int m = middle_corner(w.pts, t);
      const std::uint32_t a = t[(m + 2) % 3], b = t[m], c = t[(m + 1) % 3];  // cyclic (a, b, c)
      // The facet across the long edge c->a traverses it as a->c; exactly one, not a cap.
      auto [lo, hi] = edges.equal_range(directed(a, c));
      if (lo == hi || std::next(lo) != hi) continue;
      const std::uint32_t n = lo->second;
      if (is_cap[n]) continue;
      const std::uint32_t* nt = w.tri(n);
      const int k = int(std::find(nt, nt + 3, a) - nt);
      const std::uint32_t d = nt[(k + 2) % 3];  // n = (a, c, d) cyclically
      remove_edges(f);
      remove_edges(n);
      w.removed[f] = 1;
      std::uint32_t* nn = w.tri(n);
      nn[0] = a, nn[1] = b, nn[2] = d;
      const std::uint32_t half[3] = {b, c, d};
      w.tris.insert(w.tris.end(), half, half + 3);
      w.origin.push_back(w.origin[n]);
      w.removed.push_back(0);
      is_cap.push_back(0);
      add_edges(n);
      add_edges(w.count() - 1);
      fixed.push_back(w.origin[f]);
      f = kNoFacet;
      progress = true;
    }
  }
  report.split_caps = fixed.size();
  report.unfixed_caps = std::size_t(std::count_if(caps.begin(), caps.end(), [](std::uint32_t f) { return f != kNoFacet; }));
  std::sort(fixed.begin(), fixed.end());
  if (!fixed.empty())
    report.notes.push_back("repair: removed " + std::to_string(fixed.size()) +
                           " zero-area facet(s) with collinear corners by splitting the facet across "
                           "each one's long edge at its middle corner: facets " + facet_list(fixed));
}

void repair_duplicates(Work& w, SurfaceRepairReport& report) {
  struct Key {
    std::uint32_t sorted[3], cyclic[3], f;
  };
  std::vector<Key> keys;
  for (std::uint32_t f = 0; f < w.count(); ++f) {
    if (w.removed[f]) continue;
    Key k;
    const std::uint32_t* t = w.tri(f);
    std::copy(t, t + 3, k.sorted);
    std::sort(k.sorted, k.sorted + 3);
    const int r = int(std::min_element(t, t + 3) - t);  // rotate the smallest id first
    for (int i = 0; i < 3; ++i) k.cyclic[i] = t[(r + i) % 3];
    k.f = f;
    keys.push_back(k);
  }
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    return std::tie(a.sorted[0], a.sorted[1], a.sorted[2], a.f) < std::tie(b.sorted[0], b.sorted[1], b.sorted[2], b.f);
  });
  std::vector<std::uint32_t> removed;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && std::equal(keys[j].sorted, keys[j].sorted + 3, keys[i].sorted)) ++j;
    bool one_way = true;
    for (std::size_t k = i + 1; k < j; ++k) one_way &= std::equal(keys[k].cyclic, keys[k].cyclic + 3, keys[i].cyclic);
    if (one_way)
      for (std::size_t k = i + 1; k < j; ++k) {
        w.removed[keys[k].f] = 1;
        removed.push_back(w.origin[keys[k].f]);
      }
    i = j;
  }
  std::sort(removed.begin(), removed.end());
  report.removed_duplicates = removed.size();
  if (!removed.empty())
    report.notes.push_back("repair: removed " + std::to_string(removed.size()) +
                           " duplicated facet(s) (copies of an earlier facet, same orientation): facets " +
                           facet_list(removed));
}

void repair_orientation(Work& w, SurfaceRepairReport& report) {
  // Twins through edges used by exactly two live facets.
  struct HalfEdge {
    std::uint64_t key;
    std::uint32_t h;
  };
  std::vector<HalfEdge> hes;
  for (std::uint32_t f = 0; f < w.count(); ++f) {
    if (w.removed[f]) continue;
    const std::uint32_t* t = w.tri(f);
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      hes.push_back({std::uint64_t(std::min(a, b)) << 32 | std::max(a, b), 3 * f + k});
    }
  }
  std::sort(hes.begin(), hes.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return a.key != b.key ? a.key < b.key : a.h < b.h;
  });
  std::vector<std::uint32_t> twin(w.tris.size(), kNoFacet);
  for (std::size_t i = 0; i < hes.size();) {
    std::size_t j = i + 1;
    while (j < hes.size() && hes[j].key == hes[i].key) ++j;
    if (j - i == 2) {
      twin[hes[i].h] = hes[i + 1].h;
      twin[hes[i + 1].h] = hes[i].h;
    }
    i = j;
  }
  std::vector<std::int8_t> flip(w.count(), -1);
  std::vector<std::uint32_t> piece, stack, flipped_ids;
  for (std::uint32_t seed = 0; seed < w.count(); ++seed) {
    if (w.removed[seed] || flip[seed] >= 0) continue;
    bool conflict = false;
    piece.assign(1, seed);
    stack.assign(1, seed);
    flip[seed] = 0;
    while (!stack.empty()) {
      const std::uint32_t f = stack.back();
      stack.pop_back();
      for (std::uint32_t h = 3 * f; h < 3 * f + 3; ++h) {
        const std::uint32_t t = twin[h];
        if (t == kNoFacet) continue;
        const std::uint32_t g = t / 3;
        const std::int8_t want = std::int8_t(flip[f] ^ (w.tris[t] == w.tris[h] ? 1 : 0));
        if (flip[g] < 0) {
          flip[g] = want;
          piece.push_back(g);
          stack.push_back(g);
        } else if (flip[g] != want) {
          conflict = true;
        }
      }
    }
    if (conflict) continue;  // not orientable: validation names it
    const std::size_t ones = std::size_t(std::count_if(piece.begin(), piece.end(), [&](std::uint32_t f) { return flip[f] == 1; }));
    const std::int8_t minority = 2 * ones <= piece.size() ? 1 : 0;
    for (std::uint32_t f : piece)
      if (flip[f] == minority) {
        std::swap(w.tri(f)[1], w.tri(f)[2]);
        flipped_ids.push_back(w.origin[f]);
      }
  }
  std::sort(flipped_ids.begin(), flipped_ids.end());
  report.flipped = flipped_ids.size();
  if (!flipped_ids.empty())
    report.notes.push_back("repair: flipped " + std::to_string(flipped_ids.size()) +
                           " facet(s) to agree with the rest of their shell: facets " + facet_list(flipped_ids));
}

}  // namespace

SurfaceMesh repair_surface(SurfaceMesh mesh, const SurfaceRepairOptions& options, SurfaceRepairReport& report) {
  report = {};
  if (!options.any()) return mesh;
  const std::size_t np = mesh.points.size();
  for (std::uint32_t v : mesh.tris)  // malformed: leave it to validation, which names the facets
    if (v >= np || !std::isfinite(mesh.points.p(v)[0]) || !std::isfinite(mesh.points.p(v)[1]) ||
        !std::isfinite(mesh.points.p(v)[2]))
      return mesh;
  Work w{mesh.points, mesh.tris, {}, std::vector<char>(mesh.num_tris(), 0)};
  w.origin.resize(mesh.num_tris());
  for (std::uint32_t f = 0; f < w.count(); ++f) w.origin[f] = f;
  if (options.degenerate) repair_degenerate(w, report);
  if (options.duplicates) repair_duplicates(w, report);
  if (options.orientation) repair_orientation(w, report);
  std::size_t out = 0;
  for (std::uint32_t f = 0; f < w.count(); ++f)
    if (!w.removed[f]) {
      std::copy(w.tri(f), w.tri(f) + 3, mesh.tris.begin() + long(3 * out));
      ++out;
    }
  mesh.tris.resize(3 * out);
  return mesh;
}

}  // namespace kdmesh
