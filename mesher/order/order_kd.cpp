// kdmesh — the paper's kd-tree breadth-first insertion order (Sect. 2, Appendix I).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The rule, exactly (tests derive expected orders by hand from it):
//  * A node covers a subset S of m >= 1 points at depth d. The split axis is the axis of
//    largest extent of the axis-aligned bounding box of S (ties: lowest axis, x < y < z);
//    for the alternating variant (kd-bfs-alt) it is d mod 3 and no box is needed.
//  * S is ordered by (coordinate along the axis, point id), a total order. The element at
//    0-based position k = m/2 is the median: it becomes the node. The left child covers the
//    first k elements, the right child the m-k-1 elements after the median. Empty children
//    do not exist.
//  * Nodes are emitted breadth-first (root, then depth 1 left to right, ...). hint = the
//    parent node's point id (kNoHint for the root), level = depth.
//
// Implementation. The shape of the tree depends on n only: a node covering the index range
// [lo, lo+m) of the working array has its median at position lo + m/2 and its children at
// [lo, lo+m/2) and [lo+m/2+1, lo+m). So we
//   1. partition recursively (depth first), recording for each position p the point,
//      parent point and depth of the node whose median lands there, and carrying each
//      child's exact bounding box (one linear scan per child);
//   2. emit breadth first: subtrees occupy disjoint, left-to-right ordered ranges, so the
//      breadth-first order is simply the positions sorted by (depth, position).
// Records carry their coordinates next to the id (32 bytes), so the hot loops never load
// coordinates indirectly. Finding the median ("selection") is the hot spot; large nodes
// use a bucket selection that streams over the records without unpredictable branches:
//   - histogram of the bucket floor((c - min) * B / extent) of every record (B buckets
//     along the axis; the map is monotone, so buckets respect the order by coordinate),
//   - find the bucket holding rank m/2, and scatter the records into a second buffer in
//     three groups: lower buckets, that bucket, higher buckets,
//   - refine inside the middle group the same way until it is small, then finish with
//     std::nth_element and the exact (coordinate, id) comparator (which also settles ties).
// Nodes alternate between the two buffers. Subtrees of at most kTinyNode points are built
// in place with insertion sorts. Below the root the two halves are independent; large
// inputs build them on two threads (the result is identical to a serial run).
// Measured on the 2-core development machine, 1M cube points (bench_orders, kd-bfs-hilbert
// with its Hilbert keys and level sorts): ~0.138 s on one thread, ~0.082 s on two.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/ordering.h"
#include "core/parallel_for.h"
#include "core/point_set.h"
#include "core/uninit_allocator.h"
#include "mesher/order/order_kd.h"

