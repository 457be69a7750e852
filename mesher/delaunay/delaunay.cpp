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
// Parallel insertion (DelaunayOptions::threads > 1): after a sequential prefix, rounds in which
// each worker inserts the points of its own slab and may touch only the tets whose four
// vertices lie in that slab (insert_in_rounds below); the result is the same triangulation.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/delaunay/delaunay.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <tuple>

#include "core/cpu_count.h"
#include "core/error.h"
#include "core/page_warmer.h"
#include "core/parallel_for.h"
#include "core/rng.h"
#include "core/timer.h"
#include "core/uninit_allocator.h"
#include "mesher/delaunay/conflict.h"
#include "mesher/delaunay/predicates.h"

namespace kdmesh {

namespace {

constexpr std::uint32_t kInf = kInfiniteVertex;
constexpr std::uint32_t kNone = 0xFFFFFFFFu;
constexpr std::uint32_t kAliasBit = 0x80000000u;  // v2t entry of a duplicate: alias | vertex id
constexpr std::uint32_t kDead = 0xFFFFFFFEu;      // vertex 0 of a tet on the free list
// Face references 4*t+f must fit in 32 bits: tets < 2^30. The distributions measured here give
// 6.1-6.8 tets per point (docs/verification.md), so 2^27 points stay well inside.
constexpr std::size_t kMaxPoints = std::size_t(1) << 27;

/// A tet's mark in the current cavity search. A distinct type, not a char: a store through a
/// char pointer may alias anything, and after each one the compiler would reload the kernel's
/// arrays and stack pointers from memory.
enum Mark : std::uint8_t { kUnvisited = 0, kInCavity = 1, kOutside = 2 };

/// Hides a value from the optimiser, so that selects on it stay selects (cmov) and are not
/// turned back into branches: for coin-toss conditions, where a branch is mispredicted about
/// half the time (each ~15-20 cycles).
template <class T>
[[gnu::always_inline]] inline T opaque(T x) {
  asm("" : "+r"(x));
  return x;
}

/// A growable array of trivially copyable values for the insertion loop. Unlike
/// std::vector::push_back, whose inlining GCC gives up on once the kernel exists in two
/// instantiations (+8% instructions per point, measured with callgrind), push() is always
/// inlined and only the rare growth is a call.
template <class T>
class Stack {
 public:
  [[gnu::always_inline]] void push(const T& x) {
    if (end_ == cap_) [[unlikely]]
      grow();
    *end_++ = x;
  }
  /// Room for `count` more values: push_unchecked() may then be called that many times.
  void reserve_more(std::size_t count) {
    if (std::size_t(cap_ - end_) < count) [[unlikely]]
      grow(count);
  }
  [[gnu::always_inline]] void push_unchecked(const T& x) { *end_++ = x; }
  /// After writing values in place past end() (within reserved room): the new end.
  void set_end(T* e) { end_ = e; }
  void clear() { end_ = data_; }
  bool empty() const { return end_ == data_; }
  std::size_t size() const { return std::size_t(end_ - data_); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& back() const { return end_[-1]; }
  void pop_back() { --end_; }
  T* begin() { return data_; }
  T* end() { return end_; }
  void append(Stack& o) {
    for (const T& x : o) push(x);
  }
  void swap(Stack& o) {
    buf_.swap(o.buf_);
    std::swap(data_, o.data_);
    std::swap(end_, o.end_);
    std::swap(cap_, o.cap_);
  }

 private:
  [[gnu::noinline]] void grow(std::size_t more = 1) {
    const std::size_t n = size();
    buf_.resize(std::max<std::size_t>({64, 2 * buf_.size(), n + more}));
    data_ = buf_.data();
    end_ = data_ + n;
    cap_ = data_ + buf_.size();
  }
  std::vector<T> buf_;  // owns the storage; [data_, end_) is in use, cap_ its end
  T* data_ = nullptr;
  T* end_ = nullptr;
  T* cap_ = nullptr;
};

/// Open-addressing map from an undirected edge to the new-tet face that holds it, reused
/// across insertions without clearing: each key carries the insertion's generation in its top
/// bits (vertex ids are below 2^27, so bits 59-63 are free), and a slot whose generation is
/// older than the current one (a key below the current tag) is empty. The table is cleared
/// only when the generation wraps, every 31 insertions, and then only as far as it was used.
class EdgeMap {
 public:
  void reset(std::size_t expected_edges) {
    std::size_t cap = 64;
    while (cap < 4 * expected_edges) cap <<= 1;  // load <= 1/4: few collisions (a branch each)
    if (cap > keys_.size()) {
      keys_.assign(cap, 0);  // generation 0 is never current
      vals_.resize(cap);
      dirty_ = 0;
      gen_ = 0;
    }
    if (++gen_ == 32) {
      std::fill(keys_.begin(), keys_.begin() + std::ptrdiff_t(dirty_), 0);
      dirty_ = 0;
      gen_ = 1;
    }
    mask_ = cap - 1;
    dirty_ = std::max(dirty_, cap);
    tag_ = std::uint64_t(gen_) << kGenShift;
  }
  /// Returns the face stored for edge (a,b), or records `face` and returns kNone. Each edge of
  /// a cavity boundary is seen exactly twice, so a matched entry is simply never asked again.
  /// Whether the edge is new or seen is a coin toss, so that choice is made without a branch
  /// (a mispredicted branch costs more than the stores it saves); only a collision branches.
  [[gnu::always_inline]] std::uint32_t match(std::uint32_t a, std::uint32_t b, std::uint32_t face) {
    const std::uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    const std::uint64_t key = (std::uint64_t(lo) << 32 | hi) | tag_;  // lo < 2^27: below the tag
    std::size_t s = (key * 0x9E3779B97F4A7C15ULL) >> 40 & mask_;
    std::uint64_t k = keys_[s];
    // Older generations are below the current tag: empty. Probe on a collision only (rare).
    while (opaque(std::uint32_t(k >= tag_) & std::uint32_t(k != key))) {
      s = (s + 1) & mask_;
      k = keys_[s];
    }
    // Unconditional stores: a seen edge is never asked again, so its value may be overwritten.
    const std::uint32_t old = vals_[s];
    keys_[s] = key;
    vals_[s] = face;
    return old | opaque(0u - std::uint32_t(k != key));  // kNone (all ones) if the edge is new
  }

