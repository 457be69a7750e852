// Benchmark: node placement on a box [0, L]^3 (12-triangle surface, its 12 edges and 8
// corners as features) with a uniform or graded sizing field; per-stage times and nodes/s.
// With --fidelity it also tetrahedralizes the nodes (kd-bfs + delaunay), keeps the tets whose
// centroid is inside, and prints the edge length / target size statistics.
// Usage: bench_placement [--L 100] [--h 1] [--seed 1] [--clearance 0.8] [--fidelity]
//                        [--graded SIZE]   (a point zone of SIZE at the box centre)
//                        [--cylinder]      (a 64-gon prism of radius L/2, height L, instead)
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "core/timer.h"
#include "mesher/delaunay.h"
#include "mesher/node_placement.h"
#include "mesher/order.h"
#include "mesher/size_fidelity.h"

namespace kdmesh {
namespace {

struct Model {
  PreparedSurface surface;
  FeatureEdges features;
};

void finish(Model& m) {
  PreparedSurface& s = m.surface;
  s.tri_shell.assign(s.mesh.num_tris(), 0);
  s.shell_body = {0};
  s.shell_parent = {kNoFacet};
  s.num_bodies = 1;
  for (int a = 0; a < 3; ++a) {
    s.bbox_min[a] = INFINITY;
    s.bbox_max[a] = -INFINITY;
  }
  for (std::size_t i = 0; i < s.mesh.points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      s.bbox_min[a] = std::min(s.bbox_min[a], s.mesh.points.p(std::uint32_t(i))[a]);
      s.bbox_max[a] = std::max(s.bbox_max[a], s.mesh.points.p(std::uint32_t(i))[a]);
    }
}

Model box(double L) {
  Model m;
  for (int i = 0; i < 8; ++i) m.surface.mesh.points.push_back(L * (i & 1), L * (i >> 1 & 1), L * (i >> 2 & 1));
  // Outward, counter-clockwise seen from outside.
  m.surface.mesh.tris = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                         2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  m.features.edges = {0, 1, 0, 2, 0, 4, 1, 3, 1, 5, 2, 3, 2, 6, 3, 7, 4, 5, 4, 6, 5, 7, 6, 7};
  m.features.corners = {0, 1, 2, 3, 4, 5, 6, 7};
  m.surface.volume = L * L * L;
  m.surface.shell_volume = {m.surface.volume};
  finish(m);
  return m;
}

Model cylinder(double r, double height, int n) {
  Model m;
  auto& P = m.surface.mesh.points;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < n; ++i) {
      const double t = 2 * std::numbers::pi * i / n;
      P.push_back(r * std::cos(t), r * std::sin(t), k * height);
    }
  const std::uint32_t cb = 2 * n, ct = 2 * n + 1;
  P.push_back(0, 0, 0);
  P.push_back(0, 0, height);
  auto& T = m.surface.mesh.tris;
  for (std::uint32_t i = 0; i < std::uint32_t(n); ++i) {
    const std::uint32_t j = (i + 1) % n;
    T.insert(T.end(), {i, j, n + j, i, n + j, n + i});  // side, outward
    T.insert(T.end(), {cb, j, i});                      // bottom, normal -z
    T.insert(T.end(), {ct, n + i, n + j});              // top, normal +z
    m.features.edges.insert(m.features.edges.end(), {i, j, n + i, n + j});
  }
  for (std::size_t e = 0; e < m.features.edges.size(); e += 2)
    if (m.features.edges[e] > m.features.edges[e + 1]) std::swap(m.features.edges[e], m.features.edges[e + 1]);
  m.surface.volume = 0.5 * n * r * r * std::sin(2 * std::numbers::pi / n) * height;
  m.surface.shell_volume = {m.surface.volume};
  finish(m);
  return m;
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
  const NodeSet nodes = place_nodes(m.surface, query, m.features, sizing, po);
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
  const Ordering order = make_order(nodes.points, OrderOptions{});
  const DelaunayResult dr = delaunay(nodes.points, order);
  const std::vector<std::uint32_t> all = finite_tets(dr.tri);
  std::vector<std::uint32_t> inside, solid;
  for (std::size_t t = 0; t < all.size(); t += 4) {
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k)
      for (int a = 0; a < 3; ++a) c[a] += nodes.points.p(all[t + k])[a] / 4;
    if (query.side(c) > 0) {
      inside.insert(inside.end(), &all[t], &all[t] + 4);
      // Flat tets on a non-axis-aligned planar face: its nodes are off the plane by rounding,
      // so the face's Delaunay slivers have centroids a rounding error inside. Boundary
      // recovery removes them; the second statistic leaves them out.
      if (query.distance(c) > 1e-6 * sizing(c)) solid.insert(solid.end(), &all[t], &all[t] + 4);
    }
  }
  const SizeFidelity f = measure_size_fidelity(nodes.points, inside, sizing);
  std::printf("delaunay: %.3f s, %zu tets, %zu inside, %zu of them not flat on the surface\n",
              sw.seconds(), all.size() / 4, inside.size() / 4, solid.size() / 4);
  const SizeFidelity f2 = measure_size_fidelity(nodes.points, solid, sizing);
  std::printf("fidelity without flat surface tets: edges %zu, mean ratio %.4f, in [0.7,1.4] %.4f, "
              "short %.4f, long %.4f, min %.3f, max %.3f\n",
              f2.edges, f2.mean_ratio, f2.in_range, f2.short_fraction, f2.long_fraction,
              f2.min_ratio, f2.max_ratio);
  inside.swap(solid);  // the statistics below use the non-flat tets
  std::printf("fidelity: edges %zu, mean ratio %.4f, in [0.7,1.4] %.4f, short %.4f, long %.4f, "
              "min %.3f, max %.3f\n",
              f.edges, f.mean_ratio, f.in_range, f.short_fraction, f.long_fraction, f.min_ratio,
              f.max_ratio);
  // Boundary recovery: faces of the kept tets seen once are the boundary; each should have
  // its 3 nodes on the surface, and the kept volume should equal the solid's.
  {
    std::vector<std::array<std::uint32_t, 3>> faces;
    double vol = 0;
    for (std::size_t t = 0; t < inside.size(); t += 4) {
      const std::uint32_t* v = &inside[t];
      const double* a = nodes.points.p(v[0]);
      const double* b = nodes.points.p(v[1]);
      const double* c = nodes.points.p(v[2]);
      const double* d = nodes.points.p(v[3]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double x[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
      vol += (u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) +
              u[2] * (w[0] * x[1] - w[1] * x[0])) / 6;
      for (int i = 0; i < 4; ++i) {
        std::array<std::uint32_t, 3> f = {v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]};
        std::sort(f.begin(), f.end());
        faces.push_back(f);
      }
    }
    std::sort(faces.begin(), faces.end());
    std::size_t boundary = 0, bad = 0;
    for (std::size_t i = 0; i < faces.size();) {
      std::size_t j = i;
      while (j < faces.size() && faces[j] == faces[i]) ++j;
      if (j - i == 1) {
        ++boundary;
        for (const std::uint32_t v : faces[i])
          if (nodes.kind[v] == NodeKind::interior) {
            ++bad;
            break;
          }
      }
      i = j;
    }
    std::printf("boundary: %zu faces, %zu with an interior node; kept volume %.6g of %.6g\n",
                boundary, bad, vol, m.surface.volume);
  }
  // Breakdown by the kinds of the two end nodes: surface-surface (corner, edge or surface),
  // surface-interior, interior-interior.
  {
    std::vector<std::uint64_t> edges;
    for (std::size_t t = 0; t < inside.size(); t += 4)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          std::uint32_t a = inside[t + i], b = inside[t + j];
          if (a > b) std::swap(a, b);
          edges.push_back(std::uint64_t(a) << 32 | b);
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    double sum[3] = {0, 0, 0};
    std::size_t n[3] = {0, 0, 0}, in[3] = {0, 0, 0}, lo[3] = {0, 0, 0};
    for (const std::uint64_t e : edges) {
      const std::uint32_t a = std::uint32_t(e >> 32), b = std::uint32_t(e);
      const int cls = (nodes.kind[a] == NodeKind::interior) + (nodes.kind[b] == NodeKind::interior);
      const double* p = nodes.points.p(a);
      const double* q = nodes.points.p(b);
      const double m[3] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
      const double r = std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]) / sizing(m);
      if (r > 4 && std::getenv("KDMESH_BENCH_DEBUG"))
        std::printf("long edge %u (%d) %g %g %g - %u (%d) %g %g %g\n", a, int(nodes.kind[a]), p[0],
                    p[1], p[2], b, int(nodes.kind[b]), q[0], q[1], q[2]);
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
