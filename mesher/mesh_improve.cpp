// kdmesh — quality improvement of a volume mesh: the schedule of flips, relaxation and
// smoothing, and the per-stage measurements (mesher/mesh_improve.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/mesh_improve.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

#include "core/error.h"
#include "core/timer.h"
#include "mesher/improve_flips.h"
#include "mesher/improve_quality.h"
#include "mesher/improve_smooth.h"
#include "mesher/improve_tets.h"
#include "mesher/parallel_for.h"
#include "mesher/quality.h"

namespace kdmesh {

namespace {

ImproveStage measure(const ImproveTets& m, const std::string& name) {
  ImproveStage s;
  s.name = name;
  const std::size_t cap = m.capacity();
  std::vector<float> mind(cap, -1), maxd(cap, -1), rr(cap, 0);
  parallel_for(cap, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      if (!m.alive(std::uint32_t(t))) continue;
      const std::uint32_t* v = m.v(std::uint32_t(t));
      const TetQuality q = tet_quality(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3]));
      mind[t] = float(q.min_dihedral);
      maxd[t] = float(q.max_dihedral);
      rr[t] = float(q.radius_ratio);
    }
  });
  s.min_dihedral = 180;
  double sum = 0;
  for (std::size_t t = 0; t < cap; ++t) {
    if (mind[t] < 0) continue;
    ++s.tets;
    s.min_dihedral = std::min(s.min_dihedral, double(mind[t]));
    s.max_dihedral = std::max(s.max_dihedral, double(maxd[t]));
    sum += rr[t];
    s.under5 += mind[t] < 5;
    s.under10 += mind[t] < 10;
    s.under12 += mind[t] < 12;
    s.over165 += maxd[t] > 165;
  }
  s.mean_radius_ratio = s.tets ? sum / double(s.tets) : 0;
  return s;
}

struct Counters {
  std::size_t edge_removals = 0, face_removals = 0;
};

/// tet_sine of every tet slot (+inf for dead slots), in parallel.
std::vector<double> sines(const ImproveTets& m, unsigned threads) {
  std::vector<double> q(m.capacity(), std::numeric_limits<double>::infinity());
  parallel_for(q.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      if (m.alive(std::uint32_t(t))) q[t] = sine_of(m, std::uint32_t(t));
  }, 65536, threads);
  return q;
}

/// Flips until no tet below `threshold` has an improving edge or face removal. Tets are
/// taken worst first (ties by id); each takes the best of its candidates.
std::size_t flip_pass(ImproveTets& m, double threshold, int max_ring, unsigned threads,
                      Counters& c) {
  using Entry = std::tuple<double, std::uint32_t, std::uint32_t>;  // quality, tet, version
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  {
    const std::vector<double> q = sines(m, threads);
    for (std::uint32_t t = 0; t < m.capacity(); ++t)
      if (q[t] < threshold) heap.emplace(q[t], t, m.version(t));
  }
  std::size_t ops = 0;
  FlipCandidate cand, best;
  std::vector<std::uint32_t> created;
  static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  while (!heap.empty()) {
    const auto [q, t, ver] = heap.top();
    heap.pop();
    if (!m.alive(t) || m.version(t) != ver) continue;
    best.q_new = -1;
    best.q_old = 0;
    bool have = false, best_is_edge = false;
    const std::uint32_t* v = m.v(t);
    for (const auto& e : kEdge)
      if (edge_removal(m, t, v[e[0]], v[e[1]], max_ring, cand, have ? best.q_new : -1) &&
          cand.improves() &&
          (!have || cand.q_new > best.q_new)) {
        std::swap(best, cand);
        have = best_is_edge = true;
      }
    for (int i = 0; i < 4; ++i)
      if (face_removal(m, t, i, cand) && cand.improves() && (!have || cand.q_new > best.q_new)) {
        std::swap(best, cand);
        have = true;
        best_is_edge = false;
      }
    if (!have) continue;
    if (!m.replace(best.old, best.fresh, &created)) continue;
    ++ops;
    ++(best_is_edge ? c.edge_removals : c.face_removals);
    for (std::uint32_t n : created) {
      const double qn = sine_of(m, n);
      if (qn < threshold) heap.emplace(qn, n, m.version(n));
    }
  }
  return ops;
}

