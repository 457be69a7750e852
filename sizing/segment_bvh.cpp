// kdmesh — bounding-volume hierarchy over weighted segments: min over i of (w_i + g·d(x, s_i)).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/segment_bvh.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace kdmesh {

double segment_distance(const double* x, const double* a, const double* b) {
  const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double xa[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  double t = dd > 0 ? (xa[0] * d[0] + xa[1] * d[1] + xa[2] * d[2]) / dd : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double r[3] = {xa[0] - t * d[0], xa[1] - t * d[1], xa[2] - t * d[2]};
  return std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
}

namespace {

constexpr std::size_t kLeaf = 8;
constexpr int kMedianDepth = 48;
constexpr int kStack = 128;
constexpr std::uint32_t kCountBits = 5;
constexpr std::uint32_t kCountMask = (1u << kCountBits) - 1;
/// The prune tests' relative margin on squared distances: far above the rounding of the
/// terms' few operations (about 1e-15 relative), so a test fails only for what cannot come
/// below the bound as computed.
constexpr double kSlack = 1 + 1e-9;

/// The largest float <= v (round_up: the smallest float >= v). Beyond the float range this
/// gives +-FLT_MAX or +-inf on the correct side, so the result is still a bound.
float round_down(double v) {
  float f = float(v);
  if (double(f) > v) f = std::nextafter(f, -INFINITY);
  return f;
}
float round_up(double v) {
  float f = float(v);
  if (double(f) < v) f = std::nextafter(f, INFINITY);
  return f;
}

}  // namespace

SegmentBvh::SegmentBvh(const WeightedSegments& in) {
  const std::size_t n = in.size();
  if (n == 0) return;
  if (n >= (std::size_t(1) << (32 - kCountBits)))
    throw UsageError("sizing: too many zone segments (" + std::to_string(n) + "; at most 2^27)");
  std::vector<std::uint32_t> ids(n);
  std::vector<double> centroid(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    ids[i] = std::uint32_t(i);
    for (int k = 0; k < 3; ++k) centroid[3 * i + k] = 0.5 * (in.ab[6 * i + k] + in.ab[6 * i + 3 + k]);
  }
  double scale = 0;
  for (const double v : in.ab) scale = std::max(scale, std::fabs(v));
  // Node boxes grown by far more than a distance's rounding (about 1e-16 of the lengths
  // involved), so that a box's distance never exceeds, as computed, a segment's in it.
  grow_ = 2e-12 * scale;
  nodes_.reserve(n / 2 + 4);
  segs_.reserve(n);
  nodes_.resize(2);  // the root, and an unused slot so that sibling pairs start at even indices
  build(ids, centroid, in, 0, n, 0, 0);
}

void SegmentBvh::build(std::vector<std::uint32_t>& ids, const std::vector<double>& centroid,
                       const WeightedSegments& in, std::size_t begin, std::size_t end,
                       std::size_t slot, int depth) {
  depth_ = std::max(depth_, depth);
  double lo[3], hi[3], clo[3], chi[3], wmin = INFINITY;
  for (int k = 0; k < 3; ++k) {
    lo[k] = clo[k] = INFINITY;
    hi[k] = chi[k] = -INFINITY;
  }
  for (std::size_t i = begin; i < end; ++i) {
    const std::size_t s = ids[i];
    for (int k = 0; k < 3; ++k) {
      const double a = in.ab[6 * s + k], b = in.ab[6 * s + 3 + k];
      lo[k] = std::min({lo[k], a, b});
      hi[k] = std::max({hi[k], a, b});
      clo[k] = std::min(clo[k], centroid[3 * s + k]);
      chi[k] = std::max(chi[k], centroid[3 * s + k]);
    }
    wmin = std::min(wmin, in.weight[s]);
  }
  Node node;
  for (int k = 0; k < 3; ++k) {
    node.lo[k] = round_down(lo[k] - grow_);
    node.hi[k] = round_up(hi[k] + grow_);
  }
  node.wmin = round_down(wmin);
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
  // An inner node whose children hold [begin, mid) and [mid, end).
  auto split_at = [&](std::size_t mid) {
    const std::size_t c = nodes_.size();
    nodes_.resize(c + 2);
    build(ids, centroid, in, begin, mid, c, depth + 1);
    build(ids, centroid, in, mid, end, c + 1, depth + 1);
    node.link = std::uint32_t(c) << kCountBits;
    nodes_[slot] = node;
  };
  if (end - begin <= kLeaf || !(chi[axis] > clo[axis])) {
    // Leaf (also when every centroid coincides: no split would separate them). Such a leaf
    // may exceed kLeaf; split it by count then, so that the count fits its bits.
    if (end - begin > kCountMask) return split_at(begin + (end - begin) / 2);
    node.link = (std::uint32_t(segs_.size()) << kCountBits) | std::uint32_t(end - begin);
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t s = ids[i];
      Seg g;
      double dd = 0;
      for (int k = 0; k < 3; ++k) {
        g.a[k] = in.ab[6 * s + k];
        g.d[k] = in.ab[6 * s + 3 + k] - g.a[k];
        dd += g.d[k] * g.d[k];
      }
      g.inv_dd = dd > 0 ? 1 / dd : 0;
      g.w = in.weight[s];
      segs_.push_back(g);
    }
    nodes_[slot] = node;
    return;
  }
  // Split at the middle of the centroids' longest extent (tighter boxes than a median split on
  // clustered input); at depth >= kMedianDepth, or when one side would be empty, split at the
  // median instead, which bounds the depth by kMedianDepth + log2(n).
  std::size_t mid = begin;
  if (depth < kMedianDepth) {
    const double split = 0.5 * (clo[axis] + chi[axis]);
    const auto it = std::partition(
        ids.begin() + std::ptrdiff_t(begin), ids.begin() + std::ptrdiff_t(end),
        [&](std::uint32_t p) { return centroid[3 * std::size_t(p) + axis] < split; });
    mid = std::size_t(it - ids.begin());
  }
  if (mid == begin || mid == end) {
    mid = begin + (end - begin) / 2;
    std::nth_element(ids.begin() + std::ptrdiff_t(begin), ids.begin() + std::ptrdiff_t(mid),
                     ids.begin() + std::ptrdiff_t(end), [&](std::uint32_t p, std::uint32_t q) {
                       const double cp = centroid[3 * std::size_t(p) + axis];
                       const double cq = centroid[3 * std::size_t(q) + axis];
                       return cp != cq ? cp < cq : p < q;  // total order: deterministic
                     });
  }
  split_at(mid);
}

