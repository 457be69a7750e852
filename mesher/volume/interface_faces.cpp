// kdmesh — regions of touching bodies and the faces between them (mesher/volume/interface_faces.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/volume/interface_faces.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel_collect.h"
#include "core/parallel_for.h"
#include "mesher/tet_quality.h"
#include "mesher/volume/boundary_faces.h"

namespace kdmesh {

std::vector<std::uint32_t> label_regions(const Triangulation& tri, const NodeSet& nodes, const Domain& domain,
                                         const std::vector<std::uint8_t>& inside, std::size_t* queries,
                                         const TetMemo* memo, std::vector<TetMemo::Asked>* asked_tets,
                                         std::vector<std::int32_t>* node_regions) {
  if (!domain.regions) throw UsageError("label_regions: the domain has no region queries");
  const RegionQuery& rq = *domain.regions;
  const std::size_t n = tri.num_tets(), nn = nodes.size_count();
  std::vector<std::int32_t> own_node_regions;
  std::vector<std::int32_t>& node_region = node_regions ? *node_regions : own_node_regions;
  if (node_region.size() > nn)
    throw UsageError("label_regions: the node regions given are for " + std::to_string(node_region.size()) +
                     " nodes, but there are " + std::to_string(nn));
  const std::size_t known = node_region.size();
  node_region.resize(nn, -1);
  parallel_for(nn - known, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = known + b; i < known + e; ++i)
      if (nodes.kind[i] == NodeKind::interior) node_region[i] = rq.region(nodes.points.p(std::uint32_t(i)));
  }, 1024);
  std::size_t asked = 0;
  for (std::size_t i = known; i < nn; ++i) asked += nodes.kind[i] == NodeKind::interior;
  auto own = [&](std::uint32_t t) {
    double c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = (nodes.points.p(tri.v(t, 0))[k] + nodes.points.p(tri.v(t, 1))[k] + nodes.points.p(tri.v(t, 2))[k] +
              nodes.points.p(tri.v(t, 3))[k]) / 4;
    return rq.region(c);
  };
  // own() of every tet of `wave` into `answer`: from the memo where it knows the tet, asked
  // (and listed in asked_tets) otherwise.
  if (asked_tets) asked_tets->clear();
  const bool recall = memo && memo->size() > 0;  // (the first round's memo is empty: no lookups)
  std::vector<std::uint8_t> fresh;
  auto ask = [&](const std::vector<std::uint32_t>& wave, std::vector<std::int32_t>& answer) {
    answer.assign(wave.size(), 0);
    fresh.assign(wave.size(), 1);
    parallel_for(wave.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t k = b; k < e; ++k) {
        const std::int32_t m = recall ? memo->find(&tri.data[8 * std::size_t(wave[k])]) : TetMemo::kNone;
        fresh[k] = m == TetMemo::kNone;
        answer[k] = fresh[k] ? own(wave[k]) : m;
      }
    }, 256);
    for (std::size_t k = 0; k < wave.size(); ++k) {
      if (!fresh[k]) continue;
      ++asked;
      if (asked_tets) asked_tets->push_back({wave[k], answer[k]});
    }
  };
  std::vector<std::uint32_t> label(n, kNoRegion);
  std::vector<std::uint8_t> verified(n, 0);
  // (The scans over every tet below run on all threads; the lists come out in tet order.)
  std::vector<std::uint32_t> wave = parallel_collect(n, [&](std::size_t t) {
    if (!inside[t]) return false;
    std::int32_t r = -1;
    bool mixed = false;
    for (int i = 0; i < 4; ++i) {
      const std::int32_t x = node_region[tri.v(std::uint32_t(t), i)];
      if (x < 0) continue;
      mixed = mixed || (r >= 0 && x != r);
      r = r < 0 ? x : r;
    }
    if (r >= 0 && !mixed) label[t] = std::uint32_t(r);
    return !(r >= 0 && !mixed);
  });
  // The first wave: tets without a body yet, then those next to a tet of another body.
  std::vector<std::int32_t> answer;
  ask(wave, answer);
  for (std::size_t k = 0; k < wave.size(); ++k) {
    verified[wave[k]] = 1;
    // On an interface or outside by rounding: the body of a neighbour decides below.
    label[wave[k]] = answer[k] >= 0 ? std::uint32_t(answer[k]) : kNoRegion - 1;
  }
  wave = parallel_collect(n, [&](std::size_t t) {
    if (!inside[t] || verified[t]) return false;
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t u = tri.adj(std::uint32_t(t), i) >> 2;
      if (inside[u] && label[u] != label[t]) return true;
    }
    return false;
  });
  while (!wave.empty()) {
    for (std::uint32_t t : wave) verified[t] = 1;
    ask(wave, answer);
    std::vector<std::uint32_t> next;
    for (std::size_t k = 0; k < wave.size(); ++k) {
      const std::uint32_t t = wave[k];
      if (answer[k] < 0 || std::uint32_t(answer[k]) == label[t]) continue;
      label[t] = std::uint32_t(answer[k]);
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t u = tri.adj(t, i) >> 2;
        if (inside[u] && !verified[u]) {
          verified[u] = 1;
          next.push_back(u);
        }
      }
    }
    wave.swap(next);
  }
  // Tets whose own centroid lies on a body's surface (flat slivers) take a neighbour's body,
  // in tet order, pass after pass (only they are visited: the others would be skipped).
  const std::vector<std::uint32_t> flat =
      parallel_collect(n, [&](std::size_t t) { return label[t] == kNoRegion - 1; });
  for (bool changed = !flat.empty(); changed;) {
    changed = false;
    for (const std::uint32_t t : flat) {
      if (label[t] != kNoRegion - 1) continue;
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t u = tri.adj(t, i) >> 2;
        if (inside[u] && label[u] < kNoRegion - 1) {
          label[t] = label[u];
          changed = true;
          break;
        }
      }
    }
  }
  for (const std::uint32_t t : flat)
    if (label[t] == kNoRegion - 1) label[t] = 0;
  if (queries) *queries += asked;
  return label;
}

