// kdmesh — incremental Bowyer–Watson Delaunay kernel.
//
// Storage: one flat array of 32-byte tet records (core/tet_mesh.h: Triangulation): 4 vertex
// ids then 4 face references; adj(t,i) = 4u+j means face i of t (opposite v(t,i)) is face j
// of u. An infinite vertex closes the hull, so every face has a neighbour and the
// triangulation is a closed 3-sphere.
// Insertion: stochastic visibility walk from the hint's tet; cavity grown breadth-first with
// the perturbed insphere test; the star of the new point is built over the cavity boundary;
// new tets take the cavity's slots first (then the free list, then the end of the array), so
// the steady state allocates nothing.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/delaunay.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <string>

#include "core/error.h"
#include "core/rng.h"
#include "core/timer.h"
#include "mesher/conflict.h"
#include "mesher/predicates.h"

namespace kdmesh {

namespace {

constexpr std::uint32_t kInf = kInfiniteVertex;
constexpr std::uint32_t kNone = 0xFFFFFFFFu;
constexpr std::uint32_t kAliasBit = 0x80000000u;  // v2t entry of a duplicate: alias | vertex id
constexpr std::uint32_t kDead = 0xFFFFFFFEu;      // vertex 0 of a tet on the free list
// Face references 4*t+f must fit in 32 bits: tets < 2^30. The distributions measured here give
// 6.1-6.8 tets per point (docs/verification.md), so 2^27 points stay well inside.
constexpr std::size_t kMaxPoints = std::size_t(1) << 27;

enum : std::uint8_t { kUnvisited = 0, kInCavity = 1, kOutside = 2 };

/// kEdgeSlots[s][j]: the two slots of a tet other than s and j (s != j).
constexpr std::uint8_t kEdgeSlots[4][4][2] = {
    {{0, 0}, {2, 3}, {1, 3}, {1, 2}},
    {{2, 3}, {0, 0}, {0, 3}, {0, 2}},
    {{1, 3}, {0, 3}, {0, 0}, {0, 1}},
    {{1, 2}, {0, 2}, {0, 1}, {0, 0}},
};

/// Open-addressing map from an undirected edge to the new-tet face that holds it, reused
/// across insertions (only the used slots are cleared).
class EdgeMap {
 public:
  void reset(std::size_t expected_edges) {
    for (std::uint32_t s : used_) keys_[s] = kEmpty;
    used_.clear();
    std::size_t cap = 64;
    while (cap < 2 * expected_edges) cap <<= 1;
    if (cap > keys_.size()) {
      keys_.assign(cap, kEmpty);
      vals_.resize(cap);
    }
    mask_ = keys_.size() - 1;
  }
  /// Returns the face stored for edge (a,b), or records `face` and returns kNone. Each edge of
  /// a cavity boundary is seen exactly twice, so a matched entry is simply never asked again.
  std::uint32_t match(std::uint32_t a, std::uint32_t b, std::uint32_t face) {
    if (a > b) std::swap(a, b);
    const std::uint64_t key = (std::uint64_t(a) << 32) | b;
    std::size_t s = (key * 0x9E3779B97F4A7C15ULL) >> 40 & mask_;
    while (keys_[s] != kEmpty) {
      if (keys_[s] == key) return vals_[s];
      s = (s + 1) & mask_;
    }
    keys_[s] = key;
    vals_[s] = face;
    used_.push_back(std::uint32_t(s));
    return kNone;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> vals_;
  std::vector<std::uint32_t> used_;
  std::size_t mask_ = 0;
};

struct BoundaryFace {
  std::array<std::uint32_t, 4> v;  // vertices of the cavity tet, the face's opposite slot := p
  std::uint32_t slot;              // the slot that now holds p
  std::uint32_t outer;             // face reference 4*u+j of the tet outside the cavity
};

class Kernel {
 public:
  /// `points` are in the kernel's numbering (see delaunay()); `ids` maps it back to the
  /// caller's point ids for reports.
  Kernel(const PointSet& points, const std::uint32_t* ids, DelaunayStats& stats)
      : xyz_(points.xyz.data()), ids_(ids), n_(points.size()), stats_(stats), rng_(0x6b646d657368ULL) {
    // One spare entry at index n_: fill_cavity writes the infinite vertex's "v2t" there.
    v2t_.assign(n_ + 1, kNone);
    // Delaunay tetrahedralizations have ~6.76 tets per point for uniform points (6.2-6.5 on
    // surfaces). Reserve 7.5: only touched pages become resident, so the reserve costs address
    // space, not memory, while a reallocation would briefly hold two copies (at 5M points a
    // reserve of 6.75 was exceeded by 0.1% and the peak went from ~290 to ~495 bytes/point).
    const std::size_t expect = n_ * 15 / 2 + 64;
    T_.reserve(8 * expect);
    state_.reserve(expect);
  }

