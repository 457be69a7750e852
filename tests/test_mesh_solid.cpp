// kdmesh — the front door mesh_solid (mesher/mesh_solid.h): an in-memory surface in, a checked
// mesh and what was measured out; typed errors that keep the report; progress and
// cancellation; the same mesh as the CLI's job for the same parameters.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/surface_io.h"
#include "io/vtu_writer.h"
#include "mesher/mesh_solid.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/tet_quality.h"
#include "sizing/features.h"
#include "tests/support/box_surface.h"
#include "tools/app/mesh_job.h"

namespace kdmesh {
namespace {

/// The box [0,a] x [0,b] x [0,c] as 8 points and 12 outward triangles.
SurfaceMesh box(double a, double b, double c) { return test::box_surface({0, 0, 0}, {a, b, c}); }

MeshParams params(double size) {
  MeshParams p;
  p.name = "box";
  p.sizing.max_size = size;
  p.sizing.min_size = size / 1000;
  return p;
}

double mesh_volume_of(const VolumeMesh& m) {
  double v = 0;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const double* p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.nodes.points.p(m.tets[4 * t + k]);
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) a[k] = p[1][k] - p[0][k], b[k] = p[2][k] - p[0][k], c[k] = p[3][k] - p[0][k];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
  }
  return v;
}

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The box meshes in memory: the check passes, the tets fill its volume, and the report's
// figures are those of the mesh it returns.
TEST(MeshSolid, InMemoryBoxGivesACheckedMeshAndItsReport) {
  const MeshResult r = mesh_solid(box(1, 2, 3), params(0.4));
  const MeshReport& rep = r.report;
  ASSERT_TRUE(rep.has_check && rep.check.ok());
  EXPECT_NEAR(mesh_volume_of(r.mesh), 6.0, 1e-9);
  EXPECT_EQ(rep.counts.tets, r.mesh.num_tets());
  EXPECT_EQ(rep.counts.nodes, r.mesh.nodes.size_count());
  EXPECT_EQ(rep.counts.boundary_faces, r.mesh.boundary.size() / 3);
  EXPECT_EQ(rep.counts.nodes_by_kind[0], 8u);  // the box's corners
  EXPECT_EQ(rep.counts.feature_edges, 12u);
  EXPECT_EQ(r.mesh.tet_region.size(), r.mesh.num_tets());
  EXPECT_EQ(r.tet_mesh.tets, r.mesh.tets);
  EXPECT_EQ(rep.quality.tets, r.mesh.num_tets());
  EXPECT_GT(rep.quality.min_dihedral, 12.0);
  for (const char* k : {"prepare", "features", "sizing", "place", "mesh", "improve", "mesh_check", "quality"})
    EXPECT_TRUE(rep.seconds.count(k)) << k;
  EXPECT_TRUE(r.fe.tets.empty());  // fe_groups off
}

// With fe_groups the FE view has every tet, the boundary faces by patch (6 for a box) and the
// feature curves' segments; a named group is resolved.
TEST(MeshSolid, FeGroupsGiveTheFeMeshWithPatchesAndNamedGroups) {
  MeshParams p = params(0.5);
  p.fe_groups = true;
  GroupSpec g;
  g.name = "top";
  g.dim = 2;
  g.by = GroupSpec::Select::point;
  g.point[0] = 0.5, g.point[1] = 0.5, g.point[2] = 1.0;
  p.groups.push_back(g);
  const MeshResult r = mesh_solid(box(1, 1, 1), p);
  EXPECT_EQ(r.fe.num_tets(), r.mesh.num_tets());
  EXPECT_EQ(r.fe.num_faces(), r.mesh.boundary.size() / 3);
  ASSERT_TRUE(r.report.boundary.has_value());
  EXPECT_TRUE(r.report.boundary->pass);
  EXPECT_EQ(r.report.counts.patches, 6u);
  EXPECT_EQ(r.report.counts.curves, 12u);
  bool found = false;
  for (const FeGroup& fg : r.fe.groups) found = found || (fg.name == "top" && fg.dim == 2 && fg.entities.size() == 1);
  EXPECT_TRUE(found);
}

// The CLI's job writes the same VTU, byte for byte, as the front door's mesh written directly.
TEST(MeshSolid, SameMeshAsTheJobOfTheSameParameters) {
  const std::filesystem::path dir = std::filesystem::path(KDMESH_TEST_TMP) / "mesh_solid_same";
  std::filesystem::create_directories(dir);
  const std::string stl = (dir / "box.stl").string();
  write_stl(box(1, 2, 3), stl, false);
  MeshJob job;
  static_cast<MeshParams&>(job) = params(0.4);
  job.input = stl;
  job.vtu = (dir / "job.vtu").string();
  const MeshJobResult jr = run_mesh_job(job);
  ASSERT_TRUE(jr.ok()) << jr.summary.dump(1);
  MeshParams p = params(0.4);
  p.input = stl;
  const MeshResult r = mesh_solid(read_surface(stl), p);
  const std::string direct = (dir / "direct.vtu").string();
  write_vtu(r.tet_mesh, direct);
  EXPECT_EQ(slurp(job.vtu), slurp(direct));
  EXPECT_EQ(jr.summary["counts"]["tets"].get<std::size_t>(), r.mesh.num_tets());
}