 private:
  static constexpr int kGenShift = 59;
  static_assert((std::uint64_t(kMaxPoints) << 32) <= (std::uint64_t(1) << kGenShift),
                "vertex ids must stay below the generation tag");
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> vals_;
  std::size_t mask_ = 0;
  std::size_t dirty_ = 0;  // keys_[0, dirty_) may hold entries of past generations
  std::uint64_t tag_ = 0;  // gen_ << kGenShift
  std::uint32_t gen_ = 0;
};

/// A face of the cavity's boundary: the new tet on it is (w[0], w[1], w[2], p), positively
/// oriented, so p is always in slot 3 and the face in slot 3 is the boundary face.
struct BoundaryFace {
  std::uint32_t w[3];
  std::uint32_t outer;  // face reference 4*u+j of the tet outside the cavity
};

/// The triangulation under construction, shared by the kernel's workers (one when sequential).
struct Store {
  const double* xyz = nullptr;     // coordinates in the kernel's numbering
  std::size_t n = 0;               // points
  TetRecords T;                    // tet records, 8 per tet; those at >= used are spare slots
  std::vector<Mark> state;  // per tet: mark of the current cavity search
  std::vector<std::uint32_t> v2t;  // per vertex: a tet that contains it; entries >= n are spares
  std::size_t used = 0;            // tets [0, used) are in use (alive or on a free list)

  const double* P(std::uint32_t v) const { return xyz + 3 * std::size_t(v); }
  std::size_t num_tets() const { return used; }
  /// Appends `count` slots, all in use (alive or on a free list) from now on.
  void add_slots(std::size_t count) {
    used += count;
    if (8 * used > T.size()) resize_slots(used);
  }
  /// Room for at least `count` more slots past `used`, which is unchanged: appending a tet is
  /// then a counter increment, not a vector resize per tet (2.7% of the instructions).
  void spare_slots(std::size_t count) { resize_slots(T.size() / 8 + count); }
  /// Drops the spare slots.
  void trim() { resize_slots(used); }
  /// Slot arrays for `tets` tets; new slots are unmarked, and their records unwritten (a new
  /// tet's record is written whole; a parallel worker marks its unused slots kDead), so that
  /// their pages are first touched by the thread that fills them.
  void resize_slots(std::size_t tets) {
    T.resize(8 * tets);
    state.resize(tets, kUnvisited);
  }
};

/// dir . x, always evaluated the same way, so that a point's slab never depends on who asks.
inline double along(const std::array<double, 3>& dir, const double* x) {
  return dir[0] * x[0] + dir[1] * x[1] + dir[2] * x[2];
}

constexpr std::uint16_t kNoSlab = 0xFFFF;  // above any worker (at most 256)

/// What a worker of a parallel round may touch. It owns the vertices in its slab between two
/// parallel planes (the infinite vertex belongs to every slab) and may read or write a tet
/// only if it owns all four of its vertices. Two workers then never touch the same tet: the
/// tets they read across a face of an owned tet share three owned vertices, so no other worker
/// owns more than two of theirs (counting the infinite vertex for both). New tets come from the worker's free list, then from its own
/// slot range [next, end) of the tet array.
struct Territory {
  const std::uint16_t* slab = nullptr;  // per vertex (rank): the slab it lies in, kNoSlab if
  std::uint16_t own = 0;                // not yet placed in one; the worker owns slab `own`
  std::uint32_t next = 0, end = 0;
};

/// One inserting thread. `kParallel` workers respect a Territory: a point whose walk or cavity
/// reaches a tet they do not own is not inserted (insert() returns false; nothing changed) and
/// goes to a later round. The sequential instantiation compiles those checks away.
template <bool kParallel>
class Kernel {
 public:
  /// `ids` maps the kernel's numbering back to the caller's point ids for reports; `spare` is
  /// the v2t entry this worker writes for the infinite vertex (>= n, one per worker).
  Kernel(Store& s, const std::uint32_t* ids, DelaunayStats& stats, std::uint64_t seed,
         std::uint32_t spare)
      : s_(s), xyz_(s.xyz), ids_(ids), spare_(spare), stats_(stats), rng_(seed) {
    refresh();
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

  /// Inserts point `pid`, starting the search at the tet of `hint` (a point id). A parallel
  /// worker returns false, having changed nothing, when the point needs a tet it does not own.
  bool insert(std::uint32_t pid, std::uint32_t hint) {
    const double* p = P(pid);
    const std::uint32_t start = start_tet(hint);
    if constexpr (kParallel)
      if (start == kNone) return false;
    const std::uint32_t base = locate(p, start);
    if constexpr (kParallel)
      if (base == kNone) return false;
    if (!is_infinite(base)) {
      for (int i = 0; i < 4; ++i) {
        const std::uint32_t w = vert(base, i);
        const double* q = P(w);
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) {
          stats_.duplicates.push_back(ids_[pid]);
          stats_.duplicate_of.push_back(ids_[w]);
          v2t_[pid] = kAliasBit | w;
          return true;
        }
      }
    }
    if (!grow_cavity(base, p)) return false;
    fill_cavity(pid);
    ++stats_.inserted;
    return true;
  }

  /// Parallel rounds: the worker's territory for the next round (its last tet may be gone).
  void enter(const Territory& t) {
    terr_ = t;
    last_ = kNone;
    refresh();  // the rounds add slots to the store
  }
  /// Ends a round: unused slots of the territory's range join the free list.
  void leave() {
    for (std::uint32_t t = terr_.next; t < terr_.end; ++t) {
      vert(t, 0) = kDead;
      free_.push(t);
    }
    terr_.next = terr_.end;
  }
  Stack<std::uint32_t>& free_list() { return free_; }
  void set_last(std::uint32_t t) { last_ = t; }

 private:
  std::uint32_t& vert(std::uint32_t t, int i) { return T_[8 * std::size_t(t) + i]; }
  std::uint32_t& adj(std::uint32_t t, int i) { return T_[8 * std::size_t(t) + 4 + i]; }
  /// The adjacency slot addressed by face reference f = 4*t+i.
  std::uint32_t& adj_of(std::uint32_t f) { return T_[8 * std::size_t(f >> 2) + 4 + (f & 3)]; }

  void refresh() {
    T_ = s_.T.data();
    state_ = s_.state.data();
    v2t_ = s_.v2t.data();
  }

  bool is_infinite(std::uint32_t t) const {
    const std::uint32_t* v = &T_[8 * std::size_t(t)];
    return v[0] == kInf || v[1] == kInf || v[2] == kInf || v[3] == kInf;
  }

  bool owns_vertex(std::uint32_t v) const {
    return v == kInf || terr_.slab[v] == terr_.own;
  }
  bool owns_tet(std::uint32_t t) const {
    const std::uint32_t* v = &T_[8 * std::size_t(t)];
    return owns_vertex(v[0]) && owns_vertex(v[1]) && owns_vertex(v[2]) && owns_vertex(v[3]);
  }