  /// Takes over an existing triangulation whose vertex ids index `points` directly (ids_ must
  /// then be the identity), to insert more points into it.
  void adopt(Triangulation&& tri, std::size_t extra_points) {
    T_ = std::move(tri.data);
    T_.reserve(T_.size() + 8 * (extra_points * 15 / 2 + 64));
    state_.assign(T_.size() / 8, kUnvisited);
    for (std::size_t t = 0; t < T_.size() / 8; ++t)
      for (int i = 0; i < 4; ++i)
        if (T_[8 * t + i] != kInf) v2t_[T_[8 * t + i]] = std::uint32_t(t);
    last_ = 0;
  }

  const double* P(std::uint32_t v) const { return xyz_ + 3 * std::size_t(v); }

  /// Creates the first tet from 4 non-coplanar points and closes it with 4 infinite tets.
  void init(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    if (pred::orient3d(P(a), P(b), P(c), P(d)) < 0) std::swap(a, b);
    const std::array<std::uint32_t, 4> t0 = {a, b, c, d};
    new_tet(t0);
    for (int i = 0; i < 4; ++i) {
      std::array<std::uint32_t, 4> t = t0;
      t[i] = kInf;
      std::swap(t[(i + 1) % 4], t[(i + 2) % 4]);  // put the infinite vertex outside face i
      new_tet(t);
    }
    // Link the 5 tets by matching faces (3 vertex ids each).
    for (std::uint32_t t = 0; t < 5; ++t)
      for (std::uint32_t f = 0; f < 4; ++f)
        for (std::uint32_t u = 0; u < 5; ++u)
          for (std::uint32_t g = 0; g < 4; ++g)
            if (u != t && same_face(t, f, u, g)) adj(t, f) = 4 * u + g;
    for (std::uint32_t t = 0; t < 5; ++t)
      for (int i = 0; i < 4; ++i)
        if (vert(t, i) != kInf) v2t_[vert(t, i)] = t;
    last_ = 0;
    stats_.inserted = 4;
  }

  /// Inserts point `pid`, starting the search at the tet of `hint` (a point id).
  void insert(std::uint32_t pid, std::uint32_t hint) {
    const double* p = P(pid);
    std::uint32_t start = last_;
    if (hint != kNone && hint < n_) {
      std::uint32_t h = v2t_[hint];
      if (h != kNone && (h & kAliasBit)) h = v2t_[h & ~kAliasBit];
      if (h != kNone) start = h;
    }
    const std::uint32_t base = locate(p, start);
    if (!is_infinite(base)) {
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t w = vert(base, i);
        const double* q = P(w);
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) {
          stats_.duplicates.push_back(ids_[pid]);
          stats_.duplicate_of.push_back(ids_[w]);
          v2t_[pid] = kAliasBit | w;
          return;
        }
      }
    }
    grow_cavity(base, p);
    fill_cavity(pid);
    ++stats_.inserted;
  }

