// kdmesh — vertex smoothing of the quality-improvement pass (mesher/improve/improve_smooth.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/improve_smooth.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "mesher/improve/improve_quality.h"

namespace kdmesh {

namespace {

double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

struct StarTet {
  const double* p[4];
  std::uint32_t ids[4];
  int iv;  // position of the moving vertex
};

/// Min-norm point of the convex hull of `g` (Gilbert's algorithm; a few dozen steps suffice
/// for a direction).
std::array<double, 3> min_norm_point(const std::vector<std::array<double, 3>>& g) {
  std::array<double, 3> d = g[0];
  for (int it = 0; it < 40; ++it) {
    const double dd = dot3(d.data(), d.data());
    std::size_t jmin = 0;
    double smin = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < g.size(); ++j) {
      const double s = dot3(g[j].data(), d.data());
      if (s < smin) smin = s, jmin = j;
    }
    if (smin >= dd * (1 - 1e-9)) break;
    const double e[3] = {g[jmin][0] - d[0], g[jmin][1] - d[1], g[jmin][2] - d[2]};
    const double ee = dot3(e, e);
    if (ee <= 0) break;
    const double lam = std::clamp(-dot3(d.data(), e) / ee, 0.0, 1.0);
    for (int k = 0; k < 3; ++k) d[k] += lam * e[k];
  }
  return d;
}

/// The star of one vertex with what a move must respect.
class VertexStar {
 public:
  /// False if v may not move (a feature node, a surface node off a planar fan unless
  /// `curved` and ctx.boundary, ...). `star`, if given, is v's star (not walked again).
  bool load(const ImproveTets& m, std::uint32_t v, const SmoothContext& ctx, bool curved,
            const KnownStar* star) {
    m_ = &m;
    v_ = v;
    ctx_ = &ctx;
    curved_ = false;
    if (m.locked(v)) return false;  // on an interface between regions
    const NodeKind kind = m.nodes().kind[v];
    on_surface_ = kind != NodeKind::interior;
    feature_ = kind == NodeKind::edge;
    if (feature_ && !(curved && ctx.slide_features && ctx.boundary && ctx.boundary->features))
      return false;
    if (on_surface_ && (kind == NodeKind::corner || !ctx.surface || !ctx.query)) return false;
    if (star) {  // every tet's lines requested at once, where the walk finds them one by one
      star_.assign(star->tets, star->tets + star->size);
      for (std::uint32_t t : star_) m.prefetch_tet(t);
    } else {
      m.star(v, star_);
    }
    if (star_.empty()) return false;
    for (std::uint32_t t : star_)  // (the positions are read below and in every evaluation)
      for (int k = 0; k < 4; ++k) __builtin_prefetch(m.p(m.v(t)[k]));
    st_.clear();
    bfaces_.clear();
    bnormal_.clear();
    link_.clear();
    for (std::uint32_t t : star_) {
      const std::uint32_t* tv = m.v(t);
      StarTet s;
      for (int k = 0; k < 4; ++k) s.p[k] = m.p(tv[k]), s.ids[k] = tv[k];
      s.iv = index_in(tv, v);
      st_.push_back(s);
      for (int k = 0; k < 4; ++k) {
        if (k == s.iv) continue;
        add_link(tv[k]);
        if (m.adj(t, k) == kImproveNone) {  // a boundary face holding v
          bfaces_.push_back({tv[kTetFace[k][0]], tv[kTetFace[k][1]], tv[kTetFace[k][2]]});
          std::array<double, 3> n;
          tri_normal(m.p(bfaces_.back()[0]), m.p(bfaces_.back()[1]), m.p(bfaces_.back()[2]), n.data());
          bnormal_.push_back(n);
        }
      }
    }
    finish_link();
    if (!on_surface_) return bfaces_.empty();
    if (bfaces_.empty()) return false;
    facet_ = m.nodes().facet[v];
    const SurfaceMesh& sm = ctx.surface->mesh;
    if (facet_ == kNoFacet || facet_ >= sm.num_tris()) return false;
    for (int j = 0; j < 3; ++j) fp_[j] = sm.points.p(sm.tris[3 * std::size_t(facet_) + j]);
    tri_normal(fp_[0], fp_[1], fp_[2], n_);
    const double nl = std::sqrt(dot3(n_, n_));
    if (!(nl > 0)) return false;
    for (double& c : n_) c /= nl;
    std::copy_n(n_, 3, tn_);
    if (feature_) return load_curve(m);
    // Planar: every boundary face at v lies in the facet's plane.
    for (const auto& bf : bfaces_)
      for (std::uint32_t w : bf)
        if (std::fabs(plane_offset(m.p(w))) > ctx.on_surface) curved_ = true;
    if (!curved_) return true;
    if (!curved || !ctx.boundary) return false;
    // Curved: v moves in the fan's tangent plane (normal: the sum of the faces' area normals)
    // and back onto the surface.
    std::fill_n(tn_, 3, 0.0);
    for (const auto& bn : bnormal_)
      for (int k = 0; k < 3; ++k) tn_[k] += bn[k];
    const double tl = std::sqrt(dot3(tn_, tn_));
    if (!(tl > 0)) return false;
    for (double& c : tn_) c /= tl;
    return true;
  }

