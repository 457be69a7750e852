// kdmesh — benchmark of the mesh quality-improvement pass (mesher/improve/mesh_improve.h) on a job
// of a batch file. Runs the pipeline's stages up to mesh_volume as `kdmesh mesh` does (read,
// prepare, sharp features, sizing, node placement, volume mesh), then improve_mesh, then the
// mesh check and the quality summary, and prints after each stage of the pass: min/max
// dihedral, mean radius ratio, tets under 5/10/12 degrees and over 165, seconds; the mean
// radius ratio by number of surface nodes per tet before and after; a fingerprint of the
// result (equal for any --threads).
// Usage: bench_improve JOB.yaml [--job NAME] [--rounds N] [--work-angle DEG]
//                     [--smooth-angle DEG] [--relax ROUNDS] [--relax-below GAMMA]
//                     [--no-surface] [--no-measure] [--threads N]
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cstdint>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <string>

#include "core/timer.h"
#include "io/surface_io.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/improve/mesh_improve.h"
#include "mesher/placement/node_placement.h"
#include "mesher/tet_quality.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/features.h"
#include "tools/app/job_config.h"

namespace kdmesh {
namespace {

double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// Mean radius ratio and min dihedral of the tets grouped by how many of their nodes lie on
/// the surface (0..4): where the remaining poor tets are.
void print_by_surface_nodes(const char* what, const VolumeMesh& mesh) {
  double sum[5] = {0, 0, 0, 0, 0}, mind[5] = {180, 180, 180, 180, 180};
  std::size_t n[5] = {0, 0, 0, 0, 0};
  for (std::size_t t = 0; t < mesh.num_tets(); ++t) {
    const std::uint32_t* v = &mesh.tets[4 * t];
    int k = 0;
    for (int i = 0; i < 4; ++i) k += mesh.nodes.kind[v[i]] != NodeKind::interior;
    const TetQuality q = tet_quality(mesh.nodes.points.p(v[0]), mesh.nodes.points.p(v[1]),
                                     mesh.nodes.points.p(v[2]), mesh.nodes.points.p(v[3]));
    sum[k] += q.radius_ratio;
    mind[k] = std::min(mind[k], q.min_dihedral);
    ++n[k];
  }
  std::printf("%s, by surface nodes per tet:", what);
  for (int k = 0; k < 5; ++k)
    if (n[k]) std::printf("  [%d] %zu tets gamma %.4f min %.2f", k, n[k], sum[k] / double(n[k]), mind[k]);
  std::printf("\n");
}

void print_check(const char* what, const MeshCheck& c) {
  std::printf("%s: check %s (tets %zu, boundary faces %zu, volume error %.3g, max Hausdorff %.3g h)\n",
              what, c.ok() ? "pass" : "FAIL", c.tets, c.boundary_faces, c.volume_error,
              c.max_hausdorff);
  for (const std::string& f : c.failures) std::printf("  %s\n", f.c_str());
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_improve JOB.yaml [--job NAME] [--rounds N] [--work-angle DEG] "
                         "[--smooth-angle DEG] [--relax ROUNDS] [--relax-below GAMMA] [--no-surface] "
                         "[--no-measure] [--threads N]\n");
    return 2;
  }
  std::string file = argv[1], name;
  ImproveOptions io;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--job") name = val();
    else if (a == "--rounds") io.rounds = std::atoi(val().c_str());
    else if (a == "--smooth-angle") io.smooth_angle = std::atof(val().c_str());
    else if (a == "--relax-below") io.relax_below = std::atof(val().c_str());
    else if (a == "--relax") io.relax_rounds = std::atoi(val().c_str());
    else if (a == "--work-angle") io.work_angle = std::atof(val().c_str());
    else if (a == "--no-measure") io.measure_stages = false;
    else if (a == "--no-surface") io.smooth_surface = false;
    else if (a == "--threads") io.threads = unsigned(std::atoi(val().c_str()));
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const BatchConfig cfg = load_batch_config(file);
  const MeshJob* job = nullptr;
  for (const MeshJob& j : cfg.jobs)
    if (name.empty() || j.name == name) {
      job = &j;
      break;
    }
  if (!job) {
    std::fprintf(stderr, "no job %s in %s\n", name.c_str(), file.c_str());
    return 2;
  }
  if (!job->bodies.empty()) {  // (its own pipeline reads one surface: no imprinting, no regions)
    std::fprintf(stderr, "bench_improve: job %s has %zu bodies; this benchmark runs single-body jobs\n",
                 job->name.c_str(), job->bodies.size());
    return 2;
  }
  Stopwatch sw;
  SurfaceOptions so;
  so.scale = job->scale;
  const PreparedSurface surface = prepare_surface(read_surface(job->input), job->input, so);
  const FeatureEdges features = detect_sharp_edges(surface.mesh, job->sharp_angle);
  const SizingField sizing = build_sizing_field(surface.mesh, job->sizing);
  const SurfaceQuery query(surface.mesh);
  PlacementOptions po;
  po.seed = job->seed;
  NodeSet nodes = place_nodes({surface, query, sizing}, features, po);
  const double t_prep = sw.seconds();
  sw.reset();
  double cpu0 = cpu_seconds();
  VolumeMeshOptions vo;
  vo.order = job->order;
  vo.order.seed = job->seed;
  VolumeMesh mesh = mesh_volume({surface, query, sizing}, std::move(nodes), vo);
  const double t_mesh = sw.seconds(), c_mesh = cpu_seconds() - cpu0;
  std::printf("job %s: %zu nodes, %zu tets; read..place %.2f s, mesh %.2f s (cpu %.2f s)\n",
              job->name.c_str(), mesh.nodes.size_count(), mesh.num_tets(), t_prep, t_mesh, c_mesh);
  print_check("before", check_volume_mesh(mesh, {surface, query, sizing}));
  print_by_surface_nodes("before", mesh);