  /// Moves the (compacted) records out, with vertices renumbered to the caller's ids.
  Triangulation release() {
    compact();
    for (std::size_t t = 0; t < T_.size(); t += 8)
      for (std::size_t i = t; i < t + 4; ++i)
        if (T_[i] != kInf) T_[i] = ids_[T_[i]];
    Triangulation tri;
    tri.data = std::move(T_);
    return tri;
  }

 private:
  std::uint32_t& vert(std::uint32_t t, int i) { return T_[8 * std::size_t(t) + i]; }
  std::uint32_t& adj(std::uint32_t t, int i) { return T_[8 * std::size_t(t) + 4 + i]; }
  /// The adjacency slot addressed by face reference f = 4*t+i.
  std::uint32_t& adj_of(std::uint32_t f) { return T_[8 * std::size_t(f >> 2) + 4 + (f & 3)]; }

  bool is_infinite(std::uint32_t t) const {
    const std::uint32_t* v = &T_[8 * std::size_t(t)];
    return v[0] == kInf || v[1] == kInf || v[2] == kInf || v[3] == kInf;
  }

  bool same_face(std::uint32_t t, std::uint32_t f, std::uint32_t u, std::uint32_t g) {
    std::array<std::uint32_t, 3> x{}, y{};
    for (int i = 0, k = 0; i < 4; ++i)
      if (i != int(f)) x[k++] = vert(t, i);
    for (int i = 0, k = 0; i < 4; ++i)
      if (i != int(g)) y[k++] = vert(u, i);
    std::sort(x.begin(), x.end());
    std::sort(y.begin(), y.end());
    return x == y;
  }

  std::uint32_t new_tet(const std::array<std::uint32_t, 4>& v) {
    std::uint32_t t;
    if (!free_.empty()) {
      t = free_.back();
      free_.pop_back();
    } else {
      t = std::uint32_t(T_.size() / 8);
      T_.resize(T_.size() + 8, kNone);
      state_.push_back(kUnvisited);
    }
    std::copy(v.begin(), v.end(), T_.begin() + 8 * std::size_t(t));
    return t;
  }

  /// Visibility walk: from `t`, cross any face that separates t from p, until p is in the
  /// closed tet (finite result) or beyond a hull face (infinite result, in conflict with p).
  /// The first face tried is random, which makes the walk terminate on any triangulation.
  std::uint32_t locate(const double* p, std::uint32_t t) {
    if (is_infinite(t)) {
      int i = 0;
      while (vert(t, i) != kInf) ++i;
      t = adj(t, i) >> 2;  // the finite tet behind the hull face
    }
    std::uint32_t prev = kNone;
    const std::size_t limit = 16 + T_.size() / 2;
    for (std::size_t steps = 0; steps < limit; ++steps) {
      const std::uint32_t r = std::uint32_t(rng_.next() >> 62);
      const std::uint32_t* rec = &T_[8 * std::size_t(t)];
      const double* q[4] = {P(rec[0]), P(rec[1]), P(rec[2]), P(rec[3])};
      std::uint32_t next = kNone;
      for (std::uint32_t j = 0; j < 4; ++j) {
        const std::uint32_t f = (j + r) & 3;
        const std::uint32_t n = rec[4 + f] >> 2;
        if (n == prev) continue;  // p is on t's side of that face (tested from the other side)
        const double* saved = q[f];
        q[f] = p;
        ++stats_.orient_tests;
        const int o = pred::orient3d(q[0], q[1], q[2], q[3]);
        q[f] = saved;
        if (o < 0) {
          next = n;
          break;
        }
      }
      if (next == kNone) return t;
      prev = t;
      t = next;
      if (is_infinite(t)) return t;
    }
    throw Error("delaunay: point location did not terminate (internal error)");
  }

