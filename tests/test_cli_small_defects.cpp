// Issue 19, class 4 — smaller defects: non-convex PLY polygons, UTF-8 BOMs, true repair hints,
// batch directories, output errors naming the user's path with errno text, control bytes in
// config errors, empty and long output names, second YAML documents.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/surface_mesh.h"
#include "io/surface_io.h"
#include "tests/support/run_cli.h"

namespace {

namespace fs = std::filesystem;
using kdmesh::test::CliResult;
using kdmesh::test::slurp;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli_small_defects"); }

CliResult kdmesh(const std::string& args, const std::string& env = "") {
  return kdmesh::test::run_kdmesh(args, tmpdir(), env);
}

using kdmesh::test::contains;

/// A fresh directory for one test.
fs::path fresh(const std::string& name) { return kdmesh::test::fresh_dir(tmpdir(), name); }

/// The box [x0, x0 + e] x [0, e]^2 as 12 outward triangles (every face split on one diagonal).
void add_cube(kdmesh::SurfaceMesh& m, double x0, double e) {
  const std::uint32_t base = std::uint32_t(m.points.size());
  for (int i = 0; i < 8; ++i) m.points.push_back(x0 + e * (i & 1), e * ((i >> 1) & 1), e * ((i >> 2) & 1));
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const int t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.tris.push_back(base + std::uint32_t(t));
}

// An L-shaped prism whose hexagonal caps start at a vertex that does not see the whole
// polygon: a fan from it leaves the polygon. Ear clipping meshes it (volume 3).
TEST(SmallDefects, NonConvexPlyPolygonsAreTriangulatedInTheirPlane) {
  const fs::path d = fresh("ply");
  const double xy[6][2] = {{2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 0}, {2, 0}};  // counter-clockwise
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex 12\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 8\nproperty list uchar int vertex_indices\nend_header\n";
  for (int z = 0; z < 2; ++z)
    for (const auto& p : xy) ply << p[0] << " " << p[1] << " " << z << "\n";
  ply << "6 5 4 3 2 1 0\n";    // bottom, facing -z
  ply << "6 6 7 8 9 10 11\n";  // top, facing +z
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    ply << "4 " << i << " " << j << " " << 6 + j << " " << 6 + i << "\n";
  }
  std::ofstream(d / "l.ply") << ply.str();
  const CliResult r = kdmesh("mesh " + (d / "l.ply").string() + " --size 0.5 --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["mesh_check"]["mesh_volume"].get<double>(), 3.0, 1e-9);
}

// Issue 20, part 5: OBJ and OFF inputs, end to end (quads, v/vt/vn references, negative
// indices), meshed and checked; the help lists the formats.
TEST(SmallDefects, ObjAndOffCubesMeshEndToEnd) {
  const fs::path d = fresh("objoff");
  std::ofstream(d / "cube.obj") << "# unit cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                   "vt 0 0\nvn 0 0 -1\nf 1/1/1 4/1/1 3/1/1 2/1/1\nf 5//1 6//1 7//1 8//1\n"
                                   "f 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf -5 -8 -4 -1\n";
  std::ofstream(d / "cube.OFF") << "OFF\n8 6 12\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                                   "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n";
  std::string reference;
  for (const char* name : {"cube.obj", "cube.OFF"}) {
    const CliResult r = kdmesh("mesh " + (d / name).string() + " --size 0.3 --json -q");
    ASSERT_EQ(r.code, 0) << name << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["status"], "ok") << name;
    EXPECT_EQ(j["counts"]["surface_facets"], 12) << name;  // 6 quads, 2 triangles each
    EXPECT_NEAR(j["mesh_check"]["mesh_volume"].get<double>(), 1.0, 1e-9) << name;
    // The same quads give the same mesh, whichever format they came in.
    const std::string counts = j["counts"].dump();
    if (reference.empty())
      reference = counts;
    else
      EXPECT_EQ(counts, reference) << name;
  }
  const CliResult help = kdmesh("mesh --help");
  EXPECT_TRUE(contains(help.out, "Closed surface (.stl, .ply, .obj or .off)")) << help.out;
}

TEST(SmallDefects, AsciiStlWithUtf8BomIsRead) {
  const fs::path d = fresh("bom");
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 2);
  kdmesh::write_stl(m, (d / "plain.stl").string(), false);
  std::ofstream(d / "bom.stl", std::ios::binary) << "\xEF\xBB\xBF" << slurp(d / "plain.stl");
  const CliResult r = kdmesh("mesh " + (d / "bom.stl").string() + " --size 1 -q");
  EXPECT_EQ(r.code, 0) << r.err;
}

