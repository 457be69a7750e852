// kdmesh — quality improvement of a volume mesh: the schedule of flips, relaxation and
// smoothing, and the per-stage measurements (mesher/improve/mesh_improve.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/mesh_improve.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

#include "core/cpu_count.h"
#include "core/error.h"
#include "core/parallel_for.h"
#include "core/timer.h"
#include "core/uninit_allocator.h"
#include "mesher/improve/flip_pass.h"
#include "mesher/improve/improve_caps.h"
#include "mesher/improve/improve_flips.h"
#include "mesher/improve/improve_insert.h"
#include "mesher/improve/improve_quality.h"
#include "mesher/improve/improve_smooth.h"
#include "mesher/improve/improve_split.h"
#include "mesher/improve/improve_split_boundary.h"
#include "mesher/improve/improve_tets.h"
#include "mesher/improve/sine_cache.h"
#include "mesher/tet_quality.h"

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

/// Calls move(v, star) for every vertex of `verts` (sorted ids), on up to `threads` threads,
/// with a result independent of their number; `star` is v's star (KnownStar), walked once here
/// for the colouring. A move reads the positions of the vertex's star and writes only its own
/// position (and surface facet), so two vertices that share no tet may move at the same time,
/// and no star changes during the pass. The vertices are coloured greedily in id order (each
/// takes the smallest colour none of its earlier neighbours in `verts` has); the colours run
/// one after another, in each colour all its vertices at once. Every move therefore sees the
/// same positions whatever the thread count: neighbours of an earlier colour have moved, those
/// of a later one have not.
template <class Move>
std::vector<std::uint32_t> colour_pass(ImproveTets& m, const std::vector<std::uint32_t>& verts,
                                       unsigned threads, Move&& move) {
  const std::size_t n = verts.size();
  std::vector<std::uint32_t> slot(m.nodes().size_count(), kImproveNone);
  for (std::size_t k = 0; k < n; ++k) slot[verts[k]] = std::uint32_t(k);
  // Each worker walks the stars of a contiguous range of `verts` and lists them, and the
  // earlier neighbours of each vertex (positions in verts, each once). Vertex k's lists start
  // at nb_at[k] and star_at[k] in its worker's arrays. On the paper gear box (3.2M vertices,
  // an 11.5 s relaxation): walking each star again for its move cost 0.8 s; copying the
  // neighbour lists into one array, 0.9 s; listing a neighbour once per tet holding the edge
  // to it (34 entries a vertex instead of about 7) and growing the lists by copying, 0.3 s.
  // The lists are reserved for more than the usual stars (22 tets on average): room never
  // written costs no memory.
  struct Lists {
    std::size_t first = 0, last = 0;  // the worker's range of verts
    std::vector<std::uint32_t> nb, stars;
  };
  std::vector<Lists> lists(available_cpus());
  std::vector<std::size_t, UninitAllocator<std::size_t>> nb_at(n), star_at(n);  // written by the workers
  parallel_for(n, [&](std::size_t b, std::size_t e, unsigned w) {
    std::vector<std::uint32_t> star;
    std::vector<std::uint32_t> listed_for(n, kImproveNone);  // per position: the last k that listed it
    Lists& out = lists[w];
    out.first = b;
    out.last = e;
    out.stars.reserve(32 * (e - b));
    out.nb.reserve(12 * (e - b));
    for (std::size_t k = b; k < e; ++k) {
      const std::uint32_t v = verts[k];
      m.star(v, star);
      nb_at[k] = out.nb.size();
      star_at[k] = out.stars.size();
      out.stars.insert(out.stars.end(), star.begin(), star.end());
      for (std::uint32_t t : star)
        for (int i = 0; i < 4; ++i) {
          const std::uint32_t j = slot[m.v(t)[i]];
          if (j < k && listed_for[j] != k) {
            listed_for[j] = std::uint32_t(k);
            out.nb.push_back(j);
          }
        }
    }
  }, 1024, threads);
  // Vertex k's worker, and each worker's list ends.
  std::vector<std::uint16_t> owner(n);  // (available_cpus() is far below 2^16)
  for (std::size_t w = 0; w < lists.size(); ++w) {
    const Lists& l = lists[w];
    if (l.first >= l.last) continue;
    std::fill(owner.begin() + std::ptrdiff_t(l.first), owner.begin() + std::ptrdiff_t(l.last), std::uint16_t(w));
  }
  auto end_of = [&](const auto& at, std::size_t k, std::size_t size) {
    return k + 1 < lists[owner[k]].last ? at[k + 1] : size;
  };
  // Greedy colouring.
  std::vector<std::uint32_t> colour(n), used;
  std::uint32_t colours = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::vector<std::uint32_t>& nb = lists[owner[k]].nb;
    used.assign(colours + 1, 0);
    for (std::size_t i = nb_at[k], e = end_of(nb_at, k, nb.size()); i < e; ++i) used[colour[nb[i]]] = 1;
    std::uint32_t c = 0;
    while (used[c]) ++c;
    colour[k] = c;
    colours = std::max(colours, c + 1);
  }
  for (Lists& l : lists) std::vector<std::uint32_t>().swap(l.nb);
  std::vector<std::vector<std::uint32_t>> by_colour(colours);  // positions in verts
  for (std::size_t k = 0; k < n; ++k) by_colour[colour[k]].push_back(std::uint32_t(k));
  std::vector<std::uint8_t> moved(n, 0);
  for (const std::vector<std::uint32_t>& group : by_colour)
    parallel_for(group.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t i = b; i < e; ++i) {
        const std::size_t k = group[i];
        const std::vector<std::uint32_t>& stars = lists[owner[k]].stars;
        const std::size_t s0 = star_at[k];
        const KnownStar star{stars.data() + s0, end_of(star_at, k, stars.size()) - s0};
        moved[k] = move(verts[k], star);
      }
    }, 16, threads);
  std::vector<std::uint32_t> out;
  for (std::size_t k = 0; k < n; ++k)
    if (moved[k]) out.push_back(verts[k]);
  return out;
}

