// Benchmark: node placement on a box [0, L]^3 (12-triangle surface) with a uniform or graded
// sizing field; per-stage times and nodes/s. The surface goes through the pipeline's own
// stages (prepare_surface, detect_sharp_edges at 30 degrees: the box's 12 edges and 8 corners).
// With --fidelity it also meshes the nodes (mesh_volume), checks the mesh (check_volume_mesh)
// and prints the edge length / target size statistics, overall and by kinds of end nodes.
// Usage: bench_placement [--L 100] [--h 1] [--seed 1] [--clearance 0.8] [--fidelity]
//                        [--graded SIZE]   (a point zone of SIZE at the box centre)
//                        [--cylinder]      (a 64-gon prism of radius L/2, height L, instead)
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "core/timer.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/placement/node_placement.h"
#include "mesher/quality/size_fidelity.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"

namespace kdmesh {
namespace {

struct Model {
  PreparedSurface surface;
  FeatureEdges features;
};

/// A raw surface through the pipeline's preparation and feature detection.
Model prepared(SurfaceMesh mesh, const char* name) {
  Model m;
  m.surface = prepare_surface(std::move(mesh), name);
  m.features = detect_sharp_edges(m.surface.mesh, 30);
  return m;
}

Model box(double L) {
  SurfaceMesh s;
  for (int i = 0; i < 8; ++i) s.points.push_back(L * (i & 1), L * (i >> 1 & 1), L * (i >> 2 & 1));
  s.tris = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return prepared(std::move(s), "box");
}

/// n-gon prism of radius r: the rims are features (90 degrees), the sides' creases are not.
Model cylinder(double r, double height, int n) {
  SurfaceMesh s;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < n; ++i) {
      const double t = 2 * std::numbers::pi * i / n;
      s.points.push_back(r * std::cos(t), r * std::sin(t), k * height);
    }
  const std::uint32_t cb = 2 * n, ct = 2 * n + 1;
  s.points.push_back(0, 0, 0);
  s.points.push_back(0, 0, height);
  for (std::uint32_t i = 0; i < std::uint32_t(n); ++i) {
    const std::uint32_t j = (i + 1) % n;
    s.tris.insert(s.tris.end(), {i, j, n + j, i, n + j, n + i, cb, j, i, ct, n + i, n + j});
  }
  return prepared(std::move(s), "cylinder");
}

int run(int argc, char** argv) {
  double L = 100, h = 1, clearance = 0.8, graded = 0;
  std::uint64_t seed = 1;
  bool fidelity = false, cyl = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&] { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (a == "--L") L = val();
    else if (a == "--h") h = val();
    else if (a == "--seed") seed = std::uint64_t(val());
    else if (a == "--clearance") clearance = val();
    else if (a == "--graded") graded = val();
    else if (a == "--fidelity") fidelity = true;
    else if (a == "--cylinder") cyl = true;
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  Model m = cyl ? cylinder(L / 2, L, 64) : box(L);
  SizingOptions so;
  so.max_size = h;
  if (graded > 0) {
    SizingZone z;
    z.kind = SizingZone::Kind::point;
    z.size = graded;
    z.coords = {L / 2, L / 2, L / 2};
    if (cyl) z.coords = {0, 0, L / 2};
    so.zones.push_back(z);
  }
  const SizingField sizing = build_sizing_field(m.surface.mesh, so);
  const SurfaceQuery query(m.surface.mesh);

  PlacementOptions po;
  po.seed = seed;
  po.interior_clearance = clearance;
  auto cpu = [] {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  };
  const double cpu0 = cpu();
  Stopwatch sw;
  std::string stage;
  double t_edges = 0, t_surface = 0, c_edges = 0, c_surface = 0;
  po.progress = [&](const std::string& s, double) {
    if (s == stage) return;
    if (stage == "edges") t_edges = sw.seconds(), c_edges = cpu() - cpu0;
    if (stage == "surface") t_surface = sw.seconds(), c_surface = cpu() - cpu0;
    stage = s;
  };
  const NodeSet nodes = place_nodes({m.surface, query, sizing}, m.features, po);
  const double t_total = sw.seconds();
  const double cpu_total = cpu() - cpu0;
  std::size_t count[4] = {0, 0, 0, 0};
  for (const NodeKind k : nodes.kind) ++count[int(k)];
  const double n_surf = double(count[0] + count[1] + count[2]);
  std::printf("model %s L=%g h=%g graded=%g clearance=%g seed=%llu\n", cyl ? "cylinder" : "box", L,
              h, graded, clearance, (unsigned long long)seed);
  std::printf("nodes: %zu (corner %zu, edge %zu, surface %zu, interior %zu)\n",
              nodes.size_count(), count[0], count[1], count[2], count[3]);
  std::printf("time: edges %.3f s, surface %.3f s (%.0f nodes/s), interior %.3f s (%.0f nodes/s), "
              "total %.3f s (%.0f nodes/s)\n",
              t_edges, t_surface - t_edges, n_surf / std::max(1e-9, t_surface - t_edges),
              t_total - t_surface, double(count[3]) / std::max(1e-9, t_total - t_surface), t_total,
              double(nodes.size_count()) / t_total);
  std::printf("cpu time (all threads; the machine may be shared, so wall > cpu): edges %.3f s, "
              "surface %.3f s (%.0f nodes/cpu-s), interior %.3f s (%.0f nodes/cpu-s), total %.3f s "
              "(%.0f nodes/cpu-s)\n",
              c_edges, c_surface - c_edges, n_surf / std::max(1e-9, c_surface - c_edges),
              cpu_total - c_surface, double(count[3]) / std::max(1e-9, cpu_total - c_surface),
              cpu_total, double(nodes.size_count()) / cpu_total);
  if (!fidelity) return 0;
  sw.reset();
  const VolumeMesh vm = mesh_volume({m.surface, query, sizing}, nodes);
  const double t_mesh = sw.seconds();
  const MeshCheck check = check_volume_mesh(vm, {m.surface, query, sizing});
  std::printf("mesh: %.3f s, %zu tets, %zu Steiner points, %zu dropped nodes; check %s, volume "
              "error %.3g, max Hausdorff %.3g h\n",
              t_mesh, vm.num_tets(), vm.stats.steiner_points, vm.stats.dropped_nodes,
              check.ok() ? "pass" : "FAIL", check.volume_error, check.max_hausdorff);
  for (const std::string& f : check.failures) std::printf("  %s\n", f.c_str());
  const SizeFidelity f = measure_size_fidelity(vm.nodes.points, vm.tets, sizing);
  std::printf("fidelity: edges %zu, mean ratio %.4f, in [0.7,1.4] %.4f, short %.4f, long %.4f, "
              "min %.3f, max %.3f\n",
              f.edges, f.mean_ratio, f.in_range, f.short_fraction, f.long_fraction, f.min_ratio,
              f.max_ratio);
  // Breakdown by the kinds of the two end nodes: surface-surface (corner, edge or surface),
  // surface-interior, interior-interior.
  {
    const std::vector<std::uint32_t>& tets = vm.tets;
    const NodeSet& mn = vm.nodes;
    std::vector<std::uint64_t> edges;
    for (std::size_t t = 0; t < tets.size(); t += 4)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          std::uint32_t a = tets[t + i], b = tets[t + j];
          if (a > b) std::swap(a, b);
          edges.push_back(std::uint64_t(a) << 32 | b);
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    double sum[3] = {0, 0, 0};
    std::size_t n[3] = {0, 0, 0}, in[3] = {0, 0, 0}, lo[3] = {0, 0, 0};
    for (const std::uint64_t e : edges) {
      const std::uint32_t a = std::uint32_t(e >> 32), b = std::uint32_t(e);
      const int cls = (mn.kind[a] == NodeKind::interior) + (mn.kind[b] == NodeKind::interior);
      const double* p = mn.points.p(a);
      const double* q = mn.points.p(b);
      const double mid[3] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
      const double r = std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]) / sizing(mid);
      sum[cls] += r;
      ++n[cls];
      in[cls] += r >= 0.7 && r <= 1.4;
      lo[cls] += r < 0.7;
    }
    const char* names[3] = {"surface-surface", "surface-interior", "interior-interior"};
    for (int c = 0; c < 3; ++c)
      std::printf("  %-17s edges %9zu mean %.4f in-range %.4f short %.4f\n", names[c], n[c],
                  n[c] ? sum[c] / double(n[c]) : 0.0, n[c] ? double(in[c]) / double(n[c]) : 0.0,
                  n[c] ? double(lo[c]) / double(n[c]) : 0.0);
  }
  return 0;
}

}  // namespace
}  // namespace kdmesh

int main(int argc, char** argv) { return kdmesh::run(argc, argv); }