  /// A feature node: its two neighbours along the curve (mesh edges that run along a feature
  /// edge). False unless there are exactly two: the node then ends no curve and joins none.
  bool load_curve(const ImproveTets& m) {
    curved_ = true;  // its faces are checked against the surface like a curved fan's
    int found = 0;
    for (std::uint32_t w : link_) {
      const NodeKind k = m.nodes().kind[w];
      if (k != NodeKind::edge && k != NodeKind::corner) continue;
      if (!along_feature(m.p(v_), m.p(w), *ctx_->boundary)) continue;
      if (found == 2) return false;
      ends_[found++] = w;
    }
    return found == 2;
  }
  bool feature() const { return feature_; }
  /// The neighbour along the curve on side i (0, 1) of a feature node.
  std::uint32_t curve_end(int i) const { return ends_[i]; }

  /// Mean length of the edges at v.
  double mean_edge(const ImproveTets& m) const {
    const double* x0 = m.p(v_);
    double sum = 0;
    for (std::uint32_t w : link_) {
      const double* q = m.p(w);
      sum += std::sqrt((q[0] - x0[0]) * (q[0] - x0[0]) + (q[1] - x0[1]) * (q[1] - x0[1]) +
                       (q[2] - x0[2]) * (q[2] - x0[2]));
    }
    return link_.empty() ? 0 : sum / double(link_.size());
  }
  bool on_surface() const { return on_surface_; }
  const std::vector<std::uint32_t>& link() const { return link_; }
  std::size_t size() const { return st_.size(); }

