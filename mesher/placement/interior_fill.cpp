// kdmesh — adaptive BCC lattice fill of the solid.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/placement/interior_fill.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "core/parallel_for.h"
#include "mesher/worker_team.h"

namespace kdmesh {

namespace {

struct Candidate {
  double p[3];
  double h;
  double dlb;  // a lower bound of the distance to the surface
  int level;
};

/// The lattice's axes when InteriorFillOptions::rotate_lattice: the columns of kLatticeAxes / 7,
/// an orthogonal matrix of integers over 7 (the rotation of the quaternion (1, -5, -1, -1)):
/// of all quaternions with entries up to 6, one whose 13 low-index directions keep the largest
/// least angle (4.73 deg) from the coordinate planes. Integer entries keep the lattice exact
/// (Filler::lattice_points): with a rotation in floating point, points of one lattice plane
/// were coplanar only up to rounding, the Delaunay kernel made tets of their near-degenerate
/// configurations that the recovery found flat (the gear box dropped 7,610 nodes instead of
/// 98, in 4 rounds), and couplingdown.ply at diag/80 lost its boundary altogether.
constexpr std::int64_t kLatticeAxes[3][3] = {{6, 3, 2}, {2, -6, 3}, {3, -2, -6}};
constexpr std::int64_t kAxisAligned[3][3] = {{7, 0, 0}, {0, 7, 0}, {0, 0, 7}};

struct Filler {
  const SurfaceQuery& query;
  const SizingField& sizing;
  const InteriorFillOptions& opt;
  double hmax, hmin, lip;  // sizing bounds and Lipschitz constant used for block bounds
  double log_rho;
  int max_level;

  double spacing(int k) const { return opt.kappa * hmax * std::pow(opt.rho, -double(k)); }
  int level_of(double h) const {
    const int k = int(std::lround(std::log(hmax / h) / log_rho));
    return std::clamp(k, 0, max_level);
  }

  struct Local {
    std::vector<Candidate> out;
    InteriorFillStats stats;
  };

  /// A surface-free ball known from an enclosing block: centre, radius (a lower bound of the
  /// centre's surface distance) and the side of its points (+1 / -1; 0 = none known).
  struct Ball {
    double c[3] = {0, 0, 0};
    double r = 0;
    int side = 0;
  };