/// Calls move(v) for every vertex of `verts` (sorted ids), two threads or more at a time but
/// with a result independent of their number. The vertices are labelled by fixed slabs along
/// the longest axis of the mesh's bounding box (from their positions at the start). A vertex
/// whose neighbours all lie in its own or the two adjacent slabs is "local": two local vertices
/// of different even slabs are never neighbours (a neighbour's slab differs by at most one),
/// so their stars share no tet and neither reads a position the other writes. Phase 1 runs
/// the even slabs in parallel, each sequentially in id order; phase 2 the odd slabs; phase 3
/// the non-local vertices sequentially in id order.
template <class Move>
std::size_t slab_pass(ImproveTets& m, const std::vector<std::uint32_t>& verts, unsigned threads,
                      Move&& move) {
  constexpr int kSlabs = 16;
  const NodeSet& nodes = m.nodes();
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t i = 0; i < nodes.size_count(); ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], nodes.points.p(std::uint32_t(i))[k]);
      hi[k] = std::max(hi[k], nodes.points.p(std::uint32_t(i))[k]);
    }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  const double width = (hi[axis] - lo[axis]) / kSlabs;
  std::vector<std::uint8_t> slab(nodes.size_count());
  for (std::size_t i = 0; i < slab.size(); ++i) {
    const double x = nodes.points.p(std::uint32_t(i))[axis];
    slab[i] = std::uint8_t(std::clamp(int(width > 0 ? (x - lo[axis]) / width : 0), 0, kSlabs - 1));
  }
  std::vector<std::uint8_t> local(verts.size(), 0);
  parallel_for(verts.size(), [&](std::size_t b, std::size_t e, unsigned) {
    std::vector<std::uint32_t> star;
    for (std::size_t k = b; k < e; ++k) {
      const std::uint32_t v = verts[k];
      m.star(v, star);
      bool ok = true;
      for (std::uint32_t t : star)
        for (int i = 0; i < 4 && ok; ++i) ok = std::abs(int(slab[m.v(t)[i]]) - int(slab[v])) <= 1;
      local[k] = ok;
    }
  }, 1024, threads);
  std::vector<std::vector<std::uint32_t>> by_slab(kSlabs);
  std::vector<std::uint32_t> rest;
  for (std::size_t k = 0; k < verts.size(); ++k)
    (local[k] ? by_slab[slab[verts[k]]] : rest).push_back(verts[k]);
  std::vector<std::size_t> moved(kSlabs, 0);
  for (int phase = 0; phase < 2; ++phase)
    parallel_for(kSlabs / 2, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t j = b; j < e; ++j) {
        const std::size_t s = 2 * j + std::size_t(phase);
        for (std::uint32_t v : by_slab[s]) moved[s] += move(v);
      }
    }, 1, threads);
  std::size_t total = 0;
  for (std::size_t x : moved) total += x;
  for (std::uint32_t v : rest) total += move(v);
  return total;
}

/// Smooths every vertex of a tet below `threshold`.
std::size_t smooth_pass(ImproveTets& m, double threshold, const SmoothContext& ctx,
                        unsigned threads) {
  std::vector<std::uint8_t> pick(m.nodes().size_count(), 0);
  const std::vector<double> q = sines(m, threads);
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (q[t] < threshold)
      for (int i = 0; i < 4; ++i) pick[m.v(t)[i]] = 1;
  std::vector<std::uint32_t> verts;
  for (std::uint32_t v = 0; v < pick.size(); ++v)
    if (pick[v]) verts.push_back(v);
  return slab_pass(m, verts, threads, [&](std::uint32_t v) { return smooth_vertex(m, v, ctx); });
}

