// kdmesh — how a batch's jobs are spread (tools/app/batch_schedule.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/batch_schedule.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "io/surface_io.h"

namespace kdmesh {

namespace {

/// Bounding-box extent (largest side) and facet count of one surface file; {0, 0} if unreadable.
std::pair<double, double> extent_and_facets(const std::string& path) {
  try {
    const SurfaceMesh s = read_surface(path);
    if (s.points.size() == 0) return {0, 0};
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = s.points.p(0)[k];
    for (std::size_t i = 0; i < s.points.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], s.points.p(std::uint32_t(i))[k]);
        hi[k] = std::max(hi[k], s.points.p(std::uint32_t(i))[k]);
      }
    return {std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}), double(s.num_tris())};
  } catch (const Error&) {
    return {0, 0};
  }
}

}  // namespace

std::vector<double> estimate_job_costs(const std::vector<MeshJob>& jobs) {
  std::vector<double> cost(jobs.size(), 0);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const MeshJob& j = jobs[i];
    std::vector<std::string> inputs;
    if (j.bodies.empty()) inputs.push_back(j.input);
    for (const BodyInput& b : j.bodies) inputs.push_back(b.input);
    for (const std::string& in : inputs) {
      const auto [extent, facets] = extent_and_facets(in);
      const double cells = j.sizing.max_size > 0 ? extent * j.scale / j.sizing.max_size : 0;
      const double c = cells * cells * cells + facets;
      if (std::isfinite(c)) cost[i] += c;
    }
  }
  return cost;
}

std::vector<std::size_t> largest_first(const std::vector<double>& costs) {
  std::vector<std::size_t> order(costs.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return costs[a] > costs[b]; });
  return order;
}

Shard parse_shard(const std::string& text, const std::string& what) {
  const std::size_t slash = text.find('/');
  Shard s;
  auto number = [&](const char* b, const char* e, std::size_t& out) {
    const auto r = std::from_chars(b, e, out);
    return b != e && r.ec == std::errc() && r.ptr == e;
  };
  const char* t = text.data();
  if (slash == std::string::npos || !number(t, t + slash, s.index) || !number(t + slash + 1, t + text.size(), s.count) ||
      s.count == 0 || s.index >= s.count)
    throw UsageError(what + " '" + text + "': expected i/N with 0 <= i < N, e.g. 0/4 (Slurm: " +
                     "$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT with --array=0-3)");
  return s;
}

std::vector<std::size_t> shard_jobs(const std::vector<double>& costs, Shard s) {
  std::vector<double> load(s.count, 0);
  std::vector<std::size_t> mine;
  for (const std::size_t j : largest_first(costs)) {
    const std::size_t to = std::size_t(std::min_element(load.begin(), load.end()) - load.begin());
    load[to] += std::max(costs[j], 1.0);  // every job counts, so that free ones spread too
    if (to == s.index) mine.push_back(j);
  }
  std::sort(mine.begin(), mine.end());
  return mine;
}

}  // namespace kdmesh