template <class Leaf, class Keep>
void SegmentBvh::visit(const double* x, Leaf&& leaf, Keep&& keep) const {
  // The stack holds at most one pending sibling per level plus one: depth <= kMedianDepth +
  // log2(2^27) + 1 (the count split of oversized leaves adds at most log2 too), < kStack.
  std::uint32_t stack[kStack];
  double stack_d2[kStack];
  int sp = 0;
  stack[sp] = 0;
  stack_d2[sp++] = box_d2(nodes_[0], x);
  while (sp > 0) {
    --sp;
    const Node& n = nodes_[stack[sp]];
    if (!keep(n.wmin, stack_d2[sp])) continue;  // the bound may have dropped since the push
    const std::uint32_t count = n.link & kCountMask, first = n.link >> kCountBits;
    if (count > 0) {
      for (std::uint32_t i = first; i < first + count; ++i) leaf(i, segs_[i]);
      continue;
    }
    const Node& l = nodes_[first];
    const Node& r = nodes_[first + 1];
    const double dl = box_d2(l, x), dr = box_d2(r, x);
    const bool l_ok = keep(l.wmin, dl), r_ok = keep(r.wmin, dr);
    // Push the farther child first so that the nearer one is visited first.
    if (dl <= dr) {
      if (r_ok) { stack[sp] = first + 1; stack_d2[sp++] = dr; }
      if (l_ok) { stack[sp] = first; stack_d2[sp++] = dl; }
    } else {
      if (l_ok) { stack[sp] = first; stack_d2[sp++] = dl; }
      if (r_ok) { stack[sp] = first + 1; stack_d2[sp++] = dr; }
    }
  }
}