namespace kdmesh::detail {

namespace {

/// A point moving through the partition with its coordinates (no indirect loads).
struct KdPoint {
  double c[3];
  std::uint32_t id;
};

struct Box {
  double lo[3];
  double hi[3];
};

/// Subtrees up to this size are built in place with insertion sorts.
constexpr std::size_t kTinyNode = 8;
/// Bucket selection finishes with std::nth_element once the middle group is this small.
constexpr std::size_t kSmallGroup = 8;
/// Most buckets per bucket round (the histogram lives on the stack).
constexpr std::size_t kMaxBuckets = 2048;
/// Bucket refinement rounds before giving up on (pathological) coordinate spreads.
constexpr int kMaxBucketRounds = 8;
/// Inputs at least this large partition the two halves below the root on two threads.
constexpr std::size_t kThreadThreshold = std::size_t(1) << 16;

/// Two doubles (GCC/Clang vector extension; compiles to SSE2 min/max on x86-64).
typedef double Double2 __attribute__((vector_size(16)));

inline Double2 vmin(Double2 a, Double2 b) { return a < b ? a : b; }
inline Double2 vmax(Double2 a, Double2 b) { return a > b ? a : b; }

/// Exact bounding box of a[0..m), m >= 1. (x, y) as one vector, two interleaved
/// accumulators to hide the latency of min/max: ~40% faster than the plain loop.
Box bounding_box(const KdPoint* a, std::size_t m) {
  Double2 lo0 = {a[0].c[0], a[0].c[1]}, hi0 = lo0, lo1 = lo0, hi1 = lo0;
  double zlo0 = a[0].c[2], zhi0 = zlo0, zlo1 = zlo0, zhi1 = zlo0;
  std::size_t i = 1;
  for (; i + 2 <= m; i += 2) {
    const Double2 p = {a[i].c[0], a[i].c[1]};
    const Double2 q = {a[i + 1].c[0], a[i + 1].c[1]};
    lo0 = vmin(lo0, p);
    hi0 = vmax(hi0, p);
    lo1 = vmin(lo1, q);
    hi1 = vmax(hi1, q);
    const double pz = a[i].c[2], qz = a[i + 1].c[2];
    zlo0 = pz < zlo0 ? pz : zlo0;
    zhi0 = pz > zhi0 ? pz : zhi0;
    zlo1 = qz < zlo1 ? qz : zlo1;
    zhi1 = qz > zhi1 ? qz : zhi1;
  }
  if (i < m) {
    const Double2 p = {a[i].c[0], a[i].c[1]};
    lo0 = vmin(lo0, p);
    hi0 = vmax(hi0, p);
    const double pz = a[i].c[2];
    zlo0 = pz < zlo0 ? pz : zlo0;
    zhi0 = pz > zhi0 ? pz : zhi0;
  }
  lo0 = vmin(lo0, lo1);
  hi0 = vmax(hi0, hi1);
  Box b;
  b.lo[0] = lo0[0];
  b.lo[1] = lo0[1];
  b.lo[2] = zlo0 < zlo1 ? zlo0 : zlo1;
  b.hi[0] = hi0[0];
  b.hi[1] = hi0[1];
  b.hi[2] = zhi0 > zhi1 ? zhi0 : zhi1;
  return b;
}

/// The bounding box of two boxes' points (the comparisons of bounding_box()).
Box enclosing(const Box& a, const Box& b) {
  Box c;
  for (int i = 0; i < 3; ++i) {
    c.lo[i] = b.lo[i] < a.lo[i] ? b.lo[i] : a.lo[i];
    c.hi[i] = b.hi[i] > a.hi[i] ? b.hi[i] : a.hi[i];
  }
  return c;
}

/// Axis of largest extent; ties go to the lowest axis (strict comparisons).
int longest_axis(const Box& b) {
  const double ex = b.hi[0] - b.lo[0];
  const double ey = b.hi[1] - b.lo[1];
  const double ez = b.hi[2] - b.lo[2];
  int axis = 0;
  double best = ex;
  if (ey > best) {
    axis = 1;
    best = ey;
  }
  if (ez > best) axis = 2;
  return axis;
}

/// Strict "less" of the total order (coordinate along axis A, id).
template <int A>
inline bool less_on(const KdPoint& p, const KdPoint& q) {
  return p.c[A] < q.c[A] || (p.c[A] == q.c[A] && p.id < q.id);
}

/// Moves the element of rank k (0-based, in the (c[A], id) order) of a[0..m) to a[k],
/// smaller ones before it, larger ones after it.
template <int A>
void select_in_place(KdPoint* a, std::size_t m, std::size_t k) {
  if (m == 2) {  // k == 1: the larger one must be last
    if (less_on<A>(a[1], a[0])) std::swap(a[0], a[1]);
  } else if (m == 3) {  // k == 1: sort three
    if (less_on<A>(a[1], a[0])) std::swap(a[0], a[1]);
    if (less_on<A>(a[2], a[1])) std::swap(a[1], a[2]);
    if (less_on<A>(a[1], a[0])) std::swap(a[0], a[1]);
  } else if (m > 3) {
    std::nth_element(a, a + k, a + m,
                     [](const KdPoint& p, const KdPoint& q) { return less_on<A>(p, q); });
  }
}

/// One bucket round: histogram of in[0..m) over B buckets spanning [lo, lo + extent]
/// (bucketable) along axis A, then scatter into out[0..m) as [lower buckets | the bucket
/// holding rank k | higher buckets]. Returns the middle group as [r0, r1) (r0 <= k < r1).
template <int A>
void bucket_round(const KdPoint* in, KdPoint* out, std::size_t m, std::size_t k, double lo,
                  double extent, std::size_t& r0, std::size_t& r1) {
  // B ~ m (a power of two, at most kMaxBuckets): the middle group of smooth data is tiny.
  const std::uint32_t B =
      std::uint32_t(std::clamp<std::size_t>(std::bit_floor(m), 16, kMaxBuckets));
  const double scale = double(B) / extent;
  const double top = double(B - 1);
  // (c - lo) * scale is monotone in c, so the bucket index is monotone in c.
  auto bucket = [&](const KdPoint& p) {
    const double f = (p.c[A] - lo) * scale;
    return std::uint32_t(f < top ? f : top);
  };
  std::uint32_t hist[kMaxBuckets];
  std::fill(hist, hist + B, 0u);
  for (std::size_t i = 0; i < m; ++i) ++hist[bucket(in[i])];
  std::size_t below = 0;
  std::uint32_t beta = 0;
  while (below + hist[beta] <= k) below += hist[beta++];
  // Branch-free three-way scatter (the group of each record is unpredictable).
  std::size_t cursor[3] = {0, below, below + hist[beta]};
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t b = bucket(in[i]);
    const unsigned group = unsigned(b >= beta) + unsigned(b > beta);  // 0: <, 1: =, 2: >
    out[cursor[group]++] = in[i];
  }
  r0 = below;
  r1 = below + hist[beta];
}

/// Whether coordinates spanning [lo, hi] can be bucketed: a positive extent, and neither
/// the extent nor the bucket scale overflows (huge or subnormal spreads are left to
/// std::nth_element).
inline bool bucketable(double lo, double hi) {
  const double extent = hi - lo;
  constexpr double kMax = std::numeric_limits<double>::max();
  return extent > 0 && extent <= kMax && double(kMaxBuckets) / extent <= kMax;
}

/// Selection of rank k of src[0..m) along axis A; the coordinates along A
/// span [lo, hi]. The result (as for select_in_place) is left in dst[0..m); src is scratch.
template <int A>
void bucket_select(KdPoint* src, KdPoint* dst, std::size_t m, std::size_t k, double lo,
                   double hi) {
  if (!bucketable(lo, hi)) {  // e.g. all coordinates equal along A: order by id alone
    std::memcpy(static_cast<void*>(dst), src, m * sizeof(KdPoint));
    select_in_place<A>(dst, m, k);
    return;
  }
  std::size_t r0, r1;
  bucket_round<A>(src, dst, m, k, lo, hi - lo, r0, r1);
  for (int round = 1;; ++round) {
    const std::size_t len = r1 - r0;
    KdPoint* region = dst + r0;
    if (len > kSmallGroup && round < kMaxBucketRounds) {
      double mn = region[0].c[A], mx = mn;
      for (std::size_t i = 1; i < len; ++i) {
        const double v = region[i].c[A];
        mn = v < mn ? v : mn;
        mx = v > mx ? v : mx;
      }
      if (bucketable(mn, mx)) {  // refine: scatter the middle through src and copy back
        std::size_t s0, s1;
        bucket_round<A>(region, src + r0, len, k - r0, mn, mx - mn, s0, s1);
        std::memcpy(static_cast<void*>(region), src + r0, len * sizeof(KdPoint));
        r1 = r0 + s1;
        r0 = r0 + s0;
        continue;
      }
    }
    select_in_place<A>(region, len, k - r0);
    return;
  }
}

/// Per-position output of the build: the node whose median sits at position p of the
/// working array has point ids[p], parent point parents[p] and depth depths[p].
struct NodeArrays {
  std::uint32_t* ids;
  std::uint32_t* parents;
  std::uint8_t* depths;

