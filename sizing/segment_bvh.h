// kdmesh — bounding-volume hierarchy over weighted segments: min over i of (w_i + g·d(x, s_i)).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
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
/// rounded outward (down for lo and w_min, up for hi), so the bounds stay conservative and the
/// result equals the brute-force minimum; the two children of a node are adjacent (one cache
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
  void build(std::vector<std::uint32_t>& ids, const std::vector<double>& centroid,
             const WeightedSegments& in, std::size_t begin, std::size_t end, std::size_t slot,
             int depth);
};

}  // namespace kdmesh