  bool in_conflict(std::uint32_t n, const double* p) const {
    const std::uint32_t* v = &T_[8 * std::size_t(n)];
    if ((v[0] | v[1] | v[2] | v[3]) == kInf) return tet_in_conflict(xyz_, T_.data(), n, p);
    return pred::insphere_perturbed(P(v[0]), P(v[1]), P(v[2]), P(v[3]), p) > 0;
  }

  void grow_cavity(std::uint32_t base, const double* p) {
    cavity_.clear();
    touched_.clear();
    cavity_.push_back(base);
    state_[base] = kInCavity;
    for (std::size_t i = 0; i < cavity_.size(); ++i) {
      const std::uint32_t c = cavity_[i];
      for (int f = 0; f < 4; ++f) {
        const std::uint32_t n = adj(c, f) >> 2;
        if (state_[n] != kUnvisited) continue;
        if (in_conflict(n, p)) {
          state_[n] = kInCavity;
          cavity_.push_back(n);
        } else {
          state_[n] = kOutside;
          touched_.push_back(n);
        }
      }
    }
    stats_.conflicts += cavity_.size();
  }

  void fill_cavity(std::uint32_t pid) {
    // 1. Record the boundary faces before any cavity slot is overwritten.
    boundary_.clear();
    for (std::uint32_t c : cavity_)
      for (std::uint32_t f = 0; f < 4; ++f) {
        const std::uint32_t outer = adj(c, f);
        if (state_[outer >> 2] == kInCavity) continue;
        BoundaryFace b;
        std::memcpy(b.v.data(), &T_[8 * std::size_t(c)], sizeof(b.v));
        b.v[f] = pid;
        b.slot = f;
        b.outer = outer;
        boundary_.push_back(b);
      }
    for (std::uint32_t t : touched_) state_[t] = kUnvisited;
    // 2. Dead cavity tets become free slots; new tets take them first.
    for (std::uint32_t c : cavity_) {
      state_[c] = kUnvisited;
      vert(c, 0) = kDead;
      free_.push_back(c);
    }
    edges_.reset(boundary_.size() * 3 / 2 + 1);
    const std::uint32_t n32 = std::uint32_t(n_);
    std::uint32_t t = kNone;
    for (const BoundaryFace& b : boundary_) {
      t = new_tet(b.v);
      adj(t, b.slot) = b.outer;
      adj_of(b.outer) = 4 * t + b.slot;
      // The other 3 faces contain p and one edge of the boundary face: pair them by edge.
      for (std::uint32_t j = 0; j < 4; ++j) {
        if (j == b.slot) continue;
        const std::uint8_t* e = kEdgeSlots[b.slot][j];  // the two slots other than j and p's
        const std::uint32_t other = edges_.match(b.v[e[0]], b.v[e[1]], 4 * t + j);
        if (other != kNone) {
          adj(t, j) = other;
          adj_of(other) = 4 * t + j;
        }
      }
      // Branch-free: p's own entry is rewritten below with the last t anyway, and the infinite
      // vertex (kInf > n_) lands in the spare entry v2t_[n_].
      std::uint32_t* const v2t = v2t_.data();
      for (std::uint32_t i = 0; i < 4; ++i) v2t[std::min(b.v[i], n32)] = t;
    }
    v2t_[pid] = t;  // every new tet contains p
    last_ = t;
  }

  /// Removes free-list holes so that every tet in the array is alive.
  void compact() {
    if (free_.empty()) return;
    const std::size_t m = T_.size() / 8;
    std::vector<std::uint32_t> remap(m, kNone);
    std::uint32_t next = 0;
    for (std::size_t t = 0; t < m; ++t)
      if (T_[8 * t] != kDead) remap[t] = next++;
    for (std::size_t t = 0; t < m; ++t) {
      if (remap[t] == kNone) continue;
      const std::size_t d = 8 * std::size_t(remap[t]);
      for (int i = 0; i < 4; ++i) {
        T_[d + i] = T_[8 * t + i];
        const std::uint32_t a = T_[8 * t + 4 + i];
        T_[d + 4 + i] = 4 * remap[a >> 2] + (a & 3);
      }
    }
    T_.resize(8 * std::size_t(next));
    free_.clear();
  }