  void set(std::size_t p, std::uint32_t id, std::uint32_t parent, unsigned depth) const {
    ids[p] = id;
    parents[p] = parent;
    depths[p] = std::uint8_t(depth);
  }
};

class KdBuilder {
 public:
  KdBuilder(bool alternate, NodeArrays out) : alternate_(alternate), out_(out) {}

  /// Builds the subtree of the node covering positions [lo, lo+m): its records are in
  /// data[lo, lo+m) and other[lo, lo+m) is free scratch. `parent` is the parent node's
  /// point (kNoHint for the root) and `box` the exact bounding box of the node's points
  /// (unused by the alternating rule).
  void build(KdPoint* data, KdPoint* other, std::size_t lo, std::size_t m, unsigned depth,
             std::uint32_t parent, Box box, bool allow_thread) const {
    while (m > 1) {
      if (m <= kTinyNode) {
        build_tiny(data, lo, m, depth, parent, box);
        return;
      }
      const int axis = alternate_ ? int(depth % 3) : longest_axis(box);
      const std::size_t k = m / 2;
      select(data + lo, other + lo, m, k, axis, box);  // the node's records move to `other`
      KdPoint* result = other;
      KdPoint* scratch = data;
      KdPoint* node = result + lo;
      const std::uint32_t id = node[k].id;
      out_.set(lo + k, id, parent, depth);
      const std::size_t mr = m - k - 1;
      // Exact child boxes: one scan each, only for children that will be split again.
      Box left_box{}, right_box{};
      if (!alternate_) {
        if (k > 1) left_box = bounding_box(node, k);
        if (mr > 1) right_box = bounding_box(node + k + 1, mr);
      }
      if (allow_thread && m >= kThreadThreshold) {
        // The halves use disjoint ranges of all arrays: building the left one on a second
        // thread gives exactly the serial result.
        try {
          std::thread left(
              [&] { build(result, scratch, lo, k, depth + 1, id, left_box, false); });
          build(result, scratch, lo + k + 1, mr, depth + 1, id, right_box, false);
          left.join();
          return;
        } catch (const std::system_error&) {
          // No thread available: fall through to the serial path.
        }
      }
      // Recurse into the left child, iterate on the right one (bounded stack depth).
      build(result, scratch, lo, k, depth + 1, id, left_box, false);
      data = result;
      other = scratch;
      lo += k + 1;
      m = mr;
      ++depth;
      parent = id;
      box = right_box;
    }
    if (m == 1) out_.set(lo, data[lo].id, parent, depth);
  }