InterfaceFaces interface_faces(const Triangulation& tri, const std::vector<std::uint32_t>& label) {
  InterfaceFaces out;
  auto between = [&](std::uint32_t t, int i) {  // face i of t is an interface face, listed by t
    const std::uint32_t u = tri.adj(t, i) >> 2;
    return label[u] != kNoRegion && label[u] > label[t];
  };
  // The tets with such a face, found on all threads (in tet order), then their faces.
  const std::vector<std::uint32_t> tets = parallel_collect(tri.num_tets(), [&](std::size_t t) {
    if (label[t] == kNoRegion) return false;
    for (int i = 0; i < 4; ++i)
      if (between(std::uint32_t(t), i)) return true;
    return false;
  });
  for (const std::uint32_t t : tets) {
    for (int i = 0; i < 4; ++i) {
      if (!between(t, i)) continue;
      for (int j = 0; j < 3; ++j) out.verts.push_back(tri.v(t, kTetFace[i][j]));
      out.tet.push_back(t);
      out.face.push_back(std::uint8_t(i));
    }
  }
  return out;
}

std::uint8_t judge_interface_face(const std::uint32_t* fv, std::uint32_t ra, std::uint32_t rb, const NodeSet& nodes,
                                  const Domain& domain, double tolerance) {
  std::uint8_t w = 0;
  for (int j = 0; j < 3; ++j)
    if (nodes.kind[fv[j]] == NodeKind::interior) w |= kFaceInterior;
  if (w) return w;
  const RegionQuery& rq = *domain.regions;
  const double *p0 = nodes.points.p(fv[0]), *p1 = nodes.points.p(fv[1]), *p2 = nodes.points.p(fv[2]);
  // Its vertices on an interface, as the mesh check wants them (an outer-surface node next to
  // an interface's rim can join a face between two regions).
  const double* lo = domain.surface.bbox_min;
  const double* hi = domain.surface.bbox_max;
  const double on = kOnSurfaceDistance * std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  for (const double* p : {p0, p1, p2})
    if (!(rq.interfaces().distance(p) <= on)) return kFaceFar;
  double c[3], cp[3];
  for (int k = 0; k < 3; ++k) c[k] = (p0[k] + p1[k] + p2[k]) / 3;
  std::uint32_t facet = kNoFacet;
  double dmax = rq.interfaces().closest(c, cp, &facet);
  const double* ends[3][2] = {{p0, p1}, {p1, p2}, {p2, p0}};
  for (auto& ed : ends) {
    const double m[3] = {(ed[0][0] + ed[1][0]) / 2, (ed[0][1] + ed[1][1]) / 2, (ed[0][2] + ed[1][2]) / 2};
    dmax = std::max(dmax, rq.interfaces().distance(m));
  }
  if (dmax > tolerance * domain.sizing(c)) w |= kFaceFar;
  const std::array<std::uint32_t, 2>& b = rq.bodies(facet);
  if (!((b[0] == ra && b[1] == rb) || (b[0] == rb && b[1] == ra))) w |= kFaceAgainst;
  return w;
}

InterfaceJudgement judge_interfaces(const InterfaceFaces& faces, const Triangulation& tri,
                                    const std::vector<std::uint32_t>& label, const NodeSet& nodes,
                                    const Domain& domain, double tolerance) {
  const std::size_t nf = faces.size();
  std::vector<std::uint8_t> why(nf, 0);
  parallel_for(nf, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t f = b; f < e; ++f) {
      const std::uint32_t t = faces.tet[f];
      const std::uint32_t u = tri.adj(t, faces.face[f]) >> 2;
      why[f] = judge_interface_face(&faces.verts[3 * f], label[t], label[u], nodes, domain, tolerance);
    }
  }, 256);
  InterfaceJudgement j;
  for (std::size_t f = 0; f < nf; ++f) {
    if (!why[f]) continue;
    j.bad_faces.push_back(std::uint32_t(f));
    j.reasons.push_back(why[f] & kFaceInterior ? "interface face with an interior node"
                        : why[f] & kFaceFar    ? "interface face too far from the interface"
                                               : "interface face between other bodies");
  }
  return j;
}

}  // namespace kdmesh