  const double* xyz_;
  const std::uint32_t* ids_;
  std::size_t n_;
  DelaunayStats& stats_;
  Rng rng_;
  std::vector<std::uint32_t> T_;  // tet records, 8 per tet
  std::vector<std::uint8_t> state_;
  std::vector<std::uint32_t> v2t_;
  std::vector<std::uint32_t> free_;
  std::vector<std::uint32_t> cavity_, touched_;
  std::vector<BoundaryFace> boundary_;
  EdgeMap edges_;
  std::uint32_t last_ = 0;
};

void validate_order(const PointSet& points, const Ordering& order) {
  const std::size_t n = points.size();
  if (order.order.size() != n || order.hint.size() != n)
    throw UsageError("delaunay: ordering has " + std::to_string(order.order.size()) +
                     " entries (and " + std::to_string(order.hint.size()) + " hints) for " +
                     std::to_string(n) + " points");
  std::vector<bool> seen(n, false);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t id = order.order[k];
    if (id >= n || seen[id])
      throw UsageError("delaunay: ordering is not a permutation (rank " + std::to_string(k) +
                       ", point " + std::to_string(id) + ")");
    seen[id] = true;
    if (order.hint[k] != kNoHint && order.hint[k] >= n)
      throw UsageError("delaunay: hint of rank " + std::to_string(k) + " is not a point id");
  }
}

bool same_point(const double* a, const double* b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

}  // namespace

DelaunayResult delaunay(const PointSet& points, const Ordering& order,
                        const DelaunayOptions& options) {
  Stopwatch clock;
  const std::size_t n = points.size();
  if (n == 0) throw GeometryError("delaunay: the point set is empty");
  if (n > kMaxPoints)
    throw UsageError("delaunay: " + std::to_string(n) + " points exceed the kernel's limit of " +
                     std::to_string(kMaxPoints));
  validate_order(points, order);
  const std::uint64_t exact0 = pred::exact_calls();

  DelaunayResult result;
  DelaunayStats& st = result.stats;

  // The kernel numbers vertex k after its rank in the order and keeps its own copy of the
  // coordinates in that order: consecutive insertions (neighbouring kd cells, or a curve's
  // neighbours) then touch nearby memory, as CGAL's vertices allocated in insertion order do.
  const std::vector<std::uint32_t>& ids = order.order;
  PointSet ranked;
  ranked.xyz.resize(3 * n);
  std::vector<std::uint32_t> rank_of(n);
  for (std::size_t k = 0; k < n; ++k) {
    std::memcpy(&ranked.xyz[3 * k], points.p(ids[k]), 3 * sizeof(double));
    rank_of[ids[k]] = std::uint32_t(k);
  }
  auto P = [&](std::size_t rank) { return ranked.p(std::uint32_t(rank)); };

  // Find 4 affinely independent points in insertion order; points skipped on the way are
  // inserted right after the first tet (they may be duplicates, collinear or coplanar).
  std::vector<std::uint32_t> deferred;
  std::size_t k = 1;
  for (; k < n && same_point(P(k), P(0)); ++k) {
    st.duplicates.push_back(ids[k]);
    st.duplicate_of.push_back(ids[0]);
  }
  if (k == n)
    throw GeometryError("delaunay: all " + std::to_string(n) +
                        " points are identical; no tetrahedralization exists");
  const std::uint32_t b = std::uint32_t(k++);
  for (; k < n && pred::collinear(P(0), P(b), P(k)); ++k) deferred.push_back(std::uint32_t(k));
  if (k == n)
    throw GeometryError("delaunay: all " + std::to_string(n) +
                        " points are collinear; no tetrahedralization exists");
  const std::uint32_t c = std::uint32_t(k++);
  for (; k < n && pred::orient3d(P(0), P(b), P(c), P(k)) == 0; ++k)
    deferred.push_back(std::uint32_t(k));
  if (k == n)
    throw GeometryError("delaunay: all " + std::to_string(n) +
                        " points are coplanar; no tetrahedralization exists");
  const std::uint32_t d = std::uint32_t(k++);

  Kernel kernel(ranked, ids.data(), st);
  kernel.init(0, b, c, d);
  std::size_t done = 0;
  auto report = [&] {
    if (options.progress && (++done & 0xFFFF) == 0) options.progress(double(done) / double(n));
  };
  auto hint_of = [&](std::size_t rank) {
    return order.hint[rank] == kNoHint ? kNone : rank_of[order.hint[rank]];
  };
  for (std::uint32_t r : deferred) {
    kernel.insert(r, hint_of(r));
    report();
  }
  for (; k < n; ++k) {
    kernel.insert(std::uint32_t(k), hint_of(k));
    report();
  }
  result.tri = kernel.release();
  st.exact_fallbacks = pred::exact_calls() - exact0;
  st.seconds = clock.seconds();
  if (options.progress) options.progress(1.0);
  return result;
}