  void block(const double* lo, const double* hi, const Ball& parent, Local& L) const {
    double c[3], half = 0;
    for (int a = 0; a < 3; ++a) {
      c[a] = (lo[a] + hi[a]) / 2;
      half += (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    const double R = std::sqrt(half) / 2;
    const double S = hi[0] - lo[0];
    const double hc = sizing(c);
    const double h_lo = std::max(hmin, hc - lip * R), h_hi = std::min(hmax, hc + lip * R);
    const int k_lo = level_of(h_hi), k_hi = level_of(h_lo);
    const double far_margin = R + opt.clearance * h_hi;
    // Distance of the centre: a lower bound from the enclosing ball when it settles the block
    // (1e-9 relative margins cover rounding), else one AABB query.
    constexpr double kSafe = 1 - 1e-9;
    double dc = 0;
    int side_c = 2;  // 2 = not yet known
    if (parent.side != 0) {
      const double off = std::hypot(c[0] - parent.c[0], c[1] - parent.c[1], c[2] - parent.c[2]);
      const double lb = (parent.r - off) * kSafe;
      if (lb > R && (parent.side < 0 || lb > far_margin)) {
        if (parent.side < 0) return;  // the block lies in a surface-free ball outside
        dc = lb;
        side_c = 1;
      }
    }
    if (side_c == 2) {
      dc = query.distance(c);
      ++L.stats.distance_queries;
      if (dc > R) {  // the block misses the surface: it is all on one side
        // The parent's centre's side, carried along a segment meeting no facet (exact), else
        // the inside test.
        if (parent.side != 0 && query.segment_clear(parent.c, c)) {
          side_c = parent.side;
        } else {
          side_c = query.side(c);
          ++L.stats.side_queries;
        }
        if (side_c < 0) return;
      }
    }
    const bool far = dc > far_margin && side_c > 0;
    // Split near the surface down to ~2 coarse cells (so that most nodes there skip the
    // per-node queries), and where the size range spans >= 2 levels (so that the finest
    // level is not enumerated over a block mostly needing coarser ones).
    const bool split =
        (k_hi - k_lo >= 2 && S > 2 * spacing(k_hi)) || (!far && S > 2 * spacing(k_lo));
    if (split) {
      Ball mine;
      if (side_c == 1 || side_c == -1) mine = Ball{{c[0], c[1], c[2]}, dc, side_c};
      double mid[3] = {c[0], c[1], c[2]};
      for (int o = 0; o < 8; ++o) {
        double l2[3], h2[3];
        for (int a = 0; a < 3; ++a) {
          const bool up = o >> a & 1;
          l2[a] = up ? mid[a] : lo[a];
          h2[a] = up ? hi[a] : mid[a];
        }
        block(l2, h2, mine, L);
      }
      return;
    }
    ++L.stats.blocks;
    if (!far && side_c == 2) {
      if (parent.side != 0 && query.segment_clear(parent.c, c)) {
        side_c = parent.side;  // carried (exact)
      } else {
        side_c = query.side(c);
        ++L.stats.side_queries;
      }
    }
    for (int k = k_lo; k <= k_hi; ++k) lattice_points(k, lo, hi, c, hc, dc, side_c, far, L);
  }

  /// The level-k lattice points in the block [lo, hi) (each point in exactly one block).
  /// A point is p = q M U: U an integer vector whose entries are all even (one cubic
  /// sublattice of the BCC lattice) or all odd (the other), M the integer axes (kLatticeAxes,
  /// 7 x an orthogonal matrix), q = a / 14 rounded to 16 significant bits. M U is an exact
  /// integer and q M U is exact while |M U| < 2^37 (a part 10^10 lattice cells from the
  /// origin of coordinates), so every point sits exactly on the lattice
  /// and the lattice's own coplanar and cospherical sets stay exactly so (the Delaunay
  /// kernel's symbolic perturbation then decides them consistently). The lattice is anchored
  /// at the origin of coordinates, not at the part.
  void lattice_points(int k, const double* lo, const double* hi, const double* c, double hc, double dc,
                      int side_c, bool far, Local& L) const {
    const double a = spacing(k);
    // The sizes of level k (level_of(h) = k), widened for the rounding of the logarithm: h
    // above h_above has a lower level, h below h_below a higher one (but for the clamped end
    // levels). A point whose h is known to be beyond them (h is lip-Lipschitz, h(c) = hc) is
    // not evaluated: on the paper gear box 76 % of the points in their blocks had another
    // level, each costing a field evaluation.
    const double top = hmax * std::pow(opt.rho, 0.5 - k), bottom = hmax * std::pow(opt.rho, -0.5 - k);
    const double h_above = k > 0 ? top * (1 + 1e-9) : INFINITY;
    const double h_below = k < max_level ? bottom * (1 - 1e-9) : 0.0;
    // Sizes certainly of level k, narrowed by the same margin (the logarithm's rounding is
    // ~1e-14 of a level, the margin ~1e-9): most points need no logarithm (22.8M on the gear box).
    const double in_hi = k > 0 ? top * (1 - 1e-9) : INFINITY;
    const double in_lo = k < max_level ? bottom * (1 + 1e-9) : 0.0;
    const std::int64_t(&M)[3][3] = opt.rotate_lattice ? kLatticeAxes : kAxisAligned;
    int e = 0;
    const double mantissa = std::frexp(a / 14, &e);  // (sets e before it is read below)
    const double q = std::ldexp(std::nearbyint(std::ldexp(mantissa, 16)), e - 16);
    // Bounds of U = M^T p / (49 q) over the block's corners.
    double wlo[3] = {INFINITY, INFINITY, INFINITY}, whi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int o = 0; o < 8; ++o) {
      const double x[3] = {o & 1 ? hi[0] : lo[0], o & 2 ? hi[1] : lo[1], o & 4 ? hi[2] : lo[2]};
      for (int ax = 0; ax < 3; ++ax) {
        const double w = (double(M[0][ax]) * x[0] + double(M[1][ax]) * x[1] + double(M[2][ax]) * x[2]) / (49 * q);
        wlo[ax] = std::min(wlo[ax], w);
        whi[ax] = std::max(whi[ax], w);
      }
    }
    for (int sub = 0; sub < 2; ++sub) {  // U = 2 (i, j, m) + sub
      std::int64_t i0[3], i1[3];
      // The integers i with 2 i + sub in [wlo, whi], the box of U over the block's corners,
      // widened for the rounding of w (|w| < 2^37, so its error is below 2^-15; the margin is
      // far above it and far below a lattice step). The exact test below decides each point.
      // A margin of a whole step on each side made the box of a small block several times its
      // points (2.9 billion tries for 23M points in the block on the paper gear box); rounding
      // the ends outwards (floor, ceil) still gave 792M tries (212M lines of m) for those 23M
      // points, as most blocks are small against their coarser levels' steps; rounded
      // inwards, 88M tries (45M lines), the same points.
      for (int ax = 0; ax < 3; ++ax) {
        const double margin = 1e-9 * (1 + std::max(std::fabs(wlo[ax]), std::fabs(whi[ax])));
        i0[ax] = std::int64_t(std::ceil((wlo[ax] - sub) / 2 - margin));
        i1[ax] = std::int64_t(std::floor((whi[ax] - sub) / 2 + margin));
      }
      for (std::int64_t i = i0[0]; i <= i1[0]; ++i)
        for (std::int64_t j = i0[1]; j <= i1[1]; ++j)
          for (std::int64_t m = i0[2]; m <= i1[2]; ++m) {
            const std::int64_t U[3] = {2 * i + sub, 2 * j + sub, 2 * m + sub};
            Candidate cand{{0, 0, 0}, 0, 0, k};
            bool in = true;
            for (int ax = 0; ax < 3 && in; ++ax) {
              cand.p[ax] = q * double(M[ax][0] * U[0] + M[ax][1] * U[1] + M[ax][2] * U[2]);
              in = cand.p[ax] >= lo[ax] && cand.p[ax] < hi[ax];
            }
            if (!in) continue;
            const double dx = cand.p[0] - c[0], dy = cand.p[1] - c[1], dz = cand.p[2] - c[2];
            const double reach = lip * std::sqrt(dx * dx + dy * dy + dz * dz);
            if (opt.bound_levels && (hc + reach < h_below || hc - reach > h_above)) continue;
            cand.h = sizing(cand.p);
            if (!(cand.h > in_lo && cand.h < in_hi) && level_of(cand.h) != k) continue;
            if (far)
              cand.dlb = dc - std::hypot(cand.p[0] - c[0], cand.p[1] - c[1], cand.p[2] - c[2]);
            else if (!accept_near(cand, c, dc, side_c, L.stats))
              continue;
            L.out.push_back(cand);
          }
    }
  }

  /// Strictly inside and clear of the surface, for a candidate of a block near the surface
  /// whose centre c has surface distance dc and side side_c.
  bool accept_near(Candidate& cand, const double* c, double dc, int side_c,
                   InteriorFillStats& st) const {
    const double need = opt.clearance * cand.h;
    const double dx = cand.p[0] - c[0], dy = cand.p[1] - c[1], dz = cand.p[2] - c[2];
    const double pc = std::sqrt(dx * dx + dy * dy + dz * dz);
    // The open ball B(c, dc) holds no surface point. Margins of 1e-9 relative cover the
    // rounding of the computed distances (they only send borderline cases to exact queries).
    constexpr double kSafe = 1 - 1e-9;
    cand.dlb = dc - pc;
    if (side_c != 0 && (pc + need) < dc * kSafe) return side_c > 0;
    const double dp = query.distance(cand.p);
    cand.dlb = dp;
    ++st.distance_queries;
    if (!(dp >= need) || !(dp > 0)) return false;
    // B(p, dp) and B(c, dc) are surface-free; if they overlap, p and c are on one side.
    if (side_c != 0 && pc < (dp + dc) * kSafe) return side_c > 0;
    if (side_c != 0 && query.segment_clear(c, cand.p)) return side_c > 0;  // carried (exact)
    ++st.side_queries;
    return query.side(cand.p) > 0;
  }
};

/// One surface node's frame for its boundary-layer tries: position, outward unit normal of its
/// facet, two unit tangents, size, and how many sides it proposes points on.
struct LayerFrame {
  double s[3], n[3], e1[3], e2[3];
  double hs;
  int sides;
};

/// One boundary-layer try: its node's frame, its number k (k >= layer_tries: the other side),
/// its three draws (depth fraction, angle, radius fraction), then what the parallel phase found.
struct LayerTry {
  std::uint32_t frame;
  int k;
  double depth_u, angle, radius_u;
  double p[3], h;
  bool clash;  // conflicts with a node in the grid as it stood before the batch
};

/// One batch of boundary-layer tries: the frames of its surface nodes and its tries.
struct LayerBatch {
  std::vector<LayerFrame> frames;
  std::vector<LayerTry> tries;
};

/// Draws the next batch's tries (up to 2^14) from the surface nodes from *i on, in id order,
/// three draws each from rng; advances *i.
void draw_layer_batch(const SurfaceMesh& surface, const NodeSet& nodes, const InteriorFillOptions& options,
                      std::size_t surface_nodes, std::size_t& i, Rng& rng, LayerBatch& out) {
  constexpr std::size_t kBatchTries = std::size_t(1) << 14;  // (two batches live at once)
  out.frames.clear();
  out.tries.clear();
  for (; i < surface_nodes && out.tries.size() < kBatchTries; ++i) {
    if (nodes.kind[i] == NodeKind::interior || nodes.facet[i] >= surface.num_tris()) continue;
    const std::uint32_t* t = surface.tri(nodes.facet[i]);
    const double* a = surface.points.p(t[0]);
    const double* b = surface.points.p(t[1]);
    const double* c = surface.points.p(t[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    LayerFrame f;
    double* n = f.n;
    n[0] = u[1] * v[2] - u[2] * v[1], n[1] = u[2] * v[0] - u[0] * v[2], n[2] = u[0] * v[1] - u[1] * v[0];
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0)) continue;
    for (int ax = 0; ax < 3; ++ax) n[ax] /= nl;  // outward unit normal
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int ax = 0; ax < 3; ++ax) f.e1[ax] = u[ax] / ul;
    f.e2[0] = n[1] * f.e1[2] - n[2] * f.e1[1];
    f.e2[1] = n[2] * f.e1[0] - n[0] * f.e1[2];
    f.e2[2] = n[0] * f.e1[1] - n[1] * f.e1[0];
    for (int ax = 0; ax < 3; ++ax) f.s[ax] = nodes.points.p(std::uint32_t(i))[ax];
    f.hs = nodes.size[i];
    f.sides = nodes.facet[i] >= options.two_sided_from ? 2 : 1;
    out.frames.push_back(f);
    for (int k = 0; k < f.sides * options.layer_tries; ++k) {
      LayerTry& tr = out.tries.emplace_back();
      tr.frame = std::uint32_t(out.frames.size() - 1);
      tr.k = k;
      tr.depth_u = rng.uniform();  // the three draws, in this order
      tr.angle = rng.uniform(0, 6.283185307179586);
      tr.radius_u = rng.uniform();
    }
  }
}

/// A try of batch `in`: its point, and its size and clash with `grid` (read only).
void test_layer_try(const LayerBatch& in, const SpacingGrid& grid, const SizingField& sizing,
                    const InteriorFillOptions& options, LayerTry& tr) {
  const LayerFrame& f = in.frames[tr.frame];
  double n[3] = {f.n[0], f.n[1], f.n[2]};
  if (tr.k >= options.layer_tries)
    for (double& x : n) x = -x;  // the other side of an interface
  const double depth = f.hs * (options.clearance + options.layer_depth * tr.depth_u);
  const double rad = f.hs * 0.6 * std::sqrt(tr.radius_u);
  const double dx = rad * std::cos(tr.angle), dy = rad * std::sin(tr.angle);
  for (int ax = 0; ax < 3; ++ax) tr.p[ax] = f.s[ax] - depth * n[ax] + dx * f.e1[ax] + dy * f.e2[ax];
  // Most tries clash (17.2M of 18.1M on the paper gear box). A clash with a size below
  // h(p) is a clash with h(p) (the spacing only grows with h), and h(p) >= h(s) - g |p - s|
  // for the surface node s (its size a float: the margins cover that and the rounding).
  // So a clash found with that bound needs no field evaluation; otherwise the try is
  // decided as before. (A clash is all that is kept of a clashing try.)
  const double g = sizing.options().gradation;
  const double h_lo = f.hs * (1 - 1e-6) - g * std::sqrt(depth * depth + rad * rad) * (1 + 1e-6);
  if (h_lo > 0 && grid.conflicts(tr.p, h_lo, options.beta)) {
    tr.clash = true;
    return;
  }
  tr.h = sizing(tr.p);
  tr.clash = grid.conflicts(tr.p, tr.h, options.beta);
}

/// Boundary layer (InteriorFillOptions::layer_tries): the tries of the surface nodes in id
/// order, each kept if it conflicts with no node, lies at least clearance * h from the surface
/// and inside. One RNG stream, drawn in that order: deterministic. The tries go in batches:
/// the draws are made in order; every try of a batch gets its size and its conflict test
/// against the grid as it stood before the batch before, on the threads (those of batch k + 1
/// while batch k is decided); then the tries are decided in order, testing each one only
/// against the nodes the two batches have accepted before it (a conflict with a set is a
/// conflict with one of its parts), and the tries left get their distance and side. The
/// nodes, the grid and the stats come out as if each try had been decided when it was drawn.
/// (The decisions took about 3 ms of each 11 ms batch of the paper gear box, with one core
/// idle.)
void add_boundary_layer(const SurfaceMesh& surface, const SurfaceQuery& query,
                        const SizingField& sizing, const InteriorFillOptions& options,
                        std::size_t surface_nodes, SpacingGrid& grid, NodeSet& nodes,
                        InteriorFillStats& st) {
  if (options.layer_tries <= 0) return;
  Rng rng(options.seed ^ 0x6c8e9cf570932bd5ULL);
  const unsigned nthreads = std::max(1u, options.threads);
  WorkerTeam team(nthreads);
  // A batch's tests in blocks of tries, each block taken by whichever thread is free.
  auto test_blocks = [&](LayerBatch& in, std::atomic<std::size_t>& claim) {
    constexpr std::size_t kBlock = 1024;
    const std::size_t blocks = (in.tries.size() + kBlock - 1) / kBlock;
    for (std::size_t k; (k = claim.fetch_add(1)) < blocks;)
      for (std::size_t j = k * kBlock; j < std::min(in.tries.size(), (k + 1) * kBlock); ++j)
        test_layer_try(in, grid, sizing, options, in.tries[j]);
  };
  LayerBatch cur, next;
  std::size_t i = 0;
  draw_layer_batch(surface, nodes, options, surface_nodes, i, rng, cur);
  std::atomic<std::size_t> first_claim{0};
  team.run([&](unsigned) { test_blocks(cur, first_claim); });
  std::vector<std::array<double, 4>> before;  // accepted in the batch before: (p, h)
  while (!cur.tries.empty()) {
    draw_layer_batch(surface, nodes, options, surface_nodes, i, rng, next);
    // Batch k + 1's tests (against the grid without batch k's nodes) on the other threads
    // while this one decides batch k, then on all.
    std::atomic<std::size_t> claim{0};
    SpacingGrid batch(grid.lo(), grid.s0());
    batch.set_lipschitz(sizing.options().gradation);
    for (const auto& q : before) batch.insert(q.data(), q[3]);
    std::vector<std::array<double, 4>> accepted;
    team.run([&](unsigned w) {
      if (w > 0) return test_blocks(next, claim);
      for (const LayerTry& tr : cur.tries) {
        if (tr.clash || batch.conflicts(tr.p, tr.h, options.beta)) continue;
        // Distance and side here, for the tries left: speculated for every try without a
        // clash, they made the 1M-facet torus scan of test_large_scan 2.7x slower (most of its
        // layer tries clash only with nodes their own batch keeps).
        const double d = query.distance(tr.p);
        ++st.distance_queries;
        if (!(d >= options.clearance * tr.h) || !(d > 0)) continue;
        ++st.side_queries;
        if (query.side(tr.p) <= 0) continue;
        batch.insert(tr.p, tr.h);
        nodes.push_back(tr.p, NodeKind::interior, kNoFacet, float(tr.h));
        accepted.push_back({tr.p[0], tr.p[1], tr.p[2], tr.h});
      }
      test_blocks(next, claim);
    });
    st.layer_nodes += accepted.size();
    for (const auto& q : accepted) grid.insert(q.data(), q[3]);
    before.swap(accepted);
    std::swap(cur, next);
  }
}
}  // namespace

struct InteriorLattice::Impl {
  InteriorFillOptions options;
  const SurfaceQuery& query;
  const SizingField& sizing;
  Filler F;
  double lo[3];  // the box's low corner: the root blocks' origin
  std::int64_t nb[3];
  std::size_t nroots = 0;
  std::vector<Filler::Local> locals;
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex error_mutex;
  std::exception_ptr error;

