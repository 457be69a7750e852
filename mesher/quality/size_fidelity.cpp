// kdmesh — edge length / target size statistics of a tet mesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/quality/size_fidelity.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace kdmesh {

SizeFidelity measure_size_fidelity(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                   const SizingField& sizing) {
  if (tets.size() % 4 != 0)
    throw UsageError("size fidelity: tet array length " + std::to_string(tets.size()) +
                     " is not a multiple of 4");
  const std::size_t np = points.size();
  std::vector<std::uint64_t> edges;
  edges.reserve(tets.size() / 4 * 6);
  for (std::size_t t = 0; t < tets.size(); t += 4) {
    for (int i = 0; i < 4; ++i) {
      if (tets[t + i] >= np)
        throw UsageError("size fidelity: tet " + std::to_string(t / 4) + " refers to point " +
                         std::to_string(tets[t + i]) + " of " + std::to_string(np));
      for (int j = i + 1; j < 4; ++j) {
        std::uint32_t a = tets[t + i], b = tets[t + j];
        if (a > b) std::swap(a, b);
        edges.push_back(std::uint64_t(a) << 32 | b);
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  SizeFidelity r;
  r.edges = edges.size();
  if (edges.empty()) return r;
  double sum = 0, away_sum = 0;
  std::size_t in = 0, lo = 0, hi = 0;
  const double far = sizing.max_size();
  // The field is exactly h_max where nothing refines it (a min over terms that are all >= it).
  const auto unrefined = [&](const double* x) { return !(sizing(x) < far); };
  r.min_ratio = INFINITY;
  r.max_ratio = 0;
  for (const std::uint64_t e : edges) {
    const double* a = points.p(std::uint32_t(e >> 32));
    const double* b = points.p(std::uint32_t(e));
    const double m[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
    const double length = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    const double hm = sizing(m);
    const double ratio = length / hm;
    sum += ratio;
    if (!(hm < far) && unrefined(a) && unrefined(b)) {
      ++r.away_edges;
      away_sum += length / far;
    }
    if (ratio < 0.7) ++lo;
    else if (ratio > 1.4) ++hi;
    else ++in;
    r.min_ratio = std::min(r.min_ratio, ratio);
    r.max_ratio = std::max(r.max_ratio, ratio);
  }
  const double n = double(edges.size());
  r.mean_ratio = sum / n;
  r.in_range = double(in) / n;
  r.short_fraction = double(lo) / n;
  r.long_fraction = double(hi) / n;
  r.away_mean_ratio = r.away_edges ? away_sum / double(r.away_edges) : 0;
  return r;
}

}  // namespace kdmesh