// Two cubes touching along a face share its facets, facing opposite ways. They were refused as
// duplicated facets (and the message must not offer the duplicates repair, which cannot fix
// that); since issue 21 they are a wall written twice: two regions with one interface. Facets
// duplicated facing the same way are still refused, with the repair offered.
TEST(SmallDefects, TouchingCubesInOneFileAreTwoRegions) {
  const fs::path d = fresh("touching");
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 1);
  add_cube(m, 1, 1);
  kdmesh::write_stl(m, (d / "two.stl").string());
  const CliResult r = kdmesh("mesh " + (d / "two.stl").string() + " --size 0.5 -q --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["counts"]["bodies"], 2);
  EXPECT_GT(j["mesh_check"]["interface_faces"].get<int>(), 0);
  EXPECT_TRUE(contains(j["notices"].dump(), "internal walls")) << j["notices"].dump();
  kdmesh::SurfaceMesh twice;
  add_cube(twice, 0, 1);
  add_cube(twice, 0, 1);
  kdmesh::write_stl(twice, (d / "twice.stl").string());
  const CliResult t = kdmesh("mesh " + (d / "twice.stl").string() + " --size 0.5 -q");
  EXPECT_EQ(t.code, 4) << t.err;
  EXPECT_TRUE(contains(t.err, "duplicated facets")) << t.err;
  EXPECT_TRUE(contains(t.err, "--repair duplicates")) << t.err;
}

TEST(SmallDefects, BatchOfADirectorySaysSo) {
  const fs::path d = fresh("dir");
  const CliResult r = kdmesh("batch " + d.string() + " -q");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(contains(r.err, "is a directory")) << r.err;
  EXPECT_FALSE(contains(r.err, "empty batch file")) << r.err;
}

// A write that fails (here: the file size limit) names the path the user gave, with errno text.
TEST(SmallDefects, OutputErrorsNameTheUsersPathAndErrno) {
  const fs::path d = fresh("errno");
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 4);
  kdmesh::write_stl(m, (d / "c.stl").string());
  const std::string limit = "ulimit -f 2; trap '' XFSZ;";
  const CliResult v = kdmesh("mesh " + (d / "c.stl").string() + " --size 0.5 -q -o " + (d / "out.vtu").string(), limit);
  EXPECT_EQ(v.code, 6) << v.err;
  EXPECT_TRUE(contains(v.err, (d / "out.vtu").string() + ": write failed: File too large")) << v.err;
  EXPECT_FALSE(contains(v.err, ".tmp-")) << v.err;
  const CliResult s = kdmesh("mesh " + (d / "c.stl").string() + " --size 2 -q --summary " + (d / "s.json").string(), limit);
  EXPECT_EQ(s.code, 6) << s.err;
  EXPECT_TRUE(contains(s.err, (d / "s.json").string() + ": write failed: File too large")) << s.err;
  EXPECT_FALSE(fs::exists(d / "out.vtu"));
  EXPECT_FALSE(fs::exists(d / "s.json"));
}

TEST(SmallDefects, ConfigErrorsDoNotEchoControlBytes) {
  const fs::path d = fresh("control");
  std::ofstream(d / "c.stl") << "solid x\nendsolid x\n";
  std::ofstream(d / "jobs.yaml") << "jobs:\n  - name: a\n    input: c.stl\n    size: 1\n    \"ke\x1b[2Jy\x07\": 1\n";
  const CliResult r = kdmesh("batch " + (d / "jobs.yaml").string() + " -q");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(contains(r.err, "unknown key")) << r.err;
  EXPECT_FALSE(contains(r.err, "\x1b")) << r.err;
  EXPECT_FALSE(contains(r.err, "\x07")) << r.err;
  EXPECT_TRUE(contains(r.err, "\\x1b")) << r.err;
}

TEST(SmallDefects, EmptyOutputPathIsAUsageError) {
  const fs::path d = fresh("empty");
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 2);
  kdmesh::write_stl(m, (d / "c.stl").string());
  EXPECT_EQ(kdmesh("mesh " + (d / "c.stl").string() + " --size 1 -q -o ''").code, 2);
  EXPECT_EQ(kdmesh("mesh " + (d / "c.stl").string() + " --size 1 -q --summary ''").code, 2);
  std::ofstream(d / "p.xyz") << "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  EXPECT_EQ(kdmesh("delaunay " + (d / "p.xyz").string() + " -q -o ''").code, 2);
}

// A 251-character output name (the file-name limit is 255) is written: the temporary's
// suffix must not push it over the limit.
TEST(SmallDefects, LongOutputNameIsWritten) {
  const fs::path d = fresh("long");
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 2);
  kdmesh::write_stl(m, (d / "c.stl").string());
  const std::string name = std::string(247, 'n') + ".vtu";
  ASSERT_EQ(name.size(), 251u);
  const CliResult r = kdmesh("mesh " + (d / "c.stl").string() + " --size 1 -q -o " + (d / name).string() +
                             " --summary " + (d / (std::string(246, 's') + ".json")).string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(d / name));
}

TEST(SmallDefects, SecondYamlDocumentIsRefused) {
  const fs::path d = fresh("docs");
  std::ofstream(d / "c.stl") << "solid x\nendsolid x\n";
  std::ofstream(d / "jobs.yaml") << "jobs:\n  - {name: a, input: c.stl, size: 1}\n---\njobs:\n  - {name: b, input: c.stl, size: 1}\n";
  const CliResult r = kdmesh("batch " + (d / "jobs.yaml").string() + " -q");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(contains(r.err, (d / "jobs.yaml").string() + ":4:")) << r.err;
  EXPECT_TRUE(contains(r.err, "second YAML document")) << r.err;
}

}  // namespace