/// The vertices of the live tets t with value[t] < below, in id order (the tets scanned on
/// up to `threads` threads: the paper gear box has 23.6M).
std::vector<std::uint32_t> vertices_below(const ImproveTets& m, const double* value, double below,
                                          unsigned threads) {
  std::vector<std::uint8_t> pick(m.nodes().size_count(), 0);
  parallel_for(m.capacity(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t)
      if (value[t] < below && m.alive(std::uint32_t(t)))
        for (int i = 0; i < 4; ++i)
          std::atomic_ref<std::uint8_t>(pick[m.v(std::uint32_t(t))[i]]).store(1, std::memory_order_relaxed);
  }, 65536, threads);
  std::vector<std::uint32_t> verts;
  for (std::uint32_t v = 0; v < pick.size(); ++v)
    if (pick[v]) verts.push_back(v);
  return verts;
}

/// Smooths every vertex of a tet below `threshold`; returns the vertices moved.
std::vector<std::uint32_t> smooth_pass(ImproveTets& m, const SineCache& cache, double threshold,
                                       const SmoothContext& ctx, unsigned threads) {
  const std::vector<std::uint32_t> verts = vertices_below(m, cache.q().data(), threshold, threads);
  return colour_pass(m, verts, threads, [&](std::uint32_t v, const KnownStar& star) {
    return smooth_vertex(m, v, ctx, nullptr, nullptr, &star);
  });
}

/// Smart-Laplacian relaxation of every vertex of a tet whose radius ratio is below `below`;
/// returns the vertices moved. Every tet's ratio is computed once, its sine taken from the
/// cache, and both are kept up to date by the moves (a vertex's star at its own position is
/// then read, not computed: about a third of the relaxation's quality evaluations); the sines
/// go back to the cache.
std::vector<std::uint32_t> relax_pass(ImproveTets& m, SineCache& cache, double below, double floor,
                                      const SmoothContext& ctx, unsigned threads) {
  // (The cache's own array, current for every slot, and a ratio array written whole by the
  // pass: filling fresh arrays of 8 bytes a tet on this thread took about a second of the
  // paper gear box. Computing the sines again with the ratios took about 0.35 s.)
  std::vector<double> sine = cache.take();
  std::vector<double, UninitAllocator<double>> ratio(m.capacity());
  parallel_for(sine.size(), [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t t = b; t < e; ++t) {
      const std::uint32_t* v = m.v(std::uint32_t(t));
      ratio[t] = m.alive(std::uint32_t(t)) ? tet_radius_ratio(m.p(v[0]), m.p(v[1]), m.p(v[2]), m.p(v[3])) : 0;
    }
  }, 65536, threads);
  const std::vector<std::uint32_t> verts = vertices_below(m, ratio.data(), below, threads);
  const StarValues known{sine.data(), ratio.data()};
  std::vector<std::uint32_t> moved = colour_pass(
      m, verts, threads,
      [&](std::uint32_t v, const KnownStar& star) { return relax_vertex(m, v, ctx, floor, &known, &star); });
  cache.assign(std::move(sine));
  return moved;
}