  double eval_tet(std::size_t j, const double* x) const {
    const StarTet& s = st_[j];
    const double* p[4] = {s.p[0], s.p[1], s.p[2], s.p[3]};
    p[s.iv] = x;
    return tet_sine(p);
  }
  double eval(const double* x) const {
    double q = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < st_.size(); ++j) q = std::min(q, eval_tet(j, x));
    return q;
  }
  /// With v at x: the smallest tet_sine of the star (eval) and the sum of its radius ratios
  /// (-inf if a tet is inverted), in one sweep. The sweep stops at the first inverted tet or
  /// tet_sine below `reject_below`, with the ratio -inf: a move the caller refuses either way.
  /// If `each` is given, it gets every tet's values (when the sweep runs to the end).
  SineRatio eval_both(const double* x, double reject_below = -std::numeric_limits<double>::infinity(),
                      std::vector<SineRatio>* each = nullptr) const {
    if (each) each->clear();
    return sweep_both(reject_below, [&](std::size_t j) {
      const StarTet& t = st_[j];
      const double* p[4] = {t.p[0], t.p[1], t.p[2], t.p[3]};
      p[t.iv] = x;
      const SineRatio q = tet_sine_ratio(p[0], p[1], p[2], p[3]);
      if (each) each->push_back(q);
      return q;
    });
  }
  /// eval_both at v's own position, from the values `known` holds for the star's tets.
  SineRatio known_both(const StarValues& known) const {
    return sweep_both(-std::numeric_limits<double>::infinity(), [&](std::size_t j) {
      return SineRatio{known.sine[star_[j]], known.ratio[star_[j]]};
    });
  }
  /// Writes the star's values (in star order) to `known`.
  void store(const StarValues& known, const std::vector<SineRatio>& each) const {
    for (std::size_t j = 0; j < each.size(); ++j) {
      known.sine[star_[j]] = each[j].sine;
      known.ratio[star_[j]] = each[j].ratio;
    }
  }
  /// Projects x onto the facet plane (surface nodes of a planar fan) or onto the closest
  /// point of the surface (curved fan).
  /// Returns false where a feature node's point has no feature edge to go to (the move is
  /// refused).
  bool project(double* x) const {
    if (!on_surface_) return true;
    if (feature_) return project_on_curve(x);
    if (curved_) {
      double cp[3];
      ctx_->query->closest(x, cp);
      std::copy_n(cp, 3, x);
      return true;
    }
    const double s = plane_offset(x);
    for (int k = 0; k < 3; ++k) x[k] -= s * n_[k];
    return true;
  }
  void project_dir(double* g) const {
    if (!on_surface_) return;
    const double s = dot3(g, tn_);
    for (int k = 0; k < 3; ++k) g[k] -= s * tn_[k];
  }
  /// Every tet valid, and for a surface node: every boundary face at v keeps its orientation
  /// and x stays on the surface. The boundary faces at v form a planar fan whose outer polygon
  /// is fixed: while every face keeps its orientation, v stays in the polygon's kernel and the
  /// new fan covers the same polygon as the old one, i.e. the same part of the surface.
  bool acceptable(const double* x) const {
    if (m_->locked(v_)) return false;  // on an interface between regions
    for (std::size_t j = 0; j < st_.size(); ++j) {
      const StarTet& s = st_[j];
      const double* p[4] = {s.p[0], s.p[1], s.p[2], s.p[3]};
      p[s.iv] = x;
      if (!tet_valid(p[0], p[1], p[2], p[3]) || !m_->inside_ok_moved(star_[j], s.iv, x))
        return false;
    }
    if (!on_surface_) return true;
    for (std::size_t k = 0; k < bfaces_.size(); ++k) {
      const double* p[3];
      for (int j = 0; j < 3; ++j) p[j] = bfaces_[k][j] == v_ ? x : m_->p(bfaces_[k][j]);
      double n[3];
      tri_normal(p[0], p[1], p[2], n);
      if (!(dot3(n, bnormal_[k].data()) > 0)) return false;
    }
    if (feature_) {
      // Between its two curve neighbours, and both edges to them still along the feature.
      for (int i = 0; i < 2; ++i) {
        const double *e = m_->p(ends_[i]), *o = m_->p(ends_[1 - i]), *x0 = m_->p(v_);
        double s0 = 0, s1 = 0;
        for (int k = 0; k < 3; ++k) s0 += (x[k] - e[k]) * (x0[k] - e[k]), s1 += (x[k] - e[k]) * (o[k] - e[k]);
        if (!(s0 > 0 && s1 > 0) || !along_feature(e, x, *ctx_->boundary)) return false;
      }
    }
    if (curved_) {
      // Each face at v stays on the surface (the mesh check's sampling and tolerance); x is
      // a closest surface point (project).
      for (const auto& bf : bfaces_) {
        const double* p[3];
        for (int j = 0; j < 3; ++j) p[j] = bf[j] == v_ ? x : m_->p(bf[j]);
        if (!face_on_surface(p[0], p[1], p[2], *ctx_->boundary)) return false;
      }
      return true;
    }
    // On the node's own facet (the common case on CAD facets): no surface query needed.
    return in_facet(x) || ctx_->query->distance(x) <= ctx_->on_surface;
  }
  /// Moves v to x (already acceptable).
  void commit(ImproveTets& m, const double* x) const {
    std::copy_n(x, 3, m.p_mut(v_));
    for (std::uint32_t t : star_) m.mark_inside(t);  // acceptable(x) checked every one
    if (on_surface_ && !in_facet(x)) {
      double cp[3];
      std::uint32_t facet = kNoFacet;
      ctx_->query->closest(x, cp, &facet);
      if (facet != kNoFacet) m.nodes().facet[v_] = facet;
    }
  }