  /// The tet to start locating from: one of the hint's tets, else (no hint) the last new tet.
  /// A parallel worker gives kNone, so that the point waits for a later round, when the hint
  /// is outside its territory, not inserted yet (deferred itself), or on a tet it does not
  /// own: the point is then near a slab boundary too, and walking from farther away would
  /// cost many orientation tests only to be deferred after all.
  [[gnu::always_inline]] std::uint32_t start_tet(std::uint32_t hint) const {
    if constexpr (kParallel) {
      if (hint == kNone) return last_;
      if (!owns_vertex(hint)) return kNone;
      std::uint32_t h = v2t_[hint];
      if (h != kNone && (h & kAliasBit)) h = v2t_[h & ~kAliasBit];
      return h != kNone && owns_tet(h) ? h : kNone;
    } else {
      if (hint != kNone && hint < s_.n) {
        std::uint32_t h = v2t_[hint];
        if (h != kNone && (h & kAliasBit)) h = v2t_[h & ~kAliasBit];
        if (h != kNone) return h;
      }
      return last_;
    }
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

  [[gnu::always_inline]] std::uint32_t new_tet(const std::array<std::uint32_t, 4>& v) {
    std::uint32_t t;
    if (!free_.empty()) {
      t = free_.back();
      free_.pop_back();
    } else if constexpr (kParallel) {
      t = terr_.next++;  // room checked in grow_cavity()
    } else {
      if (8 * s_.used == s_.T.size()) [[unlikely]]
        grow_slots();
      t = std::uint32_t(s_.used++);
    }
    std::memcpy(&T_[8 * std::size_t(t)], v.data(), sizeof(v));
    return t;
  }

  [[gnu::noinline]] void grow_slots() {
    s_.spare_slots(std::max<std::size_t>(1024, s_.used / 64));
    refresh();
  }

  /// walk(), counted: the orientation tests and the walk histogram (DelaunayStats::walks).
  [[gnu::always_inline]] std::uint32_t locate(const double* p, std::uint32_t t) {
    std::uint64_t tests = 0;  // a local: the walk's loop keeps it in a register
    t = walk(p, t, tests);
    const std::size_t bin = std::min<std::size_t>(std::bit_width(tests), kWalkBins - 1);
    stats_.orient_tests += tests;
    ++stats_.walks[bin];
    stats_.walk_tests[bin] += tests;
    return t;
  }

  /// Steps of walk() with ordered faces before its first face becomes random.
  static constexpr std::size_t kOrderedSteps = 1024;

  /// Visibility walk: from `t`, cross any face that separates t from p, until p is in the
  /// closed tet (finite result) or beyond a hull face (infinite result, in conflict with p).
  /// Faces are tried in a heuristic order (below). A visibility walk terminates on a Delaunay
  /// triangulation whatever the order (the in-front relation is acyclic there); as a guard,
  /// after kOrderedSteps steps the first face becomes random, which terminates on any
  /// triangulation (with probability 1). A parallel worker returns kNone when the walk would
  /// enter a tet it does not own.
  [[gnu::always_inline]] std::uint32_t walk(const double* p, std::uint32_t t,
                                            std::uint64_t& tests) {
    if (is_infinite(t)) {
      int i = 0;
      while (vert(t, i) != kInf) ++i;
      t = adj(t, i) >> 2;  // the finite tet behind the hull face
      if constexpr (kParallel)
        if (!owns_tet(t)) return kNone;
    }
    std::uint32_t prev = kNone;
    const std::size_t limit = 16 + 4 * s_.used;
    for (std::size_t steps = 0; steps < limit; ++steps) {
      const std::uint32_t* rec = &T_[8 * std::size_t(t)];
      for (int f = 0; f < 4; ++f) __builtin_prefetch(&T_[8 * std::size_t(rec[4 + f] >> 2)]);  // next
      const double* q[4] = {P(rec[0]), P(rec[1]), P(rec[2]), P(rec[3])};
      // Faces in the order of their opposite vertices' projections on the direction from the
      // centroid to p (u = 4 (p - centroid)): the face opposite the vertex farthest behind
      // first, as p most likely lies beyond it. The order only saves tests; any order finds
      // the same tet. Past kOrderedSteps the walk turns random (termination on any input).
      std::uint32_t ord[4] = {0, 1, 2, 3};
      if (steps < kOrderedSteps) {
        const double ux = 4 * p[0] - (q[0][0] + q[1][0] + q[2][0] + q[3][0]);
        const double uy = 4 * p[1] - (q[0][1] + q[1][1] + q[2][1] + q[3][1]);
        const double uz = 4 * p[2] - (q[0][2] + q[1][2] + q[2][2] + q[3][2]);
        double k[4];
        for (int i = 0; i < 4; ++i) k[i] = q[i][0] * ux + q[i][1] * uy + q[i][2] * uz;
        // Sorting network step, keys ascending, without branches (the comparisons are coin
        // tosses): min/max for the keys, a masked exchange for the faces.
        auto cas = [&](int a, int b) {
          const std::uint32_t swap = opaque(0u - std::uint32_t(k[b] < k[a]));  // all ones if so
          const double ka = k[a], kb = k[b];
          k[a] = kb < ka ? kb : ka;
          k[b] = kb < ka ? ka : kb;
          const std::uint32_t x = (ord[a] ^ ord[b]) & swap;
          ord[a] ^= x;
          ord[b] ^= x;
        };
        cas(0, 1);
        cas(2, 3);
        cas(0, 2);
        cas(1, 3);
        cas(1, 2);
      } else {
        const std::uint32_t r = std::uint32_t(rng_.next() >> 62);
        for (std::uint32_t j = 0; j < 4; ++j) ord[j] = (j + r) & 3;
      }
      std::uint32_t next = kNone;
      for (std::uint32_t j = 0; j < 4; ++j) {
        const std::uint32_t f = ord[j];
        const std::uint32_t n = rec[4 + f] >> 2;
        if (n == prev) continue;  // p is on t's side of that face (tested from the other side)
        const double* saved = q[f];
        q[f] = p;
        ++tests;
        const int o = pred::orient3d(q[0], q[1], q[2], q[3]);
        q[f] = saved;
        if (o < 0) {
          next = n;
          break;
        }
      }
      if (next == kNone) return t;
      if constexpr (kParallel)
        if (!owns_tet(next)) return kNone;
      prev = t;
      t = next;
      if (is_infinite(t)) return t;
    }
    throw Error("delaunay: point location did not terminate (internal error)");
  }

  /// One tet against p: for the last neighbour left without a partner, for infinite tets and
  /// where the two-lane filter gives no sign; so out of line (inlined, GCC mixes its scalar
  /// code into the two-lane path: +5% instructions per point, measured with callgrind).
  [[gnu::noinline]] bool in_conflict(std::uint32_t n, const double* p) const {
    const std::uint32_t* v = &T_[8 * std::size_t(n)];
    if ((v[0] | v[1] | v[2] | v[3]) == kInf) return tet_in_conflict(xyz_, T_, n, p);
    return pred::insphere_perturbed(P(v[0]), P(v[1]), P(v[2]), P(v[3]), p) > 0;
  }

  /// in_conflict() for two tets, the finite ones' float filter evaluated in one SSE2 pass.
  [[gnu::always_inline]] void in_conflict2(std::uint32_t n0, std::uint32_t n1, const double* p,
                                           bool& c0, bool& c1) const {
    const std::uint32_t* v = &T_[8 * std::size_t(n0)];
    const std::uint32_t* w = &T_[8 * std::size_t(n1)];
    if ((v[0] | v[1] | v[2] | v[3]) == kInf || (w[0] | w[1] | w[2] | w[3]) == kInf) {
      c0 = in_conflict(n0, p);
      c1 = in_conflict(n1, p);
      return;
    }
    const double* a[4] = {P(v[0]), P(v[1]), P(v[2]), P(v[3])};
    const double* b[4] = {P(w[0]), P(w[1]), P(w[2]), P(w[3])};
    int s[2];
    pred::insphere_filter2(a, b, p, s);
    if ((s[0] == 0) | (s[1] == 0)) [[unlikely]] {
      if (s[0] == 0) s[0] = in_conflict(n0, p) ? 1 : -1;
      if (s[1] == 0) s[1] = in_conflict(n1, p) ? 1 : -1;
    }
    c0 = s[0] > 0;
    c1 = s[1] > 0;
  }

  /// Collects the tets in conflict with p, breadth-first from `base`. Unvisited neighbours are
  /// tested two at a time (in_conflict2) and recorded in the order they were met, so the cavity
  /// and its boundary come out exactly as with one test at a time. A parallel worker gives up
  /// (false, marks cleared) when the cavity holds a tet it does not own, or when its slot range
  /// cannot hold the new tets. It checks a tet's ownership when it comes to expand it, not when
  /// the tet is found in conflict: the recording then stays free of branches, whose outcome (in
  /// conflict or not) is a coin toss. The decision is the same: the cavity holds a tet the
  /// worker does not own or it does not, and such a tet is never expanded.
  [[gnu::always_inline]] bool grow_cavity(std::uint32_t base, const double* p) {
    Mark* const state = state_;
    const std::uint32_t* const T = T_;
    cavity_.clear();
    cavity_.push(base);
    state[base] = kInCavity;
    // Records a tested tet, without a branch: kInCavity and onto the cavity if in conflict,
    // otherwise left kOutside (fill_cavity() unmarks it, as each is outside a face of the
    // cavity's boundary).
    auto record = [&](std::uint32_t n, bool conflict) {
      // If n is in conflict, its neighbours will be tested once the tets queued before it are
      // done: start loading their records and marks now, the earliest moment the addresses are
      // known (n's record was just read). Whether n is in conflict is a coin toss, so this is
      // done for every tested tet. 1M points, 3 alternations: -5% on the cube, -6% on the
      // axes for the records, about as much again with the marks.
      for (int f = 0; f < 4; ++f) {
        const std::uint32_t u = T[8 * std::size_t(n) + 4 + f] >> 2;
        __builtin_prefetch(&T[8 * std::size_t(u)]);
        __builtin_prefetch(&state[u]);
      }
      state[n] = Mark(kOutside - conflict);  // kInCavity if in conflict
      cavity_.push_unchecked(n);            // room reserved by the caller
      cavity_.set_end(cavity_.end() - !conflict);
    };
    // Neighbours met, marked kOutside and not tested yet, in the order met: at most one left
    // over from the last cavity tet plus four new ones.
    std::uint32_t pend[6] = {};  // (pend[j] below may be read past np; never used then)
    std::size_t np = 0;
    for (std::size_t i = 0;;) {
      if (i == cavity_.size()) {
        if (np == 0) break;
        np = 0;  // one left: pairs are tested as soon as they form
        cavity_.reserve_more(1);
        record(pend[0], in_conflict(pend[0], p));
        continue;  // it may have grown the cavity
      }
      const std::uint32_t c = cavity_[i];
      // A tet found in conflict is adjacent to an expanded one, which the worker owns: no other
      // worker can own it or reach it, so it was safe to test and mark. Its neighbours may not be.
      if constexpr (kParallel)
        if (!owns_tet(c)) [[unlikely]]
          return abandon_cavity(i);
      // Gather the unvisited neighbours without a branch per face (whether a neighbour is new
      // is unpredictable): each is written at the end and kept by moving the end past it.
      const std::uint32_t* adj = &T[8 * std::size_t(c) + 4];
      ++i;
      // The next cavity tet's neighbours will be tested soon: start loading their records (a
      // cache miss each on large inputs; 1M points, with locate()'s prefetch: -14% on the
      // cube, -24% on the axes).
      if (i < cavity_.size()) {
        const std::uint32_t* nx = &T[8 * std::size_t(cavity_[i]) + 4];
        for (int f = 0; f < 4; ++f) __builtin_prefetch(&T[8 * std::size_t(nx[f] >> 2)]);
      }
      for (int f = 0; f < 4; ++f) {
        const std::uint32_t n = adj[f] >> 2;
        const Mark m = state[n];
        const std::uint32_t fresh = m == kUnvisited;
        pend[np] = n;
        np += fresh;
        state[n] = Mark(m | fresh << 1);  // kUnvisited -> kOutside, the others unchanged
      }
      std::size_t j = 0;
      cavity_.reserve_more(np);
      for (; j + 1 < np; j += 2) {
        bool c0, c1;
        in_conflict2(pend[j], pend[j + 1], p, c0, c1);
        record(pend[j], c0);
        record(pend[j + 1], c1);
      }
      pend[0] = pend[j];
      np -= j;
    }
    if constexpr (kParallel) {
      // A cavity of k tets (a ball) has at most 2k + 2 boundary faces, one new tet each; k of
      // them reuse the cavity's slots.
      if (cavity_.size() + 2 > free_.size() + (terr_.end - terr_.next))
        return abandon_cavity(cavity_.size());
    }
    stats_.conflicts += cavity_.size();
    return true;
  }

  /// A parallel worker gives the cavity up: unmarks its tets and every tet marked while the
  /// first `expanded` of them were expanded, i.e. their neighbours (tested or still pending).
  /// Those are adjacent to tets the worker owns, so no other worker marks them meanwhile.
  bool abandon_cavity(std::size_t expanded) {
    for (std::size_t j = 0; j < expanded; ++j) {
      const std::uint32_t* adj = &T_[8 * std::size_t(cavity_[j]) + 4];
      for (int f = 0; f < 4; ++f) state_[adj[f] >> 2] = kUnvisited;
    }
    for (std::uint32_t t : cavity_) state_[t] = kUnvisited;
    return false;
  }

  [[gnu::always_inline]] void fill_cavity(std::uint32_t pid) {
    // 1. Record the boundary faces before any cavity slot is overwritten. Face f of cavity tet
    //    (v0, v1, v2, v3) becomes the new tet with v_f replaced by p and the vertices permuted
    //    by i -> i ^ (f ^ 3): an even permutation (the identity or two swaps), so the tet stays
    //    positively oriented, that puts p in slot 3. Every new tet then has the same layout.
    //    Without a branch per face (whether a face is on the boundary is unpredictable): each
    //    face is written at the end and kept by moving the end past it. The tets outside, all
    //    tested from a cavity face (kOutside), are unmarked on the way.
    boundary_.clear();
    boundary_.reserve_more(4 * cavity_.size());
    BoundaryFace* out = boundary_.end();
    for (std::uint32_t c : cavity_) {
      const std::uint32_t* rec = &T_[8 * std::size_t(c)];
      for (std::uint32_t f = 0; f < 4; ++f) {
        const std::uint32_t outer = rec[4 + f];
        const Mark m = state_[outer >> 2];
        state_[outer >> 2] = Mark(m & kInCavity);  // kOutside -> kUnvisited
        const std::uint32_t x = f ^ 3;
        *out = BoundaryFace{{rec[x], rec[1 ^ x], rec[2 ^ x]}, outer};
        out += m != kInCavity;
      }
    }
    boundary_.set_end(out);
    // 2. Dead cavity tets become free slots; new tets take them first.
    free_.reserve_more(cavity_.size());
    for (std::uint32_t c : cavity_) {
      state_[c] = kUnvisited;
      vert(c, 0) = kDead;
      free_.push_unchecked(c);
    }
    // 3. The new tets. Face 3 is the boundary face; face k < 3 contains p and the boundary
    //    face's edge opposite w[k], shared with one other new tet: pair them by that edge.
    edges_.reset(boundary_.size() * 3 / 2 + 1);
    std::uint32_t t = kNone;
    std::uint32_t* const v2t = v2t_;
    const std::uint32_t spare = spare_;
    for (const BoundaryFace& b : boundary_) {
      t = new_tet({b.w[0], b.w[1], b.w[2], pid});
      adj(t, 3) = b.outer;
      adj_of(b.outer) = 4 * t + 3;
      // Branch-free like match(): a face met first points at itself until its partner, met
      // later, links the two.
      auto link = [&](std::uint32_t k, std::uint32_t u, std::uint32_t w) __attribute__((always_inline)) {
        const std::uint32_t self = 4 * t + k;
        const std::uint32_t other = edges_.match(u, w, self);
        const std::uint32_t first = opaque(0u - std::uint32_t(other == kNone));  // all ones if so
        adj_of(self) = other;
        adj_of((other & ~first) | (self & first)) = self;  // first: its own slot, rewritten later
      };
      link(0, b.w[1], b.w[2]);
      link(1, b.w[0], b.w[2]);
      link(2, b.w[0], b.w[1]);
      // Branch-free: the infinite vertex (kInf > every id) lands in this worker's spare entry.
      for (int k = 0; k < 3; ++k) v2t[std::min(b.w[k], spare)] = t;
    }
    v2t_[pid] = t;  // every new tet contains p
    last_ = t;
  }

  Store& s_;
  const double* xyz_;
  // The store's arrays, cached (it was once needed against reloads; state's Mark type now
  // prevents those too). refresh() after they grow.
  std::uint32_t* T_ = nullptr;
  Mark* state_ = nullptr;
  std::uint32_t* v2t_ = nullptr;
  const std::uint32_t* ids_;
  std::uint32_t spare_;
  DelaunayStats& stats_;
  Rng rng_;
  Territory terr_;
  Stack<std::uint32_t> free_;
  Stack<std::uint32_t> cavity_;
  Stack<BoundaryFace> boundary_;
  EdgeMap edges_;
  std::uint32_t last_ = 0;
};

/// Removes the holes, the slots on the free list `holes`, by moving the last live tets into
/// them, lowest hole first, in the order the tets come: as many moves as holes below the new
/// end. Sequential insertion leaves no hole (a cavity of k tets is refilled by at least k + 2
/// new ones), so there is nothing to do; parallel runs leave their unused slot ranges (1M
/// cube points: 113k holes in 6.86M slots). The free list says where the holes are, so the
/// tet array is not scanned for them: it was, twice, 0.02 s of a 1.1 s two-thread run.
void compact(Store& s, Stack<std::uint32_t>& holes) {
  if (holes.empty()) return;
  TetRecords& T = s.T;
  const std::size_t m = T.size() / 8;
  const std::size_t live = m - holes.size();
  std::vector<std::uint64_t> hole_bits((live + 63) / 64, 0);  // the holes below live
  for (std::uint32_t h : holes)
    if (h < live) hole_bits[h >> 6] |= std::uint64_t(1) << (h & 63);
  std::vector<std::uint32_t> moved_to(m - live, kNone);  // tail tet t -> moved_to[t - live]
  std::size_t word = 0;
  std::uint64_t bits = hole_bits.empty() ? 0 : hole_bits[0];
  for (std::size_t t = live; t < m; ++t) {
    if (T[8 * t] == kDead) continue;
    while (bits == 0) {  // there are as many holes below live as tets above
      if (++word >= hole_bits.size())
        throw Error("delaunay: free list and tets disagree (internal error)");
      bits = hole_bits[word];
    }
    const std::size_t hole = 64 * word + std::size_t(std::countr_zero(bits));
    bits &= bits - 1;
    std::copy(T.begin() + std::ptrdiff_t(8 * t), T.begin() + std::ptrdiff_t(8 * t + 8),
              T.begin() + std::ptrdiff_t(8 * hole));
    moved_to[t - live] = std::uint32_t(hole);
  }
  for (std::uint32_t h : moved_to) {
    if (h == kNone) continue;
    for (std::uint32_t f = 0; f < 4; ++f) {
      const std::uint32_t a = T[8 * std::size_t(h) + 4 + f];
      std::uint32_t u = a >> 2;
      if (u >= live) u = moved_to[u - live];
      T[8 * std::size_t(h) + 4 + f] = 4 * u + (a & 3);
      T[8 * std::size_t(u) + 4 + (a & 3)] = 4 * h + f;
    }
  }
  T.resize(8 * live);
  holes.clear();
}

/// Moves the records out, without holes (`holes`: the free list), with vertices renumbered to
/// the caller's ids.
Triangulation release(Store& s, Stack<std::uint32_t>& holes, const std::uint32_t* ids, unsigned threads) {
  s.trim();
  compact(s, holes);
  std::uint32_t* T = s.T.data();
  parallel_for(
      s.T.size() / 8,
      [&](std::size_t first, std::size_t last, unsigned) {
        for (std::size_t t = first; t < last; ++t)
          for (std::size_t k = 8 * t; k < 8 * t + 4; ++k)
            if (T[k] != kInf) T[k] = ids[T[k]];
      },
      1 << 16, threads);
  Triangulation tri;
  tri.data = std::move(s.T);
  return tri;
}

constexpr std::uint64_t kWalkSeed = 0x6b646d657368ULL;

/// Points below this many go to the sequential kernel: parallel rounds would not pay.
constexpr std::size_t kMinParallel = 20000;
/// Deferred points left over below this many are inserted sequentially.
constexpr std::size_t kMinRound = 4096;
/// Each parallel round takes the next points of the order up to this many times the points
/// already in, so that the tets straddling slab boundaries are small compared with the domain
/// (1M cube points: 45.5k deferrals with 2, 62.9k with 4).
constexpr std::size_t kRoundGrowth = 2;

/// Slab directions of the parallel rounds: the axes (sorted longest extent first by
/// slab_directions()), then the four diagonals, for point sets whose coordinates tie, e.g.
/// points along the coordinate axes.
using Direction = std::array<double, 3>;
using Directions = std::array<Direction, 7>;

Directions slab_directions(const Store& s, std::size_t first) {
  Directions dirs = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}}};
  std::array<double, 3> lo, hi;
  lo.fill(HUGE_VAL);
  hi.fill(-HUGE_VAL);
  for (std::size_t r = first; r < s.n; ++r)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], s.P(std::uint32_t(r))[a]);
      hi[a] = std::max(hi[a], s.P(std::uint32_t(r))[a]);
    }
  auto extent = [&](const Direction& d) { return along(d, hi.data()) - along(d, lo.data()); };
  std::sort(dirs.begin(), dirs.begin() + 3, [&](const auto& a, const auto& b) { return extent(a) > extent(b); });
  return dirs;
}