/// Smart-Laplacian relaxation of every vertex of a tet whose radius ratio is below `below`.
std::size_t relax_pass(ImproveTets& m, double below, double floor, const SmoothContext& ctx,
                       unsigned threads) {
  std::vector<std::uint8_t> low(m.capacity(), 0), pick(m.nodes().size_count(), 0);
  parallel_for(low.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      if (!m.alive(std::uint32_t(t))) continue;
      const std::uint32_t* v = m.v(std::uint32_t(t));
      low[t] = tet_radius_ratio(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])) < below;
    }
  }, 65536, threads);
  for (std::uint32_t t = 0; t < m.capacity(); ++t)
    if (low[t])
      for (int i = 0; i < 4; ++i) pick[m.v(t)[i]] = 1;
  std::vector<std::uint32_t> verts;
  for (std::uint32_t v = 0; v < pick.size(); ++v)
    if (pick[v]) verts.push_back(v);
  return slab_pass(m, verts, threads,
                   [&](std::uint32_t v) { return relax_vertex(m, v, ctx, floor); });
}

}  // namespace

ImproveStats improve_mesh(VolumeMesh& mesh, const PreparedSurface& surface,
                          const SurfaceQuery& query, const SizingField& /*sizing*/,
                          const ImproveOptions& options) {
  if (!(options.work_angle > 0 && options.work_angle < 90))
    throw UsageError("improve_mesh: work_angle must be in (0, 90) degrees");
  if (options.rounds < 0) throw UsageError("improve_mesh: rounds must be >= 0");
  if (options.max_ring < 3) throw UsageError("improve_mesh: max_ring must be >= 3");
  Stopwatch total, sw;
  ImproveStats st;
  const int total_stages = 1 + 2 * options.rounds + std::min(options.rounds, options.relax_rounds);
  ImproveTets m(mesh.nodes, mesh.tets, mesh.tet_region);
  m.inside_query = &query;
  auto stage = [&](const std::string& name, std::size_t ops) {
    const double seconds = sw.seconds();
    ImproveStage s;
    if (options.measure_stages) s = measure(m, name);
    s.name = name;
    s.operations = ops;
    s.seconds = seconds;
    st.stages.push_back(s);
    if (options.progress)
      options.progress("improve", double(st.stages.size()) / double(total_stages));
    sw.reset();
  };
  stage("input", 0);  // its time: building the adjacency
  double diag = 0;
  for (int k = 0; k < 3; ++k)
    diag += (surface.bbox_max[k] - surface.bbox_min[k]) * (surface.bbox_max[k] - surface.bbox_min[k]);
  diag = std::sqrt(diag);
  SmoothContext ctx;
  if (options.smooth_surface) {
    ctx.surface = &surface;
    ctx.query = &query;
  }
  ctx.on_surface = 1e-11 * diag;
  const double threshold = deg_to_sine(options.work_angle);
  const double smooth_threshold = deg_to_sine(options.smooth_angle);
  Counters c;
  for (int r = 0; r < options.rounds; ++r) {
    const std::string n = std::to_string(r + 1);
    const std::size_t ops = flip_pass(m, threshold, options.max_ring, options.threads, c);
    stage("flip " + n, ops);
    if (r < options.relax_rounds) {
      const std::size_t relaxed = relax_pass(m, options.relax_below, threshold, ctx, options.threads);
      st.relaxed += relaxed;
      stage("relax " + n, relaxed);
    }
    const std::size_t moved = smooth_pass(m, smooth_threshold, ctx, options.threads);
    st.smoothed += moved;
    stage("smooth " + n, moved);
  }
  st.edge_removals = c.edge_removals;
  st.face_removals = c.face_removals;
  st.boundary_changes = m.write_back(mesh);
  st.seconds = total.seconds();
  return st;
}

}  // namespace kdmesh