double SegmentBvh::min_value(const double* x, double g, double best, double reach) const {
  if (nodes_.empty()) return best;
  const double inv_g = 1 / g;
  // Could a term w + g·max(0, dist - reach), dist >= sqrt(d2), come below best? (<=> dist <
  // (best - w) / g + reach, when best > w; with the margin.)
  auto may_improve = [&](double w, double d2) {
    const double r = (best - w) * inv_g;
    return r > 0 && d2 <= (r + reach) * (r + reach) * kSlack;
  };
  visit(
      x,
      [&](std::uint32_t, const Seg& s) {
        const double d2 = seg_d2(s, x);
        if (may_improve(s.w, d2)) best = std::min(best, s.w + g * std::max(0.0, std::sqrt(d2) - reach));
      },
      [&](float wmin, double d2) { return may_improve(wmin, d2); });
  return best;
}

double SegmentBvh::min_of(const std::uint32_t* ids, const std::uint16_t* pos, std::size_t n,
                          const double* x, double g, double best) const {
  const double inv_g = 1 / g;
  for (std::size_t i = 0; i < n; ++i) {
    const Seg& s = segs_[ids[pos ? pos[i] : i]];
    const double d2 = seg_d2(s, x);
    const double r = (best - s.w) * inv_g;
    // (min_value's term at reach 0: max(0, sqrt(d2) - 0) is sqrt(d2), bit for bit)
    if (r > 0 && d2 <= r * r * kSlack) best = std::min(best, s.w + g * std::sqrt(d2));
  }
  return best;
}

void SegmentBvh::collect(const double* c, double rho, double g, double cap,
                         std::vector<std::uint32_t>& out) const {
  if (nodes_.empty()) return;
  const double least = min_value(c, g, HUGE_VAL);  // of w + g·d(c, s): below that plus g·rho
  const double bound = std::min(cap, least + g * rho) * kSlack;
  const double inv_g = 1 / g;
  // w + g·max(0, dist - rho) <= bound <=> dist <= (bound - w) / g + rho, when bound >= w.
  auto within = [&](double w, double d2) {
    const double r = (bound - w) * inv_g;
    return r >= 0 && d2 <= (r + rho) * (r + rho) * kSlack;
  };
  const std::size_t begin = out.size();
  visit(
      c,
      [&](std::uint32_t i, const Seg& s) {
        if (within(s.w, seg_d2(s, c))) out.push_back(i);
      },
      [&](float wmin, double d2) { return within(wmin, d2); });
  std::sort(out.begin() + std::ptrdiff_t(begin), out.end());
}

void SegmentBvh::collect_from(const std::uint32_t* ids, const std::uint16_t* pos, std::size_t n,
                              const double* c, double rho, double g, double cap,
                              std::vector<std::uint32_t>& kept) const {
  thread_local std::vector<double> d2;
  d2.resize(n);
  auto seg = [&](std::size_t k) -> const Seg& { return segs_[ids[pos ? pos[k] : k]]; };
  double least = HUGE_VAL;
  for (std::size_t k = 0; k < n; ++k) {
    d2[k] = seg_d2(seg(k), c);
    least = std::min(least, seg(k).w + g * std::sqrt(d2[k]));
  }
  const double bound = std::min(cap, least + g * rho) * kSlack;
  const double inv_g = 1 / g;
  for (std::size_t k = 0; k < n; ++k) {
    const double r = (bound - seg(k).w) * inv_g;
    if (r >= 0 && d2[k] <= (r + rho) * (r + rho) * kSlack) kept.push_back(std::uint32_t(k));
  }
}

}  // namespace kdmesh
