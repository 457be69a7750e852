// kdmesh — bounding-volume hierarchy over weighted segments: min over i of (w_i + g·d(x, s_i)).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace kdmesh {

/// Weighted segments for the sizing field: every zone piece that is a segment or a point
/// (a point is a segment with a == b). Model units throughout.
struct WeightedSegments {
  std::vector<double> ab;      ///< 6 per segment: a(3), b(3)
  std::vector<double> weight;  ///< 1 per segment: the zone size on it (> 0)

  std::size_t size() const { return weight.size(); }
  void push_back(const double* a, const double* b, double w) {
    ab.insert(ab.end(), a, a + 3);
    ab.insert(ab.end(), b, b + 3);
    weight.push_back(w);
  }
};

/// Distance from x to the segment [a, b] (a == b allowed): |x - (a + t (b-a))| with
/// t = clamp(((x-a)·(b-a)) / |b-a|², 0, 1).
double segment_distance(const double* x, const double* a, const double* b);

/// A binary BVH (axis-aligned boxes, split at the middle of the longest centroid extent, or at
/// the median below depth 48 or when the middle separates nothing; leaves of at most 8
/// segments). Each node keeps the least weight below it, so the query prunes a node
/// when w_min + g·dist(x, box) >= the best value so far. Node boxes and weights are floats
/// rounded outward (down for lo and w_min, up for hi), the boxes grown first by 1e-12 of the
/// segments' coordinate scale, and every prune test has a relative margin of 1e-9: a node or
/// segment is skipped only when none of its terms, as computed, can come below the best. So
/// the result is, bit for bit, the least of the terms as min_of() computes them over every
/// segment, whatever the visiting order. The two children of a node are adjacent (one cache
/// line). Immutable; const queries are thread-safe (no scratch state). Holds at most 2^27
/// segments (more throws UsageError).
class SegmentBvh {
 public:
  SegmentBvh() = default;
  explicit SegmentBvh(const WeightedSegments& segments);

  /// min(best, min_i (w_i + g·max(0, d(x, s_i) - reach))) for gradation g > 0 and reach >= 0.
  /// With reach 0 it is the field's value at x; with reach r it is a lower bound of the value
  /// at every point within r of x (d(y, s) >= d(x, s) - r).
  double min_value(const double* x, double g, double best, double reach = 0) const;
  /// min(best, min over the listed segments of w_i + g·d(x, s_i)), each term computed as
  /// min_value() computes it. The segments are ids[pos[k]] for k < n (ids[k] when pos is
  /// null); ids index the tree's own order, as collect() gives them. With a list that holds
  /// every segment that can be least at x, it equals min_value(x, g, best).
  double min_of(const std::uint32_t* ids, const std::uint16_t* pos, std::size_t n,
                const double* x, double g, double best) const;
  /// Appends to `out`, ascending, every segment that can be least somewhere in the ball of
  /// radius rho around c, or that can come below cap there: each s with
  /// w_s + g·max(0, d(c, s) - rho) <= min(cap, min_i (w_i + g·(d(c, s_i) + rho))), with a
  /// relative margin of 1e-9. (A segment left out is, at every point of the ball, above some
  /// listed segment's term or above cap.) The caller's rho must cover its points' rounding.
  void collect(const double* c, double rho, double g, double cap,
               std::vector<std::uint32_t>& out) const;
  /// collect() from a list only: of the listed segments (as for min_of), appends to `kept`
  /// the k < n that collect() keeps, ascending. The same segments as collect()'s when the list
  /// is collect()'s for a ball that holds this one.
  void collect_from(const std::uint32_t* ids, const std::uint16_t* pos, std::size_t n,
                    const double* c, double rho, double g, double cap,
                    std::vector<std::uint32_t>& kept) const;
  std::size_t size() const { return segs_.size(); }
  std::size_t num_nodes() const { return nodes_.size(); }
  /// Levels below the root (0 for a single leaf); at most 48 + log2(size()) + 1 by construction.
  int depth() const { return depth_; }

 private:
  struct Node {  // 32 bytes
    float lo[3], hi[3];
    float wmin;
    std::uint32_t link;  // leaf: first segment << 5 | count (1..16); internal: first child << 5
  };
  struct alignas(64) Seg {  // 64 bytes, in leaf order
    double a[3], d[3];  // d = b - a
    double inv_dd;      // 1 / |d|², 0 for a point
    double w;
  };
  std::vector<Node> nodes_;  // root at 0; children in pairs at (even, odd) indices from 2
  std::vector<Seg> segs_;
  int depth_ = 0;
  double grow_ = 0;  // the node boxes' growth (see the class comment)
  static double seg_d2(const Seg& s, const double* x) {
    const double xa[3] = {x[0] - s.a[0], x[1] - s.a[1], x[2] - s.a[2]};
    double t = (xa[0] * s.d[0] + xa[1] * s.d[1] + xa[2] * s.d[2]) * s.inv_dd;
    t = t < 0 ? 0.0 : t > 1 ? 1.0 : t;
    const double r[3] = {xa[0] - t * s.d[0], xa[1] - t * s.d[1], xa[2] - t * s.d[2]};
    return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  }
  static double box_d2(const Node& n, const double* x) {
    double d2 = 0;  // in double (the float bounds convert exactly)
    for (int k = 0; k < 3; ++k) {
      const double e = std::max(double(n.lo[k]) - x[k], x[k] - double(n.hi[k]));
      d2 += e > 0 ? e * e : 0.0;
    }
    return d2;
  }
  /// Depth-first from the root, nearer child first: leaf(i, seg) for each segment of every
  /// node for which keep(w_min, squared box distance) holds (asked again when popped).
  template <class Leaf, class Keep>
  void visit(const double* x, Leaf&& leaf, Keep&& keep) const;
  void build(std::vector<std::uint32_t>& ids, const std::vector<double>& centroid,
             const WeightedSegments& in, std::size_t begin, std::size_t end, std::size_t slot,
             int depth);
};

}  // namespace kdmesh