/// A round's slabs: the index of their direction in `dirs` and the cuts across it.
struct Slabs {
  std::size_t dir = 0;
  /// cuts[0] = -inf < cuts[1] <= ... < cuts[threads] = +inf; slab w holds the points with
  /// cuts[w] <= dir . x < cuts[w + 1].
  std::vector<double> cuts;
};

/// Picks the direction of a round's slabs, other than the last two rounds' (so that the points
/// deferred near their cuts are away from this one's): the one whose cuts straddle the fewest
/// tets of the current triangulation (a sample of at most ~40k). The cuts are at the round's
/// quantiles, estimated from a sample of at most ~20k of its points, which balances the slabs'
/// counts to within about 1 %; exact quantiles of all the points (nth_element over up to 443k
/// keys at 1M points, on one thread) took 0.01 s of a 1.1 s two-thread run. A straddling tet
/// cannot change during the round, and every point whose cavity reaches it is deferred. On
/// points along the coordinate axes an axis cut runs along two of them; on a cylinder's
/// surface a cut along the axis crosses the long tets through the interior; on a cube any
/// axis will do.
Slabs pick_slabs(const Store& s, const std::vector<std::uint32_t>& todo, const Directions& dirs,
                 const std::array<std::size_t, 2>& recent, unsigned threads) {
  // Only the directions this round may take are measured (5 of the 7 after the second round).
  std::vector<std::size_t> eligible;
  for (std::size_t d = 0; d < dirs.size(); ++d)
    if (d != recent[0] && d != recent[1]) eligible.push_back(d);
  std::vector<std::vector<double>> cuts(dirs.size());
  std::vector<double> key;
  const std::size_t stride = todo.size() / 20000 + 1;
  for (const std::size_t d : eligible) {
    key.clear();
    for (std::size_t i = 0; i < todo.size(); i += stride) key.push_back(along(dirs[d], s.P(todo[i])));
    for (unsigned w = 1; w < threads; ++w) {
      const std::size_t k = std::min(key.size() - 1, key.size() * w / threads);
      std::nth_element(key.begin(), key.begin() + std::ptrdiff_t(k), key.end());
      cuts[d].push_back(key[k]);
    }
  }
  // The sampled tets' counts, summed over the workers' shares (sums: the same on any count).
  const std::size_t m = s.num_tets(), tstride = m / 40000 + 1, samples = (m + tstride - 1) / tstride;
  std::vector<std::array<std::size_t, std::tuple_size_v<Directions>>> part(threads);
  parallel_for(
      samples,
      [&](std::size_t first, std::size_t last, unsigned w) {
        std::array<std::size_t, std::tuple_size_v<Directions>> count{};  // not shared: no false sharing
        const std::size_t end = std::min(last * tstride, m);
        for (std::size_t t = first * tstride; t < end; t += tstride) {
          // Each sample is a cache miss, its vertices four more: start loading the record 16
          // samples ahead and the vertices 8 ahead (their record was requested 8 samples ago).
          // 1M cube points: the seven rounds' samples took 33 ms in all, now 10-15 ms.
          if (t + 16 * tstride < end) __builtin_prefetch(&s.T[8 * (t + 16 * tstride)]);
          if (t + 8 * tstride < end) {
            // A dead slot may hold only its kDead mark (a worker's unused slot): read no further.
            const std::uint32_t* a = &s.T[8 * (t + 8 * tstride)];
            if (a[0] != kDead)
              for (int i = 0; i < 4; ++i)
                if (a[i] < s.n) __builtin_prefetch(s.P(a[i]));
          }
          const std::uint32_t* v = &s.T[8 * t];
          if (v[0] == kDead || v[0] == kInf || v[1] == kInf || v[2] == kInf || v[3] == kInf) continue;
          for (const std::size_t d : eligible) {
            double lo = HUGE_VAL, hi = -HUGE_VAL;
            for (int i = 0; i < 4; ++i) {
              const double x = along(dirs[d], s.P(v[i]));
              lo = std::min(lo, x);
              hi = std::max(hi, x);
            }
            for (double c : cuts[d]) count[d] += lo < c && hi >= c;
          }
        }
        part[w] = count;
      },
      4096, threads);
  std::size_t best = dirs.size(), fewest = 0;
  for (const std::size_t d : eligible) {
    std::size_t straddling = 0;
    for (const auto& p : part) straddling += p[d];
    if (best == dirs.size() || straddling < fewest) best = d, fewest = straddling;
  }
  Slabs slabs{best, {-HUGE_VAL}};
  std::sort(cuts[best].begin(), cuts[best].end());
  slabs.cuts.insert(slabs.cuts.end(), cuts[best].begin(), cuts[best].end());
  slabs.cuts.push_back(HUGE_VAL);
  return slabs;
}