/// Takes out every boundary cap below `threshold` (worst first, ties by id); a tet that a
/// removal leaves with two boundary faces is tried too. Returns how many were removed.
std::size_t cap_pass(ImproveTets& m, SineCache& cache, double threshold, const BoundaryContext& ctx) {
  using Entry = std::tuple<double, std::uint32_t, std::uint32_t>;  // quality, tet, version
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  for (std::uint32_t t : cache.below(threshold)) heap.emplace(cache.q()[t], t, m.version(t));
  std::size_t removed = 0;
  while (!heap.empty()) {
    const auto [q, t, ver] = heap.top();
    heap.pop();
    if (!m.alive(t) || m.version(t) != ver) continue;
    std::uint32_t nbr[4];
    for (int i = 0; i < 4; ++i) nbr[i] = m.adj(t, i);
    if (!remove_cap(m, t, ctx)) continue;
    ++removed;
    cache.refresh(t);
    for (std::uint32_t r : nbr)
      if (r != kImproveNone && cache.q()[r >> 2] < threshold)
        heap.emplace(cache.q()[r >> 2], r >> 2, m.version(r >> 2));
  }
  return removed;
}

struct SplitCounts {
  std::size_t interior = 0, boundary = 0, inserted = 0;
  /// Adds them to the stats; returns their sum (the stage's operations).
  std::size_t add_to(ImproveStats& st) const {
    st.splits += interior;
    st.boundary_splits += boundary;
    st.insertions += inserted;
    return interior + boundary + inserted;
  }
};

/// Splits tet t's longest boundary edge that split_boundary_edge accepts (longest first, ties
/// by position in t). Returns true if one was split.
bool split_a_boundary_edge(ImproveTets& m, std::uint32_t t, int max_ring, const BoundaryContext& ctx,
                           std::vector<std::uint32_t>& created) {
  for (const auto& [len2, e] : edges_longest_first(m, t)) {
    const std::uint32_t a = m.v(t)[kTetEdge[e][0]], b = m.v(t)[kTetEdge[e][1]];
    if (split_boundary_edge(m, t, a, b, max_ring, ctx, &created)) return true;
  }
  return false;
}

/// Splits every tet below `threshold` with three or four vertices on the surface (the
/// smoothing cannot move those apart; worst first, ties by id): an interior edge through a new
/// interior node (split_sliver); failing that, a boundary edge through a new surface node
/// (split_boundary_edge, when `boundary` is given); failing that, the tet and its neighbours
/// are replaced by a fan around a new interior node (insert_in_cavity). Returns the counts.
SplitCounts split_pass(ImproveTets& m, SineCache& cache, double threshold, int max_ring,
                       const BoundaryContext* boundary, bool insert, bool any_tet = false) {
  std::vector<std::pair<double, std::uint32_t>> bad;
  const NodeSet& nodes = m.nodes();
  for (std::uint32_t t : cache.below(threshold)) {
    const std::uint32_t* v = m.v(t);
    int on_surface = 0;
    for (int i = 0; i < 4; ++i) on_surface += nodes.kind[v[i]] != NodeKind::interior;
    if (on_surface >= 3 || any_tet) bad.push_back({cache.q()[t], t});
  }
  std::sort(bad.begin(), bad.end());
  SplitCounts n;
  std::vector<std::uint32_t> created;
  for (const auto& [q, t] : bad) {
    if (!m.alive(t) || !(cache.q()[t] < threshold)) continue;
    int on_surface = 0;
    for (int i = 0; i < 4; ++i) on_surface += nodes.kind[m.v(t)[i]] != NodeKind::interior;
    if (on_surface < 3) {  // (any_tet) vertices the smoothing could not move far enough
      if (!insert || !insert_in_cavity(m, t, &created)) continue;
      ++n.inserted;
    } else if (split_sliver(m, t, max_ring, nullptr, &created)) {
      ++n.interior;
    } else if (boundary && split_a_boundary_edge(m, t, max_ring, *boundary, created)) {
      ++n.boundary;
    } else if (insert && insert_in_cavity(m, t, &created)) {
      ++n.inserted;
    } else {
      continue;
    }
    for (std::uint32_t c : created) cache.refresh(c);
  }
  // The split rings' dead slots (the new tets are refreshed above; no node moved).
  if (n.interior + n.boundary + n.inserted) cache.refresh_dead();
  return n;
}

