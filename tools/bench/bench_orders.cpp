// Benchmark: building each insertion order for 1M points of the cube and axes distributions.
// Times are wall-clock, on one thread (/t1) and on two (/t2: the kd orders use a second thread
// below the root).
// Usage: bench_orders [--benchmark_filter=kd] [other Google Benchmark flags]
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/point_set.h"
#include "mesher/order/order.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {
namespace {

constexpr std::size_t kPoints = 1000000;
constexpr std::uint64_t kSeed = 1;

/// Points generated once per distribution and shared by every benchmark.
const PointSet& points(Distribution d) {
  static const PointSet cube = generate_points(Distribution::cube, kPoints, kSeed);
  static const PointSet axes = generate_points(Distribution::axes, kPoints, kSeed);
  return d == Distribution::cube ? cube : axes;
}

void bench_order(benchmark::State& state, Distribution d, OrderKind kind, unsigned threads) {
  const PointSet& ps = points(d);
  OrderOptions options;
  options.kind = kind;
  options.seed = kSeed;
  options.threads = threads;
  for (auto _ : state) {
    Ordering o = make_order(ps, options);
    benchmark::DoNotOptimize(o.order.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(ps.size()));
}

const int registered = [] {
  for (const Distribution d : {Distribution::cube, Distribution::axes}) {
    for (const std::string& name : order_kind_names()) {
      const OrderKind kind = parse_order_kind(name);
      for (const unsigned threads : {1u, 2u}) {
        const std::string label = "order/" + name + "/" + std::string(distribution_name(d)) +
                                  "/1M/t" + std::to_string(threads);
        benchmark::RegisterBenchmark(label.c_str(), [d, kind, threads](benchmark::State& s) {
          bench_order(s, d, kind, threads);
        })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinTime(0.5);
      }
    }
  }
  return 0;
}();

}  // namespace
}  // namespace kdmesh

BENCHMARK_MAIN();