/// Inserts the ranks rank_at(i), i < count, with `k`, looking their hints up a batch at a time:
/// independent loads, where hint_of() at the head of each insertion is a dependent random load
/// (rank_of) that stalls it (1M axes points, one thread: -8%. 1M cube points, two threads,
/// medians of three runs of 5-6 alternations: -2%, -3% and -9%; axes, two threads: no change).
/// Calls failed(rank) for each point `k` puts off and batch_done(size) after each batch.
template <class K, class RankAt, class HintOf, class Failed, class BatchDone>
void insert_batched(K& k, std::size_t count, const RankAt& rank_at, const HintOf& hint_of,
                    const Failed& failed, const BatchDone& batch_done) {
  constexpr std::size_t kHintBatch = 1024;
  std::array<std::uint32_t, kHintBatch> hints;
  for (std::size_t i = 0; i < count; i += kHintBatch) {
    const std::size_t size = std::min(kHintBatch, count - i);
    for (std::size_t j = 0; j < size; ++j) hints[j] = hint_of(rank_at(i + j));
    for (std::size_t j = 0; j < size; ++j)
      if (!k.insert(rank_at(i + j), hints[j])) failed(rank_at(i + j));
    batch_done(size);
  }
}

/// Inserts ranks [first, n) on `threads` workers in rounds. Round r takes the points deferred
/// so far and the next chunk of the order, and cuts them into slabs of about equal count across one
/// direction (the axes in turn, longest extent first, or a diagonal where coordinates tie);
/// each worker inserts its slab's points in order and defers those that need a tet it does not
/// own. Deferred points are near a slab boundary, which the next round moves to another
/// direction. Returns the points still left when
/// rounds stop paying; `seq` inserts them. `hint_of(r)` is the hint of rank r. Deterministic:
/// within a round the tets that straddle a slab boundary cannot change, so each worker's work
/// does not depend on the others' timing.
template <class HintOf, class Report>
std::vector<std::uint32_t> insert_in_rounds(Store& s, Kernel<false>& seq, std::size_t first,
                                            const HintOf& hint_of, const std::uint32_t* ids,
                                            unsigned threads, DelaunayStats& st, const Report& report) {
  const std::size_t n = s.n;
  const Directions dirs = slab_directions(s, first);
  std::vector<DelaunayStats> wstats(threads);
  std::vector<std::unique_ptr<Kernel<true>>> workers;
  for (unsigned w = 0; w < threads; ++w)
    workers.push_back(std::make_unique<Kernel<true>>(s, ids, wstats[w], kWalkSeed + 1 + w,
                                                      std::uint32_t(n + w)));
  workers[0]->free_list().swap(seq.free_list());
  std::vector<std::uint64_t> exact(threads, 0);
  std::vector<std::vector<std::uint32_t>> mine(threads), deferred(threads);
  std::vector<std::uint32_t> todo;
  // Ranks past the current round's last were never placed (a hint may point there: such a
  // point is not inserted yet, so its worker defers the point that asks, as without slabs).
  std::vector<std::uint16_t> slab(n, kNoSlab);
  std::size_t next = first;  // the first rank not yet given to a round
  std::array<std::size_t, 2> recent = {dirs.size(), dirs.size()};  // the last two rounds' (none yet)
  for (int round = 0;; ++round) {
    const std::size_t end = next == n ? n : std::min(n, std::max(next + kMinParallel, next * kRoundGrowth));
    for (std::size_t r = next; r < end; ++r) todo.push_back(std::uint32_t(r));
    next = end;
    if (next == n && todo.size() < kMinRound) break;
    // Slabs of about equal count, across a direction other than the last two rounds'.
    const Slabs slabs = pick_slabs(s, todo, dirs, recent, threads);
    recent = {slabs.dir, recent[0]};
    const Direction& dir = dirs[slabs.dir];
    const std::vector<double>& cuts = slabs.cuts;
    // The slab of every point up to the round's last: the workers' ownership test is then a
    // table lookup per vertex, where a dot product with its coordinates took 6% of the
    // instructions (callgrind, 300k cube points).
    parallel_for(
        end,
        [&](std::size_t first_rank, std::size_t last_rank, unsigned) {
          for (std::size_t r = first_rank; r < last_rank; ++r) {
            const double x = along(dir, s.P(std::uint32_t(r)));
            slab[r] = std::uint16_t(std::upper_bound(cuts.begin() + 1, cuts.end() - 1, x) - cuts.begin() - 1);
          }
        },
        1 << 16, threads);
    for (auto& m : mine) m.clear();
    for (std::uint32_t r : todo) mine[slab[r]].push_back(r);
    // Fresh slots: ~6.7 new tets per point on average, less the free slots the worker holds
    // (from earlier rounds); a worker that runs out defers the rest of its points.
    std::vector<Territory> terr(threads);
    std::size_t base = s.num_tets(), total = 0;
    for (unsigned w = 0; w < threads; ++w) {
      const std::size_t want = mine[w].size() * 7, held = workers[w]->free_list().size();
      const std::size_t slots = (want > held ? want - held : 0) + 1024;
      terr[w] = Territory{slab.data(), std::uint16_t(w), std::uint32_t(base + total),
                          std::uint32_t(base + total + slots)};
      total += slots;
    }
    if ((base + total) * 4 >= (std::size_t(1) << 32))
      throw ResourceError("delaunay: too many tets for 32-bit face references");
    s.add_slots(total);
    auto work = [&](unsigned w) {
      const std::uint64_t exact0 = pred::exact_calls();
      Kernel<true>& k = *workers[w];
      k.enter(terr[w]);
      deferred[w].clear();
      const std::vector<std::uint32_t>& ranks = mine[w];
      insert_batched(
          k, ranks.size(), [&](std::size_t i) { return ranks[i]; }, hint_of,
          [&](std::uint32_t r) { deferred[w].push_back(r); }, [](std::size_t) {});
      k.leave();
      exact[w] += pred::exact_calls() - exact0;
    };
    run_workers(threads, work);
    const std::size_t before = todo.size();
    todo.clear();
    for (const auto& d : deferred) todo.insert(todo.end(), d.begin(), d.end());
    std::sort(todo.begin(), todo.end());
    report(before - todo.size());
    ++st.parallel_rounds;
    st.deferrals += todo.size();
    if (todo.size() * 2 > before) break;  // most points straddle slabs: rounds do not pay
  }
  for (std::size_t r = next; r < n; ++r) todo.push_back(std::uint32_t(r));
  // Hand the free slots back to the sequential kernel, which resumes from a live tet.
  Stack<std::uint32_t>& free = seq.free_list();
  for (unsigned w = 0; w < threads; ++w) {
    free.append(workers[w]->free_list());
    st.inserted += wstats[w].inserted;
    st.orient_tests += wstats[w].orient_tests;
    for (std::size_t b = 0; b < kWalkBins; ++b) {
      st.walks[b] += wstats[w].walks[b];
      st.walk_tests[b] += wstats[w].walk_tests[b];
    }
    st.conflicts += wstats[w].conflicts;
    st.duplicates.insert(st.duplicates.end(), wstats[w].duplicates.begin(), wstats[w].duplicates.end());
    st.duplicate_of.insert(st.duplicate_of.end(), wstats[w].duplicate_of.begin(),
                           wstats[w].duplicate_of.end());
    if (w > 0) st.exact_fallbacks += exact[w];
  }
  seq.set_last(s.v2t[0]);
  return todo;
}

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
  if (options.threads > 256)
    throw UsageError("delaunay: " + std::to_string(options.threads) +
                     " threads requested; at most 256 are supported");
  const unsigned threads =
      options.threads ? options.threads : std::max(1u, std::min(256u, available_cpus()));
  st.threads = threads;
  const std::vector<std::uint32_t>& ids = order.order;
  // Unwritten until the gather below, whose threads first touch their pages.
  std::vector<double, UninitAllocator<double>> ranked(3 * n);
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> rank_of(n);
  parallel_for(  // a gather from the whole input: a memory stall per point
      n,
      [&](std::size_t first, std::size_t last, unsigned) {
        for (std::size_t k = first; k < last; ++k) {
          std::memcpy(&ranked[3 * k], points.p(ids[k]), 3 * sizeof(double));
          rank_of[ids[k]] = std::uint32_t(k);
        }
      },
      1 << 16, threads);
  auto P = [&](std::size_t rank) { return &ranked[3 * rank]; };

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

  Store s;
  s.xyz = ranked.data();
  s.n = n;
  // One spare v2t entry per worker at n, n+1, ...: fill_cavity writes the infinite vertex's
  // "v2t" there.
  s.v2t.assign(n + threads, kNone);
  // Delaunay tetrahedralizations have ~6.76 tets per point for uniform points (6.2-6.5 on
  // surfaces). Reserve 7.5 (8.5 with parallel rounds, whose slot ranges leave gaps): only
  // touched pages become resident, so the reserve costs address space, not memory, while a
  // reallocation would briefly hold two copies (at 5M points a reserve of 6.75 was exceeded by
  // 0.1% and the peak went from ~290 to ~495 bytes/point).
  const std::size_t expect = n * (threads > 1 ? 17 : 15) / 2 + 64;
  s.T.reserve(8 * expect);
  s.state.reserve(expect);
  Kernel<false> kernel(s, ids.data(), st, kWalkSeed, std::uint32_t(n));
  kernel.init(0, b, c, d);
  std::size_t done = 0;
  auto report = [&](std::size_t count) {
    const std::size_t before = done;
    done += count;
    if (options.progress && (before >> 16) != (done >> 16)) options.progress(double(done) / double(n));
  };
  auto hint_of = [&](std::size_t rank) {
    return order.hint[rank] == kNoHint ? kNone : rank_of[order.hint[rank]];
  };
  for (std::uint32_t r : deferred) {
    kernel.insert(r, hint_of(r));
    report(1);
  }
  // Parallel rounds start once the first points (in kd-bfs order: a coarse cover of the
  // domain) are in, so that the tets straddling the slab boundaries are already small.
  const std::size_t prefix = threads > 1 && n - k >= 2 * kMinParallel ? std::max(k, n / 64) : n;
  // Meanwhile the second core makes the pages of the next slots resident (the rounds' workers
  // write about 7 slots a point from here on, in order; a first touch costs them 1.6-2.1 us a
  // page). 1M cube points: about 70 MB of the rounds' 216 MB in the prefix's 26 ms. Should the
  // prefix outgrow the reserve, the ranges are stale; populating keeps contents, so that is
  // harmless.
  std::optional<PageWarmer> warmer;
  if (prefix < n) {
    const std::size_t last = std::min(expect, 7 * n);
    warmer.emplace(std::vector<PageWarmer::Range>{
        {s.state.data() + s.state.size(), s.state.data() + last},
        {s.T.data() + s.T.size(), s.T.data() + 8 * last}});
  }
  insert_batched(
      kernel, prefix - k, [k](std::size_t i) { return std::uint32_t(k + i); }, hint_of,
      [](std::uint32_t) {}, report);
  if (warmer) warmer->stop();
  k = prefix;
  if (k < n) {
    const std::vector<std::uint32_t> todo =
        insert_in_rounds(s, kernel, k, hint_of, ids.data(), threads, st, report);
    for (std::uint32_t r : todo) {
      kernel.insert(r, hint_of(r));
      report(1);
    }
  }
  result.tri = release(s, kernel.free_list(), ids.data(), threads);
  st.exact_fallbacks += pred::exact_calls() - exact0;
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
  Store s;
  s.xyz = points.xyz.data();
  s.n = n;
  s.v2t.assign(n + 1, kNone);
  s.T = std::move(tri.data);
  s.used = s.T.size() / 8;
  s.state.assign(s.num_tets(), kUnvisited);
  // Spare slots for the new tets (about 7 per point), so that the kernel does not grow its
  // arrays by 1/64 of the mesh: that copies every record when the records' capacity is not
  // there already (canonicalize_triangulation keeps the kernel's).
  s.spare_slots(ids.size() * 15 / 2 + 64);
  for (std::size_t t = 0; t < s.num_tets(); ++t)
    for (int i = 0; i < 4; ++i)
      if (s.T[8 * t + i] != kInf) s.v2t[s.T[8 * t + i]] = std::uint32_t(t);
  Kernel<false> kernel(s, identity.data(), stats, kWalkSeed, std::uint32_t(n));
  for (std::size_t k = 0; k < ids.size(); ++k) kernel.insert(ids[k], hints[k]);
  tri = release(s, kernel.free_list(), identity.data(), 1);
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