 private:
  /// The same for m <= kTinyNode, in place: each node is fully sorted by insertion sort.
  void build_tiny(KdPoint* data, std::size_t lo, std::size_t m, unsigned depth,
                  std::uint32_t parent, Box box) const {
    while (m > 1) {
      KdPoint* a = data + lo;
      switch (alternate_ ? int(depth % 3) : longest_axis(box)) {
        case 0: insertion_sort<0>(a, m); break;
        case 1: insertion_sort<1>(a, m); break;
        default: insertion_sort<2>(a, m); break;
      }
      const std::size_t k = m / 2;
      const std::uint32_t id = a[k].id;
      out_.set(lo + k, id, parent, depth);
      const std::size_t mr = m - k - 1;
      if (k == 1) {
        out_.set(lo, a[0].id, id, depth + 1);
      } else {
        build_tiny(data, lo, k, depth + 1, id, alternate_ ? Box{} : bounding_box(a, k));
      }
      if (mr > 1 && !alternate_) box = bounding_box(a + k + 1, mr);
      lo += k + 1;
      m = mr;
      ++depth;
      parent = id;
    }
    if (m == 1) out_.set(lo, data[lo].id, parent, depth);
  }

  template <int A>
  static void insertion_sort(KdPoint* a, std::size_t m) {
    for (std::size_t i = 1; i < m; ++i) {
      const KdPoint p = a[i];
      std::size_t j = i;
      for (; j > 0 && less_on<A>(p, a[j - 1]); --j) a[j] = a[j - 1];
      a[j] = p;
    }
  }

  /// Selects rank k of a[0..m) along `axis` (see bucket_select); the result is in b[0..m).
  void select(KdPoint* a, KdPoint* b, std::size_t m, std::size_t k, int axis,
              const Box& box) const {
    double lo, hi;
    if (alternate_) {  // no box: find the range along the axis
      lo = hi = a[0].c[axis];
      for (std::size_t i = 1; i < m; ++i) {
        const double v = a[i].c[axis];
        lo = v < lo ? v : lo;
        hi = v > hi ? v : hi;
      }
    } else {
      lo = box.lo[axis];
      hi = box.hi[axis];
    }
    switch (axis) {
      case 0: bucket_select<0>(a, b, m, k, lo, hi); break;
      case 1: bucket_select<1>(a, b, m, k, lo, hi); break;
      default: bucket_select<2>(a, b, m, k, lo, hi); break;
    }
  }

  bool alternate_;
  NodeArrays out_;
};

}  // namespace

