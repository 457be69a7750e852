// kdmesh — insertion orders: dispatch, names, and the hilbert / brio / random / input orders.
// The kd-tree orders live in order_kd*.cpp, Hilbert keys in order_hilbert.cpp.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Definitions (all deterministic for given points and options):
//  * input:   order[k] = k.
//  * random:  Fisher-Yates shuffle of 0..n-1 with Rng(seed): for i = n-1 down to 1,
//             swap(a[i], a[Rng::below(i + 1)]).
//  * hilbert: ids sorted by (Hilbert key, id); keys over the bounding cube of the set with
//             2^21 cells per axis (see mesher/order/hilbert.h).
//  * brio:    the random shuffle above, then rounds. Boundaries b0 = n and
//             b_{i+1} = floor(b_i * brio_ratio) as long as b_{i+1} >= 1024; the shuffled
//             positions [b_{i+1}, b_i) form a round, and [0, b_last) the first round. Each
//             round is sorted by (Hilbert key, id), keys over the whole set's bounding cube;
//             rounds are emitted smallest (first) to largest (last).
// For all of these hint[k] = order[k-1] (kNoHint for k = 0) and `level` is empty.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "mesher/order/hilbert.h"
#include "mesher/order/order.h"
#include "mesher/order/order_kd.h"

namespace kdmesh {


namespace {

struct KindName {
  OrderKind kind;
  const char* name;
};

constexpr KindName kKinds[] = {
    {OrderKind::kd_bfs, "kd-bfs"}, {OrderKind::kd_bfs_alt, "kd-bfs-alt"},
    {OrderKind::kd_bfs_hilbert, "kd-bfs-hilbert"}, {OrderKind::kd_local, "kd-local"},
    {OrderKind::hilbert, "hilbert"}, {OrderKind::brio, "brio"},
    {OrderKind::random, "random"},   {OrderKind::input, "input"},
};

/// Smallest round size kept separate by brio (rounds shrink by brio_ratio until below it).
constexpr std::size_t kBrioMinRound = 1024;

/// hint[k] = order[k-1], kNoHint for k = 0.
void previous_point_hints(Ordering& o) {
  o.hint.resize(o.order.size());
  if (o.order.empty()) return;
  o.hint[0] = kNoHint;
  for (std::size_t k = 1; k < o.order.size(); ++k) o.hint[k] = o.order[k - 1];
}

std::vector<std::uint32_t> identity(std::size_t n) {
  std::vector<std::uint32_t> a(n);
  std::iota(a.begin(), a.end(), std::uint32_t(0));
  return a;
}

/// Fisher-Yates with Rng(seed): for i = n-1 .. 1, swap a[i] with a[below(i+1)].
std::vector<std::uint32_t> shuffled(std::size_t n, std::uint64_t seed) {
  std::vector<std::uint32_t> a = identity(n);
  Rng rng(seed);
  for (std::size_t i = n; i-- > 1;) {
    const std::size_t j = std::size_t(rng.below(i + 1));
    std::swap(a[i], a[j]);
  }
  return a;
}

void check_points(const PointSet& points) {
  if (points.xyz.size() % 3 != 0) throw UsageError("point array length is not a multiple of 3");
  if (points.size() >= std::size_t(kNoHint)) {
    throw UsageError("too many points for 32-bit ids: " + std::to_string(points.size()));
  }
  for (const double v : points.xyz) {
    if (!std::isfinite(v)) throw GeometryError("point coordinates must be finite");
  }
}

/// Round boundaries of brio, b0 = n > b1 > ... > b_last (see the file comment).
std::vector<std::size_t> brio_boundaries(std::size_t n, double ratio) {
  std::vector<std::size_t> b{n};
  for (;;) {
    const std::size_t next = std::size_t(std::floor(double(b.back()) * ratio));
    if (next < kBrioMinRound || next >= b.back()) break;
    b.push_back(next);
  }
  return b;
}

}  // namespace

Ordering make_order(const PointSet& points, const OrderOptions& options) {
  check_points(points);
  const std::size_t n = points.size();
  Ordering out;
  switch (options.kind) {
    case OrderKind::kd_bfs:
      out = detail::make_kd_order(points, false, options.threads);
      break;
    case OrderKind::kd_bfs_alt:
      out = detail::make_kd_order(points, true, options.threads);
      break;
    case OrderKind::kd_bfs_hilbert:
      out = detail::make_kd_hilbert_order(points, options.threads);
      break;
    case OrderKind::kd_local:
      if (options.local_points == 0) throw UsageError("kd-local subtree size must be positive");
      out = detail::make_kd_local_order(detail::make_kd_order(points, false, options.threads),
                                       options.local_points);
      break;
    case OrderKind::hilbert: {
      out.order = identity(n);
      const std::vector<std::uint64_t> keys = hilbert::point_keys(points);
      hilbert::sort_ids_by_key(out.order.data(), n, keys.data());
      previous_point_hints(out);
      break;
    }
    case OrderKind::brio: {
      if (!(options.brio_ratio > 0.0 && options.brio_ratio < 1.0)) {
        throw UsageError("brio ratio must be in (0, 1), got " +
                         std::to_string(options.brio_ratio));
      }
      out.order = shuffled(n, options.seed);
      if (n > 0) {
        const std::vector<std::uint64_t> keys = hilbert::point_keys(points);
        const std::vector<std::size_t> b = brio_boundaries(n, options.brio_ratio);
        // Rounds [b[i+1], b[i]) plus [0, b.back()); sorting each in place keeps them in
        // ascending position order, i.e. smallest round first.
        hilbert::sort_ids_by_key(out.order.data(), b.back(), keys.data());
        for (std::size_t i = 0; i + 1 < b.size(); ++i) {
          hilbert::sort_ids_by_key(out.order.data() + b[i + 1], b[i] - b[i + 1], keys.data());
        }
      }
      previous_point_hints(out);
      break;
    }
    case OrderKind::random:
      out.order = shuffled(n, options.seed);
      previous_point_hints(out);
      break;
    case OrderKind::input:
      out.order = identity(n);
      previous_point_hints(out);
      break;
    default:
      throw UsageError("unknown order kind");
  }
  out.name = std::string(order_kind_name(options.kind));
  return out;
}

OrderKind parse_order_kind(std::string_view name) {
  for (const KindName& k : kKinds) {
    if (name == k.name) return k.kind;
  }
  std::string valid;
  for (const KindName& k : kKinds) valid += (valid.empty() ? "" : ", ") + std::string(k.name);
  throw UsageError("unknown order '" + std::string(name) + "' (valid: " + valid + ")");
}

std::string_view order_kind_name(OrderKind kind) {
  for (const KindName& k : kKinds) {
    if (kind == k.kind) return k.name;
  }
  throw UsageError("unknown order kind " + std::to_string(int(kind)));
}

std::vector<std::string> order_kind_names() {
  std::vector<std::string> names;
  for (const KindName& k : kKinds) names.emplace_back(k.name);
  return names;
}

}  // namespace kdmesh
