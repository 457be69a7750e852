// kdmesh — benchmark of the volume mesher on a box: structured surface nodes of spacing h and
// a jittered interior lattice (0.85 h clearance), about (1/h)^3 nodes. Prints the stage times,
// the classification rate and the end-to-end / Delaunay ratio.
// Usage: bench_volume_mesh [h=0.01] [--check]   (h = 0.01: ~1.03M nodes; 0.0068: ~3.2M)
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/rng.h"
#include "core/timer.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/volume/volume_mesh.h"

using namespace kdmesh;

namespace {

/// The unit cube [0,1]^3: 8 corners, 12 outward facets (two per face).
PreparedSurface unit_cube() {
  PreparedSurface s;
  for (int i = 0; i < 8; ++i) s.mesh.points.push_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  s.mesh.tris = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  s.tri_shell.assign(12, 0);
  s.shell_body = {0};
  s.shell_parent = {kNoFacet};
  s.shell_volume = {1.0};
  s.num_bodies = 1;
  s.volume = 1;
  for (int k = 0; k < 3; ++k) s.bbox_min[k] = 0, s.bbox_max[k] = 1;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  double h = 0.01;
  bool check = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--check") == 0) check = true;
    else h = std::atof(argv[i]);
  }
  if (!(h > 0 && h < 0.5)) {
    std::fprintf(stderr, "usage: bench_volume_mesh [h in (0, 0.5)] [--check]\n");
    return 2;
  }
  const PreparedSurface s = unit_cube();
  const SurfaceQuery q(s.mesh);
  SizingOptions so;
  so.max_size = h;
  const SizingField sizing = build_sizing_field(s.mesh, so);

  Stopwatch sw;
  const int m = int(std::lround(1 / h));
  const double step = 1.0 / m;
  NodeSet nodes;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= m; ++j)
      for (int k = 0; k <= m; ++k) {
        if (i != 0 && i != m && j != 0 && j != m && k != 0 && k != m) continue;
        const double p[3] = {i * step, j * step, k * step};
        double cp[3];
        std::uint32_t f = kNoFacet;
        q.closest(p, cp, &f);
        nodes.push_back(p, NodeKind::surface, f, float(step));
      }
  Rng rng(1);
  for (int i = 1; i < m; ++i)
    for (int j = 1; j < m; ++j)
      for (int k = 1; k < m; ++k) {
        double p[3] = {i * step, j * step, k * step};
        for (double& x : p) x += rng.uniform(-0.15, 0.15) * step;
        nodes.push_back(p, NodeKind::interior, kNoFacet, float(step));
      }
  std::printf("nodes            %zu (surface lattice %d^2 per face, h = %g), built in %.2f s\n",
              nodes.size_count(), m + 1, step, sw.seconds());

  VolumeMeshOptions vo;
  sw.reset();
  const VolumeMesh vm = mesh_volume({s, q, sizing}, nodes, vo);
  const double total = sw.seconds();
  const VolumeMeshStats& st = vm.stats;
  std::printf("tets             %zu inside; %zu classified over %d round(s)\n", vm.num_tets(),
              st.classified_tets, st.rounds + 1);
  std::printf("order            %.3f s\n", st.order_seconds);
  std::printf("delaunay         %.3f s (first: %.3f s)\n", st.delaunay_seconds, st.delaunay.seconds);
  std::printf("classify         %.3f s  -> %.2f M tets/s; %zu side queries, %zu rim flips\n",
              st.classify_seconds, double(st.classified_tets) / st.classify_seconds / 1e6,
              st.side_queries, st.rim_flips);
  std::printf("recover/judge    %.3f s; steiner %zu, dropped %zu\n", st.recover_seconds, st.steiner_points,
              st.dropped_nodes);
  std::printf("regions/output   %.3f s\n", st.region_seconds);
  std::printf("mesh_volume      %.3f s = %.2f x (order + Delaunay) = %.2f x Delaunay alone\n", total,
              total / (st.order_seconds + st.delaunay_seconds), total / st.delaunay_seconds);
  if (check) {
    sw.reset();
    const MeshCheck c = check_volume_mesh(vm, {s, q, sizing});
    std::printf("check            %.3f s: %s; volume error %.3g, max hausdorff %.3g h\n", sw.seconds(),
                c.ok() ? "ok" : "FAILED", c.volume_error, c.max_hausdorff);
    for (auto& f : c.failures) std::printf("  %s\n", f.c_str());
    if (!c.ok()) return 5;
  }
  return 0;
}