  cpu0 = cpu_seconds();
  const ImproveStats st = improve_mesh(mesh, {surface, query, sizing}, io);
  const double c_improve = cpu_seconds() - cpu0;
  std::printf("\n%-10s %8s %9s %9s %7s %8s %8s %8s %8s %8s\n", "stage", "ops", "min_dih", "max_dih",
              "gamma", "<5deg", "<10deg", "<12deg", ">165deg", "seconds");
  for (const ImproveStage& s : st.stages)
    std::printf("%-10s %8zu %9.3f %9.3f %7.4f %8zu %8zu %8zu %8zu %8.3f\n", s.name.c_str(),
                s.operations, s.min_dihedral, s.max_dihedral, s.mean_radius_ratio, s.under5,
                s.under10, s.under12, s.over165, s.seconds);
  std::printf("\nimprove: %.2f s (%.2fx mesh; cpu %.2f s, %.2fx mesh), edge removals %zu, face removals %zu, smoothed %zu, "
              "relaxed %zu, boundary faces changed %zu\n",
              st.seconds, st.seconds / t_mesh, c_improve, c_improve / c_mesh, st.edge_removals, st.face_removals, st.smoothed,
              st.relaxed, st.boundary_changes);
  sw.reset();
  const MeshCheck after = check_volume_mesh(mesh, {surface, query, sizing});
  print_check("after", after);
  print_by_surface_nodes("after", mesh);
  const QualitySummary q = summarize_quality(to_tet_mesh(mesh));
  std::printf("quality: %zu tets, inverted %zu, dihedral %.3f .. %.3f deg, radius ratio mean %.4f min %.4g\n",
              q.tets, q.inverted, q.min_dihedral, q.max_dihedral, q.mean_radius_ratio,
              q.min_radius_ratio);
  // A fingerprint of the result (FNV-1a over tets and coordinates): equal across --threads.
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&](const void* data, std::size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  };
  mix(mesh.tets.data(), mesh.tets.size() * sizeof(std::uint32_t));
  mix(mesh.nodes.points.xyz.data(), mesh.nodes.points.xyz.size() * sizeof(double));
  std::printf("fingerprint %016llx\n", (unsigned long long)h);
  return after.ok() ? 0 : 1;
}

}  // namespace
}  // namespace kdmesh

int main(int argc, char** argv) {
  try {
    return kdmesh::run(argc, argv);
  } catch (const std::exception& e) {  // (an input error, a refused surface, ...: said, not a crash)
    std::fprintf(stderr, "bench_improve: %s\n", e.what());
    return 1;
  }
}