void delaunay_insert(Triangulation& tri, const PointSet& points,
                     const std::vector<std::uint32_t>& ids,
                     const std::vector<std::uint32_t>& hints, DelaunayStats& stats) {
  Stopwatch clock;
  const std::size_t n = points.size();
  if (n > kMaxPoints)
    throw UsageError("delaunay_insert: " + std::to_string(n) +
                     " points exceed the kernel's limit of " + std::to_string(kMaxPoints));
  if (hints.size() != ids.size())
    throw UsageError("delaunay_insert: " + std::to_string(hints.size()) + " hints for " +
                     std::to_string(ids.size()) + " points");
  if (tri.num_tets() == 0)
    throw UsageError("delaunay_insert: the triangulation is empty (use delaunay() first)");
  for (std::uint32_t id : ids)
    if (id >= n)
      throw UsageError("delaunay_insert: point id " + std::to_string(id) + " out of range (" +
                       std::to_string(n) + " points)");
  // Validate before the kernel takes the records over: on error `tri` is left unchanged.
  for (std::size_t t = 0; t < tri.num_tets(); ++t)
    for (int i = 0; i < 4; ++i)
      if (tri.v(t, i) != kInf && tri.v(t, i) >= n)
        throw UsageError("delaunay_insert: the triangulation has vertex " +
                         std::to_string(tri.v(t, i)) + " but only " + std::to_string(n) +
                         " points are given");
  const std::uint64_t exact0 = pred::exact_calls();
  std::vector<std::uint32_t> identity(n);
  for (std::size_t i = 0; i < n; ++i) identity[i] = std::uint32_t(i);
  Kernel kernel(points, identity.data(), stats);
  kernel.adopt(std::move(tri), ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) kernel.insert(ids[k], hints[k]);
  tri = kernel.release();
  stats.exact_fallbacks += pred::exact_calls() - exact0;
  stats.seconds += clock.seconds();
}

std::vector<std::uint32_t> finite_tets(const Triangulation& tri) {
  std::vector<std::uint32_t> out;
  out.reserve(tri.data.size() / 2);
  for (std::size_t t = 0; t < tri.num_tets(); ++t)
    if (!tri.is_infinite(t))
      out.insert(out.end(), tri.data.begin() + 8 * t, tri.data.begin() + 8 * t + 4);
  return out;
}

std::size_t count_finite_tets(const Triangulation& tri) {
  std::size_t n = 0;
  for (std::size_t t = 0; t < tri.num_tets(); ++t) n += !tri.is_infinite(t);
  return n;
}

}  // namespace kdmesh
