// kdmesh — benchmark of sizing-field evaluation (single thread, evaluations per second).
// Two surfaces with ~10k sharp feature edges each:
//  - "pins": 80 closed cylinders (64 sides, radius 1, height 6) on a 10 x 8 lattice of pitch 5
//    in a 50 x 40 x 6 block: 80 x 128 = 10,240 rim edges (the 5.6° side edges are not sharp),
//    i.e. many separate fine feature curves, as in a part with many holes;
//  - "star": a 3,400-gon prism zig-zagging between radii 20 and 18 (height 40, caps fanned from
//    the axis): 3,400 vertical and 6,800 rim edges, all sharp and 0.035 apart, a worst case in
//    which thousands of nearly equidistant edges must be ruled out.
// Queries are 2^20 points uniform in the bounding box grown by 2, either in random order or
// sorted along a Morton curve (coherent, as node placement queries neighbouring points).
// Usage: bench_sizing [--benchmark_filter=pins] [other Google Benchmark flags]
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "core/surface_mesh.h"
#include "sizing/features.h"
#include "sizing/sizing_field.h"

namespace kdmesh {
namespace {

/// A closed prism over the polygon (x, y pairs, counter-clockwise, star-shaped from (cx, cy)),
/// z in [z0, z1], caps fanned from their centres; appended to s.
void add_prism(SurfaceMesh& s, const std::vector<double>& xy, double cx, double cy, double z0,
               double z1) {
  const std::uint32_t b = std::uint32_t(s.points.size()), n = std::uint32_t(xy.size() / 2);
  for (const double z : {z0, z1})
    for (std::uint32_t i = 0; i < n; ++i) s.points.push_back(xy[2 * i], xy[2 * i + 1], z);
  s.points.push_back(cx, cy, z0);
  s.points.push_back(cx, cy, z1);
  const std::uint32_t c0 = b + 2 * n, c1 = c0 + 1;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t p = b + i, q = b + (i + 1) % n;
    s.tris.insert(s.tris.end(), {c0, q, p});                  // bottom, normal -z
    s.tris.insert(s.tris.end(), {c1, p + n, q + n});          // top, normal +z
    s.tris.insert(s.tris.end(), {p, q, q + n, p, q + n, p + n});  // side, outward
  }
}

struct Scene {
  SurfaceMesh surface;
  double lo[3], hi[3];  // query box
  SizingOptions options;
};

SizingZone make_zone(SizingZone::Kind kind, double size, std::vector<double> coords) {
  SizingZone z;
  z.kind = kind;
  z.size = size;
  z.coords = std::move(coords);
  return z;
}

/// h_max 4, g 0.3; sharp edges at 0.5, two planes, one segment.
Scene pins() {
  Scene sc;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 8; ++j) {
      const double cx = 2.5 + 5 * i, cy = 2.5 + 5 * j;
      std::vector<double> xy;
      for (int k = 0; k < 64; ++k) {
        const double a = 2 * std::numbers::pi * k / 64;
        xy.insert(xy.end(), {cx + std::cos(a), cy + std::sin(a)});
      }
      add_prism(sc.surface, xy, cx, cy, 0, 6);
    }
  sc.lo[0] = sc.lo[1] = sc.lo[2] = -2;
  sc.hi[0] = 52, sc.hi[1] = 42, sc.hi[2] = 8;
  sc.options.max_size = 4;
  sc.options.gradation = 0.3;
  sc.options.zones = {make_zone(SizingZone::Kind::sharp_edges, 0.5, {}),
                      make_zone(SizingZone::Kind::plane, 0.4, {0, 0, 3, 0, 0, 1}),
                      make_zone(SizingZone::Kind::plane, 0.6, {12.5, 0, 0, 1, 0.2, 0}),
                      make_zone(SizingZone::Kind::segment, 0.3, {0, 0, 1, 50, 40, 5})};
  return sc;
}