/// Fills st's below_target, worst_sine and below_target_at from the cache (the mesh's final state).
void record_below_target(const ImproveTets& m, const SineCache& cache, double target, ImproveStats& st) {
  std::vector<std::pair<double, std::uint32_t>> below;
  for (std::uint32_t t = 0; t < m.capacity(); ++t) {
    if (!m.alive(t)) continue;
    const double q = cache.q()[t];
    st.worst_sine = std::min(st.worst_sine, q);
    if (q < target) below.push_back({q, t});
  }
  st.below_target = below.size();
  std::sort(below.begin(), below.end());
  below.resize(std::min(below.size(), ImproveStats::kBelowTargetPlaces));
  for (const auto& [q, t] : below) {
    const std::uint32_t* v = m.v(t);
    for (int k = 0; k < 3; ++k)
      st.below_target_at.push_back((m.p(v[0])[k] + m.p(v[1])[k] + m.p(v[2])[k] + m.p(v[3])[k]) / 4);
  }
}

}  // namespace

ImproveStats improve_mesh(VolumeMesh& mesh, const Domain& domain, const ImproveOptions& options) {
  const PreparedSurface& surface = domain.surface;
  const SurfaceQuery& query = domain.query;
  const SizingField& sizing = domain.sizing;
  if (!(options.work_angle > 0 && options.work_angle < 90))
    throw UsageError("improve_mesh: work_angle must be in (0, 90) degrees");
  if (options.rounds < 0) throw UsageError("improve_mesh: rounds must be >= 0");
  if (options.max_ring < 3) throw UsageError("improve_mesh: max_ring must be >= 3");
  Stopwatch total, sw;
  ImproveStats st;
  const int total_stages = 1 + 2 * options.rounds + std::min(options.rounds, options.relax_rounds) +
                           (options.rounds > 0 && (options.cap_angle > 0 || options.split_angle > 0));
  ImproveTets m(mesh.nodes, mesh.tets, mesh.tet_region, &mesh.tet_adj);
  std::vector<std::uint32_t>().swap(mesh.tet_adj);  // taken into m; freed (16 bytes a tet)
  m.inside_query = &query;
  m.region_query = domain.regions;
  m.certify_inside();
  auto stage = [&](const std::string& name, std::size_t ops) {
    const double seconds = sw.seconds();
    ImproveStage s;
    if (options.measure_stages) s = measure(m, name);
    s.name = name;
    s.operations = ops;
    s.seconds = seconds;
    st.stages.push_back(s);
    if (options.progress)  // extra rounds (max_rounds) hold below 1 until the end
      options.progress("improve", std::min(double(st.stages.size()), double(total_stages - 1)) / double(total_stages));
    sw.reset();
  };
  stage("input", 0);  // its time: building the adjacency
  double diag = 0;
  for (int k = 0; k < 3; ++k)
    diag += (surface.bbox_max[k] - surface.bbox_min[k]) * (surface.bbox_max[k] - surface.bbox_min[k]);
  diag = std::sqrt(diag);
  const double threshold = deg_to_sine(options.work_angle);
  const double smooth_threshold = deg_to_sine(options.smooth_angle);
  FlipCounts c;
  SineCache cache(m, options.threads);
  BoundaryContext boundary;
  boundary.surface = &surface;
  boundary.query = &query;
  boundary.sizing = &sizing;
  boundary.max_distance = 0.8 * options.hausdorff_tolerance;
  FeatureEdges features;
  if (options.feature_angle > 0) {
    features = detect_sharp_edges(surface.mesh, options.feature_angle);
    boundary.features = &features;
  }
  SmoothContext ctx;
  if (options.smooth_surface) {
    ctx.surface = &surface;
    ctx.query = &query;
    if (options.slide_curved) ctx.boundary = &boundary;
    ctx.slide_features = options.slide_features;
  }
  ctx.on_surface = 1e-11 * diag;
  const BoundaryContext* flip_boundary = options.flip_boundary ? &boundary : nullptr;
  const BoundaryContext* split_boundary = options.split_boundary ? &boundary : nullptr;
  const double cap_threshold = options.cap_angle > 0 ? deg_to_sine(options.cap_angle) : -1;
  // Rounds beyond `rounds` continue while the tets below the target keep getting fewer: until
  // none is left, or three rounds in a row found no new low (the count is not monotone: the
  // handle at diag/20 went 62, 39, 28, 33, 28, 23, 22, 19, 20, 20, 15, 9, 0 over rounds 4-16).
  const double target = deg_to_sine(options.target_angle);
  std::size_t fewest = std::numeric_limits<std::size_t>::max();
  int stalled = 0;
  const int max_rounds = options.rounds > 0 ? std::max(options.rounds, options.max_rounds) : 0;
  for (int r = 0; r < max_rounds; ++r) {
    if (r >= options.rounds) {
      std::size_t below = 0;
      for (double q : cache.q()) below += q < target;
      if (below == 0) break;
      if (below < fewest) {
        fewest = below;
        stalled = 0;
      } else if (++stalled == 3) {
        break;
      }
    }
    const std::string n = std::to_string(r + 1);
    st.rounds = r + 1;
    std::size_t ops = flip_pass(m, cache, threshold, options.max_ring, c, flip_boundary, options.threads);
    if (cap_threshold > 0) {
      const std::size_t removed = cap_pass(m, cache, cap_threshold, boundary);
      st.caps_removed += removed;
      if (removed) ops += removed + flip_pass(m, cache, threshold, options.max_ring, c, flip_boundary, options.threads);
    }
    if (options.split_angle > 0) {
      ops += split_pass(m, cache, deg_to_sine(options.split_angle), options.max_ring, split_boundary,
                        options.insert_nodes).add_to(st);
    }
    stage("flip " + n, ops);
    if (r < options.relax_rounds) {
      const std::vector<std::uint32_t> relaxed =
          relax_pass(m, cache, options.relax_below, threshold, ctx, options.threads);
      st.relaxed += relaxed.size();
      stage("relax " + n, relaxed.size());
    }
    const std::vector<std::uint32_t> moved =
        smooth_pass(m, cache, smooth_threshold, ctx, options.threads);
    cache.refresh_stars(moved);
    st.smoothed += moved.size();
    for (std::uint32_t v : moved) st.feature_slides += m.nodes().kind[v] == NodeKind::edge;
    stage("smooth " + n, moved.size());
  }
  // The last smoothing can leave a cap or a sliver that an earlier pass would have taken
  // (a base vertex moved in a star whose worst tet was worse): one more flip, cap and split
  // pass, without moves (a sphere of 1,280 facets kept a 1.3 deg cap this way).
  if (options.rounds > 0 && (cap_threshold > 0 || options.split_angle > 0)) {
    std::size_t ops = 0;
    if (cap_threshold > 0) {
      const std::size_t removed = cap_pass(m, cache, cap_threshold, boundary);
      st.caps_removed += removed;
      ops += removed;
    }
    if (options.split_angle > 0) {
      ops += split_pass(m, cache, deg_to_sine(options.split_angle), options.max_ring, split_boundary,
                        options.insert_nodes, /*any_tet=*/true).add_to(st);
    }
    if (ops) ops += flip_pass(m, cache, threshold, options.max_ring, c, flip_boundary, options.threads);
    stage("final", ops);
  }
  if (options.progress) options.progress("improve", 1.0);
  record_below_target(m, cache, deg_to_sine(options.target_angle), st);
  st.edge_removals = c.edge_removals;
  st.face_removals = c.face_removals;
  st.boundary_flips = c.boundary_flips;
  st.boundary_changes = m.write_back(mesh);
  st.seconds = total.seconds();
  return st;
}

}  // namespace kdmesh