 private:
  /// The smallest sine and the sum of the ratios of value(j) over the star's tets, in star
  /// order; stops at the first tet with ratio <= 0 or sine below `reject_below`, with the sum
  /// -inf.
  template <class Value>
  SineRatio sweep_both(double reject_below, Value&& value) const {
    SineRatio out{std::numeric_limits<double>::infinity(), 0};
    for (std::size_t j = 0; j < st_.size(); ++j) {
      const SineRatio q = value(j);
      out.sine = std::min(out.sine, q.sine);
      if (!(q.ratio > 0) || out.sine < reject_below) {
        out.ratio = -std::numeric_limits<double>::infinity();
        return out;
      }
      out.ratio += q.ratio;
    }
    return out;
  }

  /// Adds w to the link unless it is there: a small open-addressing set (a vertex is seen
  /// through 3-6 tets of its star; sorting every sighting took a tenth of the relaxation).
  /// Past kLinkSlots / 2 vertices the link takes every sighting and finish_link sorts them out.
  void add_link(std::uint32_t w) {
    if (link_.size() >= kLinkSlots / 2) {
      link_.push_back(w);
      return;
    }
    for (std::uint32_t h = (w * 0x9E3779B1u) >> 24;; h = (h + 1) & (kLinkSlots - 1)) {
      if (slot_[h] == w) return;
      if (slot_[h] == kEmptySlot) {
        slot_[h] = w;
        used_.push_back(h);
        link_.push_back(w);
        return;
      }
    }
  }
  /// The link sorted, without repeats; the set emptied for the next star.
  void finish_link() {
    for (std::uint32_t h : used_) slot_[h] = kEmptySlot;
    used_.clear();
    const bool spilled = link_.size() > kLinkSlots / 2;
    std::sort(link_.begin(), link_.end());
    if (spilled) link_.erase(std::unique(link_.begin(), link_.end()), link_.end());
  }