// Errors are typed and carry their data; the report keeps what was measured before them.
TEST(MeshSolid, ErrorsAreTypedAndTheReportKeepsWhatWasMeasured) {
  {  // an open box (one facet missing): SurfaceError naming the surface
    SurfaceMesh open = box(1, 1, 1);
    open.tris.resize(open.tris.size() - 3);
    MeshParams p = params(0.3);
    p.input = "open-box";
    MeshReport rep;
    try {
      mesh_solid(open, p, {}, &rep);
      FAIL() << "an open surface meshed";
    } catch (const SurfaceError& e) {
      EXPECT_NE(std::string(e.what()).find("open-box"), std::string::npos) << e.what();
      EXPECT_EQ(e.code(), ExitCode::geometry);
    }
    EXPECT_FALSE(rep.has_surface);
  }
  {  // bad parameters: UsageError before any work
    MeshParams p = params(0.3);
    p.sizing.gradation = 5;
    MeshReport rep;
    EXPECT_THROW(mesh_solid(box(1, 1, 1), p, {}, &rep), UsageError);
    EXPECT_FALSE(rep.has_surface);
  }
  {  // a memory limit below the estimate: ResourceError after the estimate, with it
    MeshParams p = params(0.05);
    p.max_memory = 1e6;
    MeshReport rep;
    EXPECT_THROW(mesh_solid(box(1, 1, 1), p, {}, &rep), ResourceError);
    EXPECT_TRUE(rep.has_surface);
    EXPECT_TRUE(rep.has_estimate);
    EXPECT_GT(rep.estimate.peak_bytes, 1e6);
    EXPECT_FALSE(rep.has_mesh);
  }
}

// Progress reaches the caller; a cancellation stops the job with CancelledError at the next
// stage or progress step, and leaves nothing behind: the next call gives the same mesh as a
// call never cancelled.
TEST(MeshSolid, ProgressAndCancellationLeaveNoState) {
  const MeshResult plain = mesh_solid(box(1, 1, 1), params(0.1));
  std::vector<std::string> stages;
  MeshCallbacks cb;
  cb.progress = [&](const std::string& s, double f) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    if (stages.empty() || stages.back() != s) stages.push_back(s);
  };
  bool placing = false;
  std::size_t logs_after = 0;
  cb.log = [&](const std::string& m) {
    if (placing) ++logs_after;
    if (m.rfind("placing nodes", 0) == 0) placing = true;
  };
  cb.cancel = [&] { return placing; };  // cancel once node placement has started
  MeshReport rep;
  EXPECT_THROW(mesh_solid(box(1, 1, 1), params(0.1), cb, &rep), CancelledError);
  EXPECT_EQ(logs_after, 0u);  // no later stage started
  EXPECT_FALSE(rep.has_mesh);
  // Cancelled inside a stage (at a progress step of the Delaunay insertion): the job stops
  // there, before the stage ends.
  MeshCallbacks inside;
  bool in_delaunay = false;
  inside.progress = [&](const std::string& s, double) { in_delaunay = in_delaunay || s == "delaunay"; };
  inside.cancel = [&] { return in_delaunay; };
  MeshReport rep2;
  EXPECT_THROW(mesh_solid(box(1, 1, 1), params(0.1), inside, &rep2), CancelledError);
  EXPECT_TRUE(in_delaunay);
  EXPECT_FALSE(rep2.has_mesh);
  EXPECT_GT(rep2.counts.placed_nodes, 0u);
  // Uncancelled, with progress: the stages report, and the mesh is the plain one.
  cb.cancel = {};
  stages.clear();
  const MeshResult again = mesh_solid(box(1, 1, 1), params(0.1), cb);
  EXPECT_EQ(again.mesh.tets, plain.mesh.tets);
  EXPECT_EQ(again.mesh.nodes.points.size(), plain.mesh.nodes.points.size());
  for (const char* s : {"surface", "interior", "delaunay", "improve"})
    EXPECT_NE(std::find(stages.begin(), stages.end(), s), stages.end()) << s;
}