  Impl(const double* l, const SurfaceQuery& q, const SizingField& s, const InteriorFillOptions& o)
      : options(o), query(q), sizing(s),
        F{q, s, options, s.max_size(), s.min_size(), 0, std::log(o.rho), 0} {
    std::copy_n(l, 3, lo);
  }
};

InteriorLattice::InteriorLattice(const double* lo, const double* hi, const SurfaceQuery& query,
                                 const SizingField& sizing, const InteriorFillOptions& options)
    : impl_(std::make_unique<Impl>(lo, query, sizing, options)) {
  if (!(options.kappa > 0) || !(options.rho > 1) || !(options.beta > 0) ||
      !(options.clearance >= 0))
    throw UsageError("interior fill: kappa, beta must be > 0, rho > 1, clearance >= 0");
  Filler& F = impl_->F;
  // Same-level lattice nodes must never conflict (the acceptance below relies on it).
  if (!(options.beta * std::sqrt(options.rho) < 0.8660254037844386 * options.kappa))
    throw UsageError("interior fill: beta must be < sqrt(3)/2 * kappa / sqrt(rho)");
  if (!(F.hmax > 0)) throw UsageError("interior fill: the sizing field has no positive max_size");
  if (!(F.hmin > 0) || F.hmin > F.hmax) F.hmin = F.hmax;
  // h is g-Lipschitz for zone gradation g (sizing/sizing_field.h). A field that varies
  // faster (a curvature bound) only makes some nodes take a neighbouring level.
  F.lip = 1.05 * std::max(0.0, sizing.options().gradation);
  F.max_level = int(std::lround(std::log(F.hmax / F.hmin) / F.log_rho)) + 1;
  // Root blocks: cubes of 8 coarse cells covering the box.
  const double B = 8 * F.spacing(0);
  for (int a = 0; a < 3; ++a)
    impl_->nb[a] = std::max<std::int64_t>(1, std::int64_t(std::ceil((hi[a] - lo[a]) / B)));
  impl_->nroots = std::size_t(impl_->nb[0] * impl_->nb[1] * impl_->nb[2]);
  impl_->locals.resize(impl_->nroots);
}

InteriorLattice::~InteriorLattice() = default;

void InteriorLattice::work() {
  Impl& I = *impl_;
  const double B = 8 * I.F.spacing(0);
  try {
    for (;;) {
      const std::size_t r = I.next.fetch_add(1);
      if (r >= I.nroots) return;
      const std::int64_t ix = std::int64_t(r % std::size_t(I.nb[0]));
      const std::int64_t iy = std::int64_t((r / std::size_t(I.nb[0])) % std::size_t(I.nb[1]));
      const std::int64_t iz = std::int64_t(r / std::size_t(I.nb[0] * I.nb[1]));
      const double l[3] = {I.lo[0] + double(ix) * B, I.lo[1] + double(iy) * B, I.lo[2] + double(iz) * B};
      const double h[3] = {I.lo[0] + double(ix + 1) * B, I.lo[1] + double(iy + 1) * B,
                           I.lo[2] + double(iz + 1) * B};
      I.F.block(l, h, Filler::Ball{}, I.locals[r]);
      I.done.fetch_add(1);
    }
  } catch (...) {
    const std::lock_guard<std::mutex> lock(I.error_mutex);
    if (!I.error) I.error = std::current_exception();
    stop();
  }
}

void InteriorLattice::stop() { impl_->next.store(impl_->nroots); }

void InteriorLattice::work_on(unsigned threads) {
  // work() takes blocks until none is left (and never throws), so a worker whose thread could
  // not be started and runs after the others (run_workers) finds nothing left to do.
  run_workers(threads, [this](unsigned) { work(); });
}

InteriorFillStats InteriorLattice::finish(const SurfaceMesh& surface, SpacingGrid& grid, NodeSet& nodes,
                                          const std::function<void(double)>& progress) {
  Impl& I = *impl_;
  if (I.error) std::rethrow_exception(I.error);
  if (I.done.load() != I.nroots)
    throw UsageError("interior fill: finish() before work() generated every block (" +
                     std::to_string(I.done.load()) + " of " + std::to_string(I.nroots) + ")");
  const InteriorFillOptions& options = I.options;
  const Filler& F = I.F;
  const unsigned nthreads = std::max(1u, options.threads);
  // Concatenate in root-block order, then finest level first (stable): deterministic.
  InteriorFillStats st;
  std::size_t total = 0;
  int levels = 0;
  for (const auto& L : I.locals) {
    total += L.out.size();
    st.distance_queries += L.stats.distance_queries;
    st.side_queries += L.stats.side_queries;
    st.blocks += L.stats.blocks;
    for (const Candidate& c : L.out) levels = std::max(levels, c.level + 1);
  }
  st.candidates = total;
  std::vector<std::vector<const Candidate*>> by_level(static_cast<std::size_t>(levels));
  for (const auto& L : I.locals)
    for (const Candidate& c : L.out) by_level[std::size_t(c.level)].push_back(&c);
  nodes.points.xyz.reserve(nodes.points.xyz.size() + 3 * total);
  nodes.kind.reserve(nodes.kind.size() + total);
  nodes.facet.reserve(nodes.facet.size() + total);
  nodes.size.reserve(nodes.size.size() + total);
  std::size_t seen = 0;
  const std::size_t surface_nodes = nodes.size_count();
  // Two lattice nodes of one level never conflict: they are >= a sqrt(3)/2 apart, and
  // beta (h_p + h_q) / 2 <= beta rho^1/2 a / kappa < a sqrt(3)/2 (InteriorFillOptions::beta).
  // So each candidate is tested against the surface nodes (`grid` so far) only when it may
  // be within reach of one (reach <= beta (h + h_max) / 2), and against the nodes of the
  // (finer) levels accepted before (`others`) only if there are any. The
  // result equals testing everything against one grid, at a fraction of the cost.
  SpacingGrid others(grid.lo(), grid.s0());
  others.set_lipschitz(I.sizing.options().gradation);
  // Room for every candidate, and in `grid` for the boundary layer too (at most one node a
  // surface node here; the paper gear box: 3.56M of 4.32M candidates kept, 124k layer nodes for
  // 539k surface nodes). Growing by doubling copied the 40-byte records into fresh pages,
  // 450 MB on the gear box, with the other core idle. Unused room is never touched.
  others.reserve(total);
  grid.reserve(grid.size() + total + surface_nodes);
  // Within a level the tests are independent (both grids are only read), so they run on
  // `threads` threads; the accepted candidates keep their order.
  std::vector<const Candidate*> accepted;
  for (int k = levels - 1; k >= 0; --k) {
    const std::size_t first = accepted.size();
    const std::vector<const Candidate*>& level = by_level[std::size_t(k)];
    std::vector<std::uint8_t> ok(level.size());
    parallel_for(level.size(), [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t i = b; i < e; ++i) {
        const Candidate* c = level[i];
        const double reach = options.beta * (c->h + F.hmax) / 2;
        ok[i] = !(!(c->dlb * (1 - 1e-9) > reach) && grid.conflicts(c->p, c->h, options.beta)) &&
                !(others.size() && others.conflicts(c->p, c->h, options.beta));
      }
    }, 1024, nthreads);
    for (std::size_t i = 0; i < level.size(); ++i)
      if (ok[i]) accepted.push_back(level[i]);
    seen += level.size();
    if (progress) progress(0.5 + 0.4 * double(seen) / double(std::max<std::size_t>(total, 1)));
    for (std::size_t i = first; i < accepted.size(); ++i) others.insert(accepted[i]->p, accepted[i]->h);
  }
  for (const Candidate* c : accepted) {
    grid.insert(c->p, c->h);
    nodes.push_back(c->p, NodeKind::interior, kNoFacet, float(c->h));
  }
  st.lattice_nodes = accepted.size();
  if (progress) progress(0.9);

  add_boundary_layer(surface, I.query, I.sizing, options, surface_nodes, grid, nodes, st);
  if (progress) progress(1.0);
  return st;
}

InteriorFillStats fill_interior(const SurfaceMesh& surface, const double* lo, const double* hi,
                                const SurfaceQuery& query,
                                const SizingField& sizing, const InteriorFillOptions& options,
                                SpacingGrid& grid, NodeSet& nodes,
                                const std::function<void(double)>& progress) {
  InteriorLattice lattice(lo, hi, query, sizing, options);
  if (progress) progress(0.0);
  lattice.work_on(std::max(1u, options.threads));
  if (progress) progress(0.5);
  return lattice.finish(surface, grid, nodes, progress);
}

}  // namespace kdmesh