  /// x to the closest point of a feature edge of the facet closest to x.
  bool project_on_curve(double* x) const {
    double cp[3];
    std::uint32_t facet = kNoFacet;
    ctx_->query->closest(x, cp, &facet);
    if (facet == kNoFacet) return false;
    const SurfaceMesh& sm = ctx_->surface->mesh;
    double best = std::numeric_limits<double>::infinity(), y[3] = {0, 0, 0};
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t p = sm.tri(facet)[j], q = sm.tri(facet)[(j + 1) % 3];
      if (!ctx_->boundary->features->has_edge(p, q)) continue;
      const double *pp = sm.points.p(p), *pq = sm.points.p(q);
      double d[3], t = 0, dd = 0;
      for (int k = 0; k < 3; ++k) d[k] = pq[k] - pp[k], t += (x[k] - pp[k]) * d[k], dd += d[k] * d[k];
      t = dd > 0 ? std::clamp(t / dd, 0.0, 1.0) : 0.0;
      double z[3], dist = 0;
      for (int k = 0; k < 3; ++k) z[k] = pp[k] + t * d[k], dist += (z[k] - x[k]) * (z[k] - x[k]);
      if (dist < best) best = dist, std::copy_n(z, 3, y);
    }
    if (!(best < std::numeric_limits<double>::infinity())) return false;
    std::copy_n(y, 3, x);
    return true;
  }
  double plane_offset(const double* x) const {
    const double d[3] = {x[0] - fp_[0][0], x[1] - fp_[0][1], x[2] - fp_[0][2]};
    return dot3(d, n_);
  }
  bool in_facet(const double* x) const {
    if (std::fabs(plane_offset(x)) > ctx_->on_surface) return false;
    for (int j = 0; j < 3; ++j) {
      double n[3];
      tri_normal(x, fp_[(j + 1) % 3], fp_[(j + 2) % 3], n);
      if (dot3(n, n_) < 0) return false;
    }
    return true;
  }

  const ImproveTets* m_ = nullptr;
  const SmoothContext* ctx_ = nullptr;
  std::uint32_t v_ = 0, facet_ = kNoFacet;
  bool on_surface_ = false, curved_ = false, feature_ = false;
  std::uint32_t ends_[2] = {0, 0};  // a feature node's neighbours along its curve
  double n_[3] = {0, 0, 0};   // the facet's unit normal
  double tn_[3] = {0, 0, 0};  // the tangent plane's unit normal (n_ on a planar fan)
  const double* fp_[3] = {nullptr, nullptr, nullptr};
  static constexpr std::uint32_t kLinkSlots = 256, kEmptySlot = 0xFFFFFFFFu;
  std::vector<std::uint32_t> star_, link_, used_;
  std::array<std::uint32_t, kLinkSlots> slot_ = filled_slots();
  static constexpr std::array<std::uint32_t, kLinkSlots> filled_slots() {
    std::array<std::uint32_t, kLinkSlots> a{};
    for (std::uint32_t& x : a) x = kEmptySlot;
    return a;
  }
  std::vector<StarTet> st_;
  std::vector<std::array<std::uint32_t, 3>> bfaces_;
  std::vector<std::array<double, 3>> bnormal_;
};

/// A feature node's moves along its curve: towards either curve neighbour by 40, 20, 10 and 5%
/// of the way, projected onto the feature, best first; the first acceptable one that raises
/// the star's smallest quality is taken, up to `iterations` times. x and q0 are updated.
bool slide_on_curve(const ImproveTets& m, const VertexStar& vs, int iterations, double* x, double& q0) {
  static constexpr double kSteps[4] = {0.4, 0.2, 0.1, 0.05};
  bool moved = false;
  for (int iter = 0; iter < iterations; ++iter) {
    std::array<std::pair<double, std::array<double, 3>>, 8> cand;
    int n = 0;
    for (int side = 0; side < 2; ++side) {
      const double* e = m.p(vs.curve_end(side));
      for (double f : kSteps) {
        std::array<double, 3> y;
        for (int k = 0; k < 3; ++k) y[k] = x[k] + f * (e[k] - x[k]);
        // The chord's point first: the projection (a closest-point query) only for a move
        // that helps before it (on a straight curve the projection does not move it).
        if (!(vs.eval(y.data()) > q0) || !vs.project(y.data())) continue;
        const double q = vs.eval(y.data());
        if (q > q0) cand[n++] = {q, y};
      }
    }
    // Best first; ties in the order generated (side 0 first, longer steps first).
    std::stable_sort(cand.begin(), cand.begin() + n,
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    bool stepped = false;
    for (int i = 0; i < n && !stepped; ++i) {
      if (!vs.acceptable(cand[i].second.data())) continue;
      std::copy_n(cand[i].second.data(), 3, x);
      q0 = cand[i].first;
      stepped = moved = true;
    }
    if (!stepped) break;
  }
  return moved;
}

}  // namespace