Ordering make_kd_order(const PointSet& points, bool alternate, unsigned threads) {
  Ordering out;
  const std::size_t n = points.size();
  const bool two_threads = threads != 1 && n >= kThreadThreshold;
  if (n == 0) return out;
  if (n >= std::size_t(kNoHint)) throw UsageError("kd order: too many points for 32-bit ids");

  // 1. Records (x, y, z, id) in the working buffer; a second buffer for the scatters.
  //    Default-initialised arrays: no zeroing pass. First touching 64 MB for 1M points
  //    costs as much as a few tree levels (page faults), so large inputs split the copy
  //    and the first touch of the scratch buffer between two threads. Each part takes the
  //    bounding box of its records a block at a time, while the block is in the cache: the
  //    root's box without another pass over all of them.
  const unsigned parts = two_threads ? 2 : 1;
  const std::size_t bound[3] = {0, parts == 2 ? n / 2 : n, n};
  std::unique_ptr<KdPoint[]> work(new KdPoint[n]);
  std::unique_ptr<KdPoint[]> scratch(new KdPoint[n]);
  const double* xyz = points.xyz.data();
  Box part_box[2] = {};
  run_workers(parts, [&](unsigned w) {
    constexpr std::size_t kBlock = 2048;  // 64 KB of records
    for (std::size_t begin = bound[w]; begin < bound[w + 1]; begin += kBlock) {
      const std::size_t end = std::min(bound[w + 1], begin + kBlock);
      for (std::size_t i = begin; i < end; ++i)
        work[i] = KdPoint{{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}, std::uint32_t(i)};
      if (alternate) continue;  // no boxes
      const Box b = bounding_box(work.get() + begin, end - begin);
      part_box[w] = begin == bound[w] ? b : enclosing(part_box[w], b);
    }
    constexpr std::size_t kPerPage = 4096 / sizeof(KdPoint);
    for (std::size_t i = bound[w]; i < bound[w + 1]; i += kPerPage) scratch[i].id = 0;
  });
  const Box root_box = parts == 2 ? enclosing(part_box[0], part_box[1]) : part_box[0];
  // Written at every position by the build (each position holds exactly one node): no
  // zeroing pass, and the halves' threads first touch their own parts.
  std::vector<std::uint32_t, UninitAllocator<std::uint32_t>> ids(n), parents(n);
  std::vector<std::uint8_t, UninitAllocator<std::uint8_t>> depths(n);
  const KdBuilder builder(alternate, NodeArrays{ids.data(), parents.data(), depths.data()});
  builder.build(work.get(), scratch.get(), 0, n, 0, kNoHint, root_box, two_threads);

  // 2. Breadth-first order. Subtrees occupy disjoint, left-to-right ordered position
  //    ranges, so the nodes of one depth appear left to right in increasing position: the
  //    breadth-first order is the positions sorted by (depth, position), a counting sort.
  //    (Depths are below 32 since n < 2^32.) With two threads each half of the positions is
  //    placed by its own thread: a depth's nodes in the first half come before those in the
  //    second, so the first half's run of each depth starts at the depth's start and the
  //    second's after it. The same result as one pass.
  constexpr int kDepths = 34;
  std::size_t next[2][kDepths] = {};  // per part: its count per depth, then its next rank
  out.order.resize(n);
  out.hint.resize(n);
  out.level.resize(n);
  run_workers(parts, [&](unsigned w) {
    // The records are done with; releasing each buffer (unmapping 32 bytes a point) is a
    // thread's work too.
    if (w == 0) work.reset();
    if (w + 1 == parts) scratch.reset();
    for (std::size_t p = bound[w]; p < bound[w + 1]; ++p) ++next[w][depths[p]];
  });
  for (std::size_t d = 0, rank = 0; d < kDepths; ++d)
    for (unsigned w = 0; w < parts; ++w) rank += std::exchange(next[w][d], rank);
  run_workers(parts, [&](unsigned w) {
    std::size_t* const at = next[w];
    for (std::size_t p = bound[w]; p < bound[w + 1]; ++p) {
      const std::size_t r = at[depths[p]]++;
      out.order[r] = ids[p];
      out.hint[r] = parents[p];
      out.level[r] = depths[p];
    }
  });
  return out;
}

}  // namespace kdmesh::detail