Scene star() {
  Scene sc;
  constexpr std::uint32_t n = 3400;
  std::vector<double> xy;
  for (std::uint32_t i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n, r = i % 2 ? 18 : 20;
    xy.insert(xy.end(), {r * std::cos(a), r * std::sin(a)});
  }
  add_prism(sc.surface, xy, 0, 0, 0, 40);
  sc.lo[0] = sc.lo[1] = -22, sc.lo[2] = -2;
  sc.hi[0] = sc.hi[1] = 22, sc.hi[2] = 42;
  sc.options.max_size = 4;
  sc.options.gradation = 0.3;
  sc.options.zones = {make_zone(SizingZone::Kind::sharp_edges, 0.5, {}),
                      make_zone(SizingZone::Kind::plane, 0.4, {0, 0, 20, 0, 0, 1}),
                      make_zone(SizingZone::Kind::plane, 0.6, {3, 0, 0, 1, 0.2, 0}),
                      make_zone(SizingZone::Kind::segment, 0.3, {-10, -10, 5, 10, 10, 35})};
  return sc;
}

const Scene& scene(bool is_star) {
  static const Scene p = pins(), s = star();
  return is_star ? s : p;
}

/// 2^20 uniform points in the scene's box; Morton-sorted (10 bits per axis) if coherent.
std::vector<double> make_queries(const Scene& sc, bool coherent) {
  std::vector<std::array<double, 3>> q(1 << 20);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  for (auto& p : q)
    for (int k = 0; k < 3; ++k) p[k] = sc.lo[k] + (sc.hi[k] - sc.lo[k]) * u(rng);
  if (coherent) {
    auto key = [&](const std::array<double, 3>& p) {
      std::uint64_t m = 0;
      std::uint32_t c[3];
      for (int k = 0; k < 3; ++k) c[k] = std::uint32_t((p[k] - sc.lo[k]) / (sc.hi[k] - sc.lo[k]) * 1023);
      for (int bit = 9; bit >= 0; --bit)
        for (int k = 0; k < 3; ++k) m = (m << 1) | ((c[k] >> bit) & 1);
      return m;
    };
    std::sort(q.begin(), q.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  }
  std::vector<double> flat;
  flat.reserve(3 * q.size());
  for (const auto& p : q) flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

void bench_eval(benchmark::State& state, bool is_star, bool coherent, bool sharp_only) {
  const Scene& sc = scene(is_star);
  SizingOptions o = sc.options;
  if (sharp_only) o.zones.resize(1);
  const SizingField h = build_sizing_field(sc.surface, o);
  const std::vector<double> q = make_queries(sc, coherent);
  const std::size_t n = q.size() / 3;
  std::size_t i = 0;
  double sum = 0;
  for (auto _ : state) {
    sum += h(q.data() + 3 * i);
    if (++i == n) i = 0;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}

void bench_build(benchmark::State& state, bool is_star) {
  const Scene& sc = scene(is_star);
  for (auto _ : state) {
    SizingField h = build_sizing_field(sc.surface, sc.options);
    benchmark::DoNotOptimize(&h);
  }
}

void bench_features(benchmark::State& state, bool is_star) {
  std::size_t edges = 0;
  for (auto _ : state) edges = detect_sharp_edges(scene(is_star).surface, 30).num_edges();
  state.counters["feature_edges"] = double(edges);
}

const int registered = [] {
  for (const bool is_star : {false, true}) {
    const std::string name = is_star ? "star" : "pins";
    for (const bool coherent : {true, false})
      for (const bool sharp_only : {false, true}) {
        const std::string label = "sizing/eval/" + name + (sharp_only ? "/sharp_edges_only" : "/all_zones") +
                                  (coherent ? "/coherent" : "/random");
        benchmark::RegisterBenchmark(label.c_str(), [=](benchmark::State& s) {
          bench_eval(s, is_star, coherent, sharp_only);
        })->MinTime(0.5);
      }
    benchmark::RegisterBenchmark(("sizing/build/" + name).c_str(), [=](benchmark::State& s) {
      bench_build(s, is_star);
    })->Unit(benchmark::kMillisecond)->MinTime(0.5);
    benchmark::RegisterBenchmark(("sizing/detect_sharp_edges/" + name).c_str(),
                                 [=](benchmark::State& s) { bench_features(s, is_star); })
        ->Unit(benchmark::kMillisecond)
        ->MinTime(0.5);
  }
  return 0;
}();

}  // namespace
}  // namespace kdmesh

BENCHMARK_MAIN();