bool smooth_vertex(ImproveTets& m, std::uint32_t v, const SmoothContext& ctx, double* before,
                   double* after, const KnownStar* star) {
  static thread_local VertexStar vs;
  static thread_local std::vector<std::array<double, 3>> grads, active;
  static thread_local std::vector<double> qs;
  if (!vs.load(m, v, ctx, true, star)) return false;
  const double* x0 = m.p(v);
  double x[3] = {x0[0], x0[1], x0[2]};
  const double q_start = vs.eval(x);
  double q0 = q_start;
  if (vs.feature()) {
    const bool slid = slide_on_curve(m, vs, ctx.iterations, x, q0);
    if (before) *before = q_start;
    if (after) *after = q0;
    if (slid) vs.commit(m, x);
    return slid;
  }
  bool moved = false;
  const double L = vs.mean_edge(m), h = 1e-7 * L;
  const std::size_t n = vs.size();
  qs.resize(n);
  for (int iter = 0; iter < ctx.iterations; ++iter) {
    grads.assign(n, {0, 0, 0});
    for (std::size_t j = 0; j < n; ++j) {
      qs[j] = vs.eval_tet(j, x);
      for (int k = 0; k < 3; ++k) {
        double y[3] = {x[0], x[1], x[2]};
        y[k] += h;
        grads[j][k] = (vs.eval_tet(j, y) - qs[j]) / h;
      }
      vs.project_dir(grads[j].data());
    }
    active.clear();
    for (std::size_t j = 0; j < n; ++j)
      if (qs[j] <= q0 + 1e-3) active.push_back(grads[j]);
    if (active.empty()) break;
    const std::array<double, 3> d = min_norm_point(active);
    const double dd = dot3(d.data(), d.data());
    if (!(dd > 0) || std::sqrt(dd) * L < 1e-9) break;
    // Largest step before a non-active tet's linearised quality falls to the active level.
    double alpha = 0.3 * L / std::sqrt(dd);
    for (std::size_t j = 0; j < n; ++j) {
      const double gd = dot3(grads[j].data(), d.data());
      if (qs[j] > q0 + 1e-3 && gd < dd) alpha = std::min(alpha, (qs[j] - q0) / (dd - gd));
    }
    bool stepped = false;
    for (int ls = 0; ls < 12; ++ls, alpha /= 2) {
      double y[3] = {x[0] + alpha * d[0], x[1] + alpha * d[1], x[2] + alpha * d[2]};
      if (!vs.project(y)) continue;
      const double q = vs.eval(y);
      if (!(q > q0) || !vs.acceptable(y)) continue;
      std::copy_n(y, 3, x);
      q0 = q;
      stepped = moved = true;
      break;
    }
    if (!stepped) break;
  }
  if (before) *before = q_start;
  if (after) *after = q0;
  if (moved) vs.commit(m, x);
  return moved;
}

bool relax_vertex(ImproveTets& m, std::uint32_t v, const SmoothContext& ctx, double floor,
                  const StarValues* known, const KnownStar* star) {
  static thread_local VertexStar vs;
  static thread_local std::vector<SineRatio> each;
  if (!vs.load(m, v, ctx, false, star)) return false;
  const double* x0 = m.p(v);
  double c[3] = {0, 0, 0};
  for (std::uint32_t w : vs.link())
    for (int k = 0; k < 3; ++k) c[k] += m.p(w)[k];
  for (double& ck : c) ck /= double(vs.link().size());
  const SineRatio old = known ? vs.known_both(*known) : vs.eval_both(x0);
  const double q_floor = std::min(old.sine, floor);
  for (double f : {1.0, 0.5, 0.25}) {
    double y[3];
    for (int k = 0; k < 3; ++k) y[k] = x0[k] + f * (c[k] - x0[k]);
    if (!vs.project(y)) continue;
    const SineRatio now = vs.eval_both(y, q_floor, known ? &each : nullptr);  // stops at a tet below q_floor
    if (!(now.ratio > old.ratio)) continue;
    if (now.sine < q_floor) continue;
    if (!vs.acceptable(y)) continue;
    vs.commit(m, y);
    if (known) vs.store(*known, each);  // the sweep ran to the end: a ratio sum, not -inf
    return true;
  }
  return false;
}

}  // namespace kdmesh