/// A wedge: the prism over the triangle (0,0), (1,-t), (1,t) with t = tan(angle/2), z in
/// [0, width]; its edge on the z axis has the dihedral angle `angle`.
SurfaceMesh wedge(double angle_deg, double width) {
  const double t = std::tan(angle_deg * 3.14159265358979323846 / 360);
  SurfaceMesh s;
  for (double z : {0.0, width}) {
    s.points.push_back(0, 0, z);
    s.points.push_back(1, -t, z);
    s.points.push_back(1, t, z);
  }
  for (std::uint32_t x : {0, 2, 1, 3, 4, 5, 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 2, 0, 3, 2, 3, 5}) s.tris.push_back(x);
  return s;
}

double min_dihedral_of(const VolumeMesh& m) {
  double worst = 180;
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const std::uint32_t* v = &m.tets[4 * t];
    worst = std::min(worst, tet_quality(m.nodes.points.p(v[0]), m.nodes.points.p(v[1]), m.nodes.points.p(v[2]),
                                        m.nodes.points.p(v[3])).min_dihedral);
  }
  return worst;
}

// Quality refinement (triceratops.ply at diag/20 kept one tet at 11.89 deg that no local
// operation improved; halving the size around it and meshing again gave 12.68 deg). An 8 deg
// wedge: every tet at its sharp edge has a dihedral of at most 8 deg there (the tets around
// the edge share its 8 deg), so the target cannot be met; the first mesh has a worse tet
// than that, the refinements improve it, and the mesh with the better worst tet is the one
// returned, with the report's figures its own. Whether the first mesh falls short of 8 deg
// depends on the order in which the quality pass meets its ties, which any change to the
// pipeline reshuffles: at most sizes the first mesh already reaches 8 deg and nothing is
// refined. The test therefore takes the first size of a list whose first mesh shows the
// mechanism (a scan of h = 0.05-0.1 on 2026-11-28 found 0.1 and 0.0720...01; the exact
// 0.072 the test used before did not), and fails if none does.
TEST(MeshSolid, QualityRefinementKeepsTheMeshWithTheBetterWorstTet) {
  double h = 0, w0 = 180;
  MeshResult first;
  for (const double size : {0.072, 0.1, 0.078, 0.082, 0.066, 0.09, 0.058, 0.0720001}) {
    MeshParams once = params(size);
    once.max_refinements = 0;
    first = mesh_solid(wedge(8, 1), once);
    w0 = min_dihedral_of(first.mesh);
    h = size;
    if (w0 < 8.0 - 1.0) break;
  }
  ASSERT_LT(w0, 8.0 - 1.0) << "no size of the list leaves the first mesh's worst tet below 7 deg";
  const MeshResult r = mesh_solid(wedge(8, 1), params(h));
  ASSERT_TRUE(first.report.check.ok() && r.report.check.ok());
  const double w = min_dihedral_of(r.mesh);
  EXPECT_GT(w, w0 + 1.0);             // refined: better
  EXPECT_LE(w, 8.0 + 1e-9);           // and not above the wedge's own angle
  const auto& notices = r.report.notices;
  EXPECT_TRUE(std::any_of(notices.begin(), notices.end(),
                          [](const std::string& n) { return n.rfind("quality: ", 0) == 0; }));
  EXPECT_FALSE(std::any_of(first.report.notices.begin(), first.report.notices.end(),
                           [](const std::string& n) { return n.rfind("quality", 0) == 0; }));
  // The report describes the returned mesh, also when an earlier one was kept.
  EXPECT_EQ(r.report.counts.tets, r.mesh.num_tets());
  EXPECT_EQ(r.report.counts.nodes, r.mesh.nodes.size_count());
  ASSERT_TRUE(r.report.improve.has_value());
  EXPECT_NEAR(r.report.quality.min_dihedral, w, 1e-9);
  EXPECT_GT(r.report.improve->below_target, 0u);
  EXPECT_LE(r.report.improve->worst_sine, std::sin(w * 3.14159265358979323846 / 180) + 1e-12);
  // Its volume is the one the report's check measured (and passed: the wedge's own within the
  // check's tolerance; a boundary face across the 8 deg edge can cut a sliver of it off).
  EXPECT_NEAR(mesh_volume_of(r.mesh), r.report.check.mesh_volume, 1e-12);
  // The refined mesh reached the wedge's angle: no further refinement is tried (one notice).
  EXPECT_EQ(std::count_if(notices.begin(), notices.end(),
                          [](const std::string& n) { return n.rfind("quality", 0) == 0; }), 1);
}

// The input's smallest edge angle, against the solids' own: a box 90, the wedge its angle.
TEST(Features, SmallestEdgeAngleIsTheSolidsSharpestEdge) {
  EXPECT_NEAR(smallest_edge_angle(box(1, 2, 3)), 90, 1e-9);
  EXPECT_NEAR(smallest_edge_angle(wedge(8, 1)), 8, 1e-9);
  EXPECT_NEAR(smallest_edge_angle(wedge(30, 1)), 30, 1e-9);
}

}  // namespace
}  // namespace kdmesh
