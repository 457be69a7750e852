// kdmesh mesh and kdmesh batch end to end: outputs and summaries, failure isolation between
// batch jobs, seeded determinism under concurrency, and that failed jobs write nothing.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <vector>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/surface_mesh.h"
#include "io/medit_reader.h"
#include "io/msh_reader.h"
#include "io/surface_io.h"
#include "tests/support/run_cli.h"
#include "tests/support/sanitizer.h"
#include "tools/app/mesh_job.h"
#include "tests/support/tetgen.h"

namespace {

namespace fs = std::filesystem;

using kdmesh::test::CliResult;
using kdmesh::test::slurp;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli_mesh"); }

CliResult kdmesh(const std::string& args) { return kdmesh::test::run_kdmesh(args, tmpdir()); }

/// The cube [0, e]^3 as 12 outward triangles (each face split along a diagonal).
kdmesh::SurfaceMesh cube(double e) {
  kdmesh::SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.push_back(e * (i & 1), e * ((i >> 1) & 1), e * ((i >> 2) & 1));
  // Point i = (x, y, z) bits (1, 2, 4). Faces as quads a b c d, counter-clockwise from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (const std::uint32_t t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.tris.push_back(t);
  return m;
}

fs::path write_cube(const std::string& name, double e, bool open = false) {
  kdmesh::SurfaceMesh m = cube(e);
  if (open) m.tris.resize(m.tris.size() - 3);  // drop one facet: a hole
  const fs::path p = tmpdir() / name;
  kdmesh::write_stl(m, p.string());
  return p;
}

bool has_temp_leftovers(const fs::path& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  return false;
}

std::size_t count_lines(const std::string& text) {
  std::size_t n = 0;
  std::istringstream s(text);
  for (std::string line; std::getline(s, line);)
    if (!line.empty() && line[0] != '#') ++n;
  return n;
}

TEST(CliMesh, CubeWritesVtuSummaryAndNodes) {
  const fs::path stl = write_cube("cube10.stl", 10);
  const fs::path dir = tmpdir() / "mesh-ok";
  fs::remove_all(dir);
  const fs::path vtu = dir / "cube.vtu", json = dir / "cube.json", xyz = dir / "cube.xyz";
  const CliResult r = kdmesh("mesh " + stl.string() + " --size 3 --seed 3 --json -q -o " + vtu.string() +
                             " --summary " + json.string() + " --nodes " + xyz.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);  // stdout is exactly one JSON document
  EXPECT_EQ(j, nlohmann::json::parse(slurp(json)));  // the summary file is the same document
  EXPECT_EQ(j["status"], "ok");
  for (const char* k : {"counts", "seconds", "quality", "size_fidelity", "mesh_check", "notices", "outputs"})
    EXPECT_TRUE(j.contains(k)) << k;
  for (const char* k : {"read", "prepare", "features", "sizing", "place", "mesh", "mesh_check", "quality",
                        "write", "total"})
    EXPECT_TRUE(j["seconds"].contains(k)) << k;
  const auto& c = j["counts"];
  EXPECT_EQ(c["surface_points"], 8);
  EXPECT_EQ(c["surface_facets"], 12);
  EXPECT_EQ(c["bodies"], 1);
  EXPECT_EQ(c["feature_edges"], 12);  // every cube edge turns by 90 >= 30 degrees
  EXPECT_EQ(c["feature_corners"], 8);
  const auto& k = c["nodes_by_kind"];
  EXPECT_EQ(k["corner"], 8);
  const std::uint64_t nb = k["corner"].get<std::uint64_t>() + k["edge"].get<std::uint64_t>() +
                           k["surface"].get<std::uint64_t>();
  EXPECT_EQ(nb + k["interior"].get<std::uint64_t>(), c["nodes"].get<std::uint64_t>());
  // The boundary is a closed genus-0 triangulation of the nb boundary nodes: Euler's
  // V - E + F = 2 with 3F = 2E gives F = 2V - 4.
  EXPECT_EQ(c["boundary_faces"].get<std::uint64_t>(), 2 * nb - 4);
  EXPECT_GT(c["tets"].get<std::uint64_t>(), 0u);
  EXPECT_TRUE(j["mesh_check"]["pass"].get<bool>());
  EXPECT_NEAR(j["mesh_check"]["mesh_volume"].get<double>(), 1000.0, 1e-9 * 1000);  // 10^3
  EXPECT_GT(j["quality"]["min_dihedral"].get<double>(), 0.0);
  EXPECT_GT(j["size_fidelity"]["edges"].get<std::uint64_t>(), c["tets"].get<std::uint64_t>());
  EXPECT_GT(j["size_fidelity"]["mean_ratio"].get<double>(), 0.5);
  EXPECT_LT(j["size_fidelity"]["mean_ratio"].get<double>(), 2.0);
  // Outputs: the nodes file has one line per node; the VTU carries the mesh's data arrays.
  EXPECT_EQ(count_lines(slurp(xyz)), c["nodes"].get<std::uint64_t>());
  const std::string xml = slurp(vtu);
  EXPECT_NE(xml.find("UnstructuredGrid"), std::string::npos);
  EXPECT_NE(xml.find("node_kind"), std::string::npos);
  EXPECT_FALSE(has_temp_leftovers(dir));
}

// Solver formats from the pipeline: every patch and curve of the cube is a group
// (--patch-groups), the elements read back from the .msh and .mesh agree with the summary, and
// at order 2 every boundary mid-edge node of the (flat-faced) cube sits at its edge midpoint.
TEST(CliMesh, SolverFormatsCarryTheBoundaryGroups) {
  const fs::path stl = write_cube("cube-fe.stl", 10);
  const fs::path dir = tmpdir() / "mesh-fe";
  fs::remove_all(dir);
  for (const int order : {1, 2}) {
    const std::string o = std::to_string(order);
    const fs::path msh = dir / ("c" + o + ".msh"), inp = dir / ("c" + o + ".inp"), mesh = dir / ("c" + o + ".mesh");
    const CliResult r = kdmesh("mesh " + stl.string() + " --size 4 --json -q --patch-groups --element-order " + o +
                               " --msh " + msh.string() + " --inp " + inp.string() + " --medit " + mesh.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["counts"]["patches"], 6);
    EXPECT_EQ(j["counts"]["curves"], 12);
    EXPECT_TRUE(j["boundary"]["pass"].get<bool>());
    ASSERT_EQ(j["groups"].size(), 1u + 6u + 12u);  // body_1, patch_1..6, curve_1..12
    for (const fs::path& f : {msh, mesh}) {
      const kdmesh::FeMesh fe = f.extension() == ".msh" ? kdmesh::read_msh(f.string()) : kdmesh::read_medit(f.string());
      EXPECT_EQ(fe.order, order) << f;
      EXPECT_EQ(fe.num_tets(), j["counts"]["tets"].get<std::size_t>()) << f;
      EXPECT_EQ(fe.num_faces(), j["counts"]["boundary_faces"].get<std::size_t>()) << f;
      EXPECT_EQ(fe.num_edges(), j["counts"]["mesh_feature_edges"].get<std::size_t>()) << f;
      if (order == 2)
        for (std::size_t t = 0; t < fe.num_faces(); ++t) {
          const std::uint32_t* v = &fe.faces[6 * t];
          const int ends[3][2] = {{0, 1}, {1, 2}, {2, 0}};
          for (int e = 0; e < 3; ++e)
            for (int k = 0; k < 3; ++k)
              ASSERT_NEAR(fe.points.p(v[3 + e])[k],  // to the 16 digits the text formats keep
                          0.5 * (fe.points.p(v[ends[e][0]])[k] + fe.points.p(v[ends[e][1]])[k]), 1e-13);
        }
    }
    const std::string deck = slurp(inp);
    EXPECT_NE(deck.find(order == 1 ? "TYPE=C3D4" : "TYPE=C3D10"), std::string::npos);
    EXPECT_NE(deck.find("*SURFACE, NAME=patch_1"), std::string::npos);
    EXPECT_NE(deck.find("*NSET, NSET=curve_12"), std::string::npos);
  }
}

// --body NAME=PATH (issue 21): two cubes apart are two regions, named in the summary and as the
// INP's volume ELSETs; two touching cubes are refused (exit 4) naming both; a surface and
// --body together, or neither, are usage errors.
// Regression (issue 21): bodies that touch were refused; they now share one interface, its own
// group, and only overlapping bodies are refused.
TEST(CliMesh, BodiesAreNamedRegionsTouchingOnesShareAnInterfaceOverlappingOnesAreRefused) {
  auto shifted = [](double dx, const std::string& name) {
    kdmesh::SurfaceMesh m = cube(10);
    for (std::size_t i = 0; i < m.points.size(); ++i) m.points.xyz[3 * i] += dx;
    const fs::path p = tmpdir() / name;
    kdmesh::write_stl(m, p.string());
    return p.string();
  };
  const std::string left = shifted(0, "left.stl"), right = shifted(20, "right.stl"), next = shifted(10, "next.stl"),
                    half = shifted(5, "half.stl");
  const fs::path inp = tmpdir() / "bodies.inp";
  const CliResult r = kdmesh("mesh --body left=" + left + " --body right=" + right + " --size 4 --json -q --inp " +
                             inp.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["counts"]["bodies"], 2);
  ASSERT_EQ(j["bodies"].size(), 2u);
  EXPECT_EQ(j["bodies"][0]["name"], "left");
  EXPECT_EQ(j["bodies"][1]["name"], "right");
  EXPECT_NEAR(j["bodies"][1]["mesh_volume"].get<double>(), 1000.0, 1e-6);
  const std::string deck = slurp(inp);
  EXPECT_NE(deck.find("*ELSET, ELSET=left"), std::string::npos);
  EXPECT_NE(deck.find("*ELSET, ELSET=right"), std::string::npos);

  const fs::path touch_inp = tmpdir() / "touch.inp";
  const CliResult touch =
      kdmesh("mesh --body left=" + left + " --body next=" + next + " --size 4 -q --json --inp " + touch_inp.string());
  ASSERT_EQ(touch.code, 0) << touch.err;
  const auto t = nlohmann::json::parse(touch.out);
  EXPECT_GT(t["mesh_check"]["interface_faces"].get<int>(), 0);
  EXPECT_EQ(t["mesh_check"]["straddling_tets"], 0);
  EXPECT_GT(t["counts"]["interface_facets"].get<int>(), 0);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(t["bodies"][k]["mesh_volume"].get<double>(), 1000.0, 1e-6);
  EXPECT_EQ(t["counts"]["interface_slivers"], 0);
  // The interfaces' own work, timed inside the stages: each part within its stage, the sum
  // within the job's time.
  const auto& sec = t["seconds"];
  const auto& is = sec["interface_stages"];
  ASSERT_TRUE(is.is_object()) << sec.dump();
  EXPECT_LE(is["imprint"].get<double>(), sec["prepare"].get<double>());
  EXPECT_LE(is["place"].get<double>(), sec["place"].get<double>());
  EXPECT_LE(is["regions"].get<double>(), sec["mesh"].get<double>());
  EXPECT_LE(is["check"].get<double>(), sec["mesh_check"].get<double>());
  EXPECT_LE(is["groups"].get<double>(), sec["groups"].get<double>());
  EXPECT_NEAR(is["total"].get<double>(),
              is["imprint"].get<double>() + is["place"].get<double>() + is["regions"].get<double>() +
                  is["check"].get<double>() + is["groups"].get<double>(), 1e-9);
  EXPECT_LE(is["total"].get<double>(), sec["total"].get<double>());
  EXPECT_FALSE(j["seconds"].contains("interface_stages"));  // apart: no interfaces
  const std::string touch_deck = slurp(touch_inp);
  EXPECT_NE(touch_deck.find("NAME=left-next"), std::string::npos);
  EXPECT_NE(touch_deck.find("NAME=left-exterior"), std::string::npos);
  const CliResult overlap = kdmesh("mesh --body left=" + left + " --body half=" + half + " --size 4 -q");
  EXPECT_EQ(overlap.code, 4);
  EXPECT_NE(overlap.err.find("bodies 'left' and 'half' overlap"), std::string::npos) << overlap.err;
  EXPECT_EQ(kdmesh("mesh " + left + " --body right=" + right + " --size 4 -q").code, 2);
  EXPECT_EQ(kdmesh("mesh --size 4 -q").code, 2);
  EXPECT_EQ(kdmesh("mesh --body nopath --size 4 -q").code, 2);
}

TEST(CliMesh, DelaunayChecksOfTheNodes) {
  KDMESH_REQUIRE_TETGEN();
  const fs::path stl = write_cube("cube4.stl", 4);
  const CliResult r = kdmesh("mesh " + stl.string() + " --size 1.5 --check tetgen,delaunay --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("delaunay_check"));
  EXPECT_TRUE(j["delaunay_check"]["pass"].get<bool>());
  EXPECT_TRUE(j["delaunay_check"]["validity"]["pass"].get<bool>());
  EXPECT_TRUE(j["delaunay_check"].contains("tetgen"));
  EXPECT_TRUE(j["delaunay_check"].contains("cgal"));
  // The Delaunay tetrahedralization of the nodes fills their convex hull, the cube: volume 4^3.
  EXPECT_NEAR(j["delaunay_check"]["validity"]["volume"].get<double>(), 64.0, 1e-9 * 64);
}

TEST(CliMesh, RefineEdgesAddsNodesAlongFeatures) {
  const fs::path stl = write_cube("cube6.stl", 6);
  const CliResult plain = kdmesh("mesh " + stl.string() + " --size 2 --json -q");
  const CliResult fine = kdmesh("mesh " + stl.string() + " --size 2 --refine-edges 30 --edge-size 0.5 --json -q");
  ASSERT_EQ(plain.code, 0) << plain.err;
  ASSERT_EQ(fine.code, 0) << fine.err;
  const auto a = nlohmann::json::parse(plain.out), b = nlohmann::json::parse(fine.out);
  EXPECT_EQ(b["options"]["zones"], 1);
  // 12 edges of length 6 at spacing ~0.5 instead of ~2: several times more edge nodes.
  EXPECT_GT(b["counts"]["nodes_by_kind"]["edge"].get<double>(),
            2 * a["counts"]["nodes_by_kind"]["edge"].get<double>());
}

TEST(CliMesh, ErrorsHaveTheirExitCodesAndWriteNothing) {
  const fs::path dir = tmpdir() / "mesh-errors";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path vtu = dir / "x.vtu", json = dir / "x.json";
  const std::string outs = " -o " + vtu.string() + " --summary " + json.string();
  // Missing input: exit 3, the message names the file.
  CliResult r = kdmesh("mesh " + (dir / "none.stl").string() + " --size 1 -q" + outs);
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("none.stl"), std::string::npos) << r.err;
  // An open surface bounds no solid: exit 4.
  const fs::path open = write_cube("open.stl", 1, true);
  r = kdmesh("mesh " + open.string() + " --size 0.5 -q --json" + outs);
  EXPECT_EQ(r.code, 4) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "failed");
  EXPECT_EQ(j["error"]["exit_code"], 4);
  // Bad options: exit 2.
  const fs::path ok = write_cube("ok.stl", 1);
  EXPECT_EQ(kdmesh("mesh " + ok.string() + " --size 0 -q" + outs).code, 2);
  EXPECT_EQ(kdmesh("mesh " + ok.string() + " --size 1 --min-size 2 -q" + outs).code, 2);
  EXPECT_EQ(kdmesh("mesh " + ok.string() + " --size 1 --check nothing -q" + outs).code, 2);
  EXPECT_FALSE(fs::exists(vtu));
  EXPECT_FALSE(fs::exists(json));
  EXPECT_FALSE(has_temp_leftovers(dir));
}

// The memory estimate is printed before node placement; a job whose estimate exceeds
// --max-memory is refused there (exit 7), before anything large is allocated.
TEST(CliMesh, MemoryEstimateAndMaxMemory) {
  const fs::path dir = tmpdir() / "mesh-memory";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path cube = write_cube("mem.stl", 100);
  const fs::path vtu = dir / "x.vtu";
  // Size 0.01 in a 100-edge cube: ~1e12 nodes, refused in a fraction of a second.
  CliResult r = kdmesh("mesh " + cube.string() + " --size 0.01 --max-memory 2G --json -o " + vtu.string());
  EXPECT_EQ(r.code, 7) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["error"]["type"], "resource");
  EXPECT_TRUE(j["estimate"]["capped"].get<bool>());
  EXPECT_GT(j["estimate"]["peak_bytes"].get<double>(), 2e9);
  EXPECT_DOUBLE_EQ(j["estimate"]["limit_bytes"].get<double>(), 2e9);
  const std::string msg = j["error"]["message"];
  EXPECT_NE(msg.find("needs an estimated more than"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the limit is 2 GB"), std::string::npos) << msg;
  EXPECT_NE(r.err.find("estimate: more than"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("placing nodes"), std::string::npos) << r.err;
  EXPECT_FALSE(j.contains("counts") && j["counts"].contains("placed_nodes"));
  EXPECT_FALSE(fs::exists(vtu));
  // A feasible job reports its estimate, within a factor 2 of what it placed (a 4x4x4 cube
  // at size 1: the estimate integrates the same density the placement follows).
  const fs::path small = write_cube("mem-small.stl", 4);
  r = kdmesh("mesh " + small.string() + " --size 1 --max-memory 1G --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json k = nlohmann::json::parse(r.out);
  const double est = k["estimate"]["nodes"], placed = k["counts"]["placed_nodes"];
  EXPECT_GT(est, 0.5 * placed);
  EXPECT_LT(est, 2 * placed);
  EXPECT_FALSE(k["estimate"]["capped"].get<bool>());
  // Bad amounts are usage errors.
  EXPECT_EQ(kdmesh("mesh " + small.string() + " --size 1 --max-memory lots -q").code, 2);
  EXPECT_EQ(kdmesh("mesh " + small.string() + " --size 1 --max-memory none -q").code, 0);
}

TEST(CliMesh, OutputsAreAllOrNothing) {
  const fs::path stl = write_cube("cube2.stl", 2);
  const fs::path dir = tmpdir() / "mesh-outputs";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "plainfile") << "not a directory\n";
  // The VTU and the summary can be written, the nodes cannot (their directory would have to be
  // a regular file): the job fails with exit 6 and leaves neither the VTU nor the summary.
  const CliResult r = kdmesh("mesh " + stl.string() + " --size 1 -q -o " + (dir / "m.vtu").string() +
                             " --summary " + (dir / "m.json").string() + " --nodes " +
                             (dir / "plainfile" / "m.xyz").string());
  EXPECT_EQ(r.code, 6) << r.err;
  EXPECT_NE(r.err.find("plainfile"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "m.vtu"));
  EXPECT_FALSE(fs::exists(dir / "m.json"));
  EXPECT_FALSE(has_temp_leftovers(dir));
}

TEST(CliMesh, HelpListsTheOptions) {
  const CliResult m = kdmesh("mesh --help");
  EXPECT_EQ(m.code, 0);
  for (const char* opt : {"--size", "--refine-edges", "--edge-size", "--min-size", "--gradation", "--sharp-angle",
                          "--scale", "--order", "--seed", "--check", "--summary", "--nodes", "--json"})
    EXPECT_NE(m.out.find(opt), std::string::npos) << opt;
  const CliResult b = kdmesh("batch --help");
  EXPECT_EQ(b.code, 0);
  for (const char* opt : {"--jobs", "--out-dir", "--only", "--json"}) EXPECT_NE(b.out.find(opt), std::string::npos) << opt;
  EXPECT_EQ(kdmesh("batch x.yaml --jobs 0").code, 2);
}

// The library entry point behind both commands: never throws, reports progress in [0, 1].
TEST(MeshJob, ReportsProgressAndReturnsErrorsInsteadOfThrowing) {
  kdmesh::MeshJob job;
  job.name = "lib";
  job.input = write_cube("lib-cube.stl", 3).string();
  job.sizing.max_size = 1;
  std::map<std::string, std::pair<double, double>> seen;  // stage -> (min, max) fraction
  std::vector<std::string> logs;
  kdmesh::MeshJobCallbacks cb;
  cb.log = [&](const std::string& s) { logs.push_back(s); };
  cb.progress = [&](const std::string& stage, double f) {
    auto [it, fresh] = seen.try_emplace(stage, f, f);
    it->second.first = std::min(it->second.first, f);
    it->second.second = std::max(it->second.second, f);
  };
  const kdmesh::MeshJobResult ok = kdmesh::run_mesh_job(job, cb);
  ASSERT_TRUE(ok.ok()) << ok.summary.dump(2);
  EXPECT_FALSE(seen.empty());
  for (const auto& [stage, range] : seen) {
    EXPECT_GE(range.first, 0.0) << stage;
    EXPECT_LE(range.second, 1.0) << stage;
  }
  EXPECT_FALSE(logs.empty());
  EXPECT_FALSE(ok.summary.contains("error"));

  job.input = (tmpdir() / "missing.stl").string();
  kdmesh::MeshJobResult bad;
  EXPECT_NO_THROW(bad = kdmesh::run_mesh_job(job));
  EXPECT_EQ(bad.code, kdmesh::ExitCode::input);
  EXPECT_EQ(bad.summary["status"], "failed");
  EXPECT_EQ(bad.summary["error"]["type"], "input");
  EXPECT_NE(bad.summary["error"]["message"].get<std::string>().find("missing.stl"), std::string::npos);

  job.input = write_cube("lib-cube2.stl", 3).string();
  job.sizing.max_size = -1;  // a bad option is a usage error, not a crash
  EXPECT_EQ(kdmesh::run_mesh_job(job).code, kdmesh::ExitCode::usage);
}

/// A batch of three jobs; `broken` is an STL that exists but is malformed.
fs::path write_three_job_batch() {
  write_cube("b-cube10.stl", 10);
  write_cube("b-cube4.stl", 4);
  std::ofstream(tmpdir() / "broken.stl") << "solid broken\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n";
  const fs::path yaml = tmpdir() / "three.yaml";
  std::ofstream(yaml) << R"(# three jobs, the middle one broken
defaults:
  order: kd-bfs
  seed: 11
jobs:
  - name: big
    input: b-cube10.stl
    size: 3
    output: {vtu: big.vtu, summary: big.json, nodes: big.xyz}
  - name: broken
    input: broken.stl
    size: 1
    output: {vtu: broken.vtu, summary: broken.json, nodes: broken.xyz}
  - name: small
    input: b-cube4.stl
    size: 1
    order: hilbert
    zones:
      - {type: point, size: 0.4, at: [0, 0, 0]}
    output: {vtu: small.vtu, summary: small.json, nodes: small.xyz}
)";
  return yaml;
}

TEST(CliBatch, FailedJobIsIsolatedAndConcurrencyIsDeterministic) {
  const fs::path yaml = write_three_job_batch();
  nlohmann::json runs[2];
  fs::path dirs[2];
  for (int t = 0; t < 2; ++t) {
    dirs[t] = tmpdir() / ("batch-j" + std::to_string(t + 1));
    fs::remove_all(dirs[t]);
    const CliResult r = kdmesh("batch " + yaml.string() + " --jobs " + std::to_string(t + 1) +
                               " --out-dir " + dirs[t].string() + " --json");
    // The broken job fails with an input error (3); the only failure, so the batch's code is 3.
    EXPECT_EQ(r.code, 3) << r.err;
    runs[t] = nlohmann::json::parse(r.out);
    EXPECT_NE(r.err.find("[broken]"), std::string::npos) << r.err;  // progress lines carry the name
    EXPECT_NE(r.err.find("broken.stl"), std::string::npos) << r.err;
    const auto& jobs = runs[t]["jobs"];
    ASSERT_EQ(jobs.size(), 3u);
    EXPECT_EQ(jobs[0]["job"], "big");
    EXPECT_EQ(jobs[0]["status"], "ok");
    EXPECT_EQ(jobs[1]["job"], "broken");
    EXPECT_EQ(jobs[1]["status"], "failed");
    EXPECT_EQ(jobs[1]["error"]["type"], "input");
    EXPECT_EQ(jobs[1]["error"]["exit_code"], 3);
    EXPECT_EQ(jobs[2]["status"], "ok");
    EXPECT_EQ(runs[t]["succeeded"], 2);
    EXPECT_EQ(runs[t]["failed"], 1);
    for (const char* f : {"big.vtu", "big.json", "big.xyz", "small.vtu", "small.json", "small.xyz"})
      EXPECT_TRUE(fs::exists(dirs[t] / f)) << f;
    for (const char* f : {"broken.vtu", "broken.json", "broken.xyz"}) EXPECT_FALSE(fs::exists(dirs[t] / f)) << f;
    EXPECT_FALSE(has_temp_leftovers(dirs[t]));
  }
  // Seeded determinism: --jobs 2 gives what --jobs 1 gives, down to the node coordinates.
  for (int i : {0, 2}) {
    EXPECT_EQ(runs[0]["jobs"][i]["counts"], runs[1]["jobs"][i]["counts"]) << i;
    EXPECT_EQ(runs[0]["jobs"][i]["quality"]["min_dihedral"], runs[1]["jobs"][i]["quality"]["min_dihedral"]);
  }
  EXPECT_EQ(slurp(dirs[0] / "big.xyz"), slurp(dirs[1] / "big.xyz"));
  EXPECT_EQ(slurp(dirs[0] / "small.xyz"), slurp(dirs[1] / "small.xyz"));
}

// A job whose process crashes (here a SIGSEGV injected through KDMESH_INJECT_CRASH, the
// documented test hook of tools/app/job_process.h) fails alone: the batch goes on, the other
// jobs' outputs are written, and the crashed job leaves neither outputs nor temporaries, even
// when it dies with one output already written to its temporary file.
TEST(CliBatch, CrashedJobIsIsolatedAndLeavesNoTemporaries) {
  const fs::path yaml = write_three_job_batch();
  const fs::path dir = tmpdir() / "batch-crash";
  fs::remove_all(dir);
  const std::string crash_at = "big@writing " + (dir / "big.xyz").string();
  const CliResult r = kdmesh::test::run_kdmesh("batch " + yaml.string() + " --jobs 2 --only big,small --out-dir " +
                                                   dir.string() + " --json",
                                               tmpdir(), "KDMESH_INJECT_CRASH='" + crash_at + "'");
  EXPECT_EQ(r.code, 1) << r.err;  // internal error: a crash is a bug
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["jobs"].size(), 2u);
  EXPECT_EQ(j["jobs"][0]["job"], "big");
  EXPECT_EQ(j["jobs"][0]["status"], "failed");
  const std::string message = j["jobs"][0]["error"]["message"];
#if KDMESH_UNDER_ASAN
  // Under AddressSanitizer its SEGV handler catches the signal, reports, and then aborts or
  // exits with status 1 (by ASAN_OPTIONS): the job is lost all the same.
  EXPECT_TRUE(message.find("crashed: killed by signal") != std::string::npos ||
              message.find("without a result") != std::string::npos)
      << message;
#else
  EXPECT_NE(message.find("crashed: killed by signal 11"), std::string::npos) << message;
#endif
  EXPECT_EQ(j["jobs"][1]["status"], "ok");
  EXPECT_TRUE(fs::exists(dir / "small.vtu"));
  EXPECT_TRUE(fs::exists(dir / "small.json"));
  for (const char* f : {"big.vtu", "big.json", "big.xyz"}) EXPECT_FALSE(fs::exists(dir / f)) << f;
  EXPECT_FALSE(has_temp_leftovers(dir));
  EXPECT_NE(r.err.find("writing " + (dir / "big.vtu").string()), std::string::npos)
      << "the crash must come after the first output was opened:\n" << r.err;
}

// Under a limit on processes and threads (a batch system's task limit, `ulimit -u`): the
// batch as an unprivileged user with RLIMIT_NPROC 2 can start one job process, which can
// start no thread.
// Regression: the batch stopped with "cannot start a job process" when its second job's
// fork failed, and a job process whose threads could not start failed with "internal error:
// Resource temporarily unavailable". Now the jobs run one at a time, each on its one thread,
// and give the nodes of a run without the limit.
TEST(CliBatch, RegressionProcessLimitRunsTheJobsFewerAtATime) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root, to run the batch as another user under RLIMIT_NPROC";
  if (std::system("command -v prlimit >/dev/null && command -v setpriv >/dev/null") != 0)
    GTEST_SKIP() << "needs prlimit and setpriv (util-linux)";
  const fs::path yaml = write_three_job_batch();
  const fs::path free_dir = tmpdir() / "batch-nproc-free", dir = tmpdir() / "batch-nproc";
  for (const fs::path& d : {free_dir, dir}) {
    fs::remove_all(d);
    fs::create_directories(d);
    fs::permissions(d, fs::perms::all);  // the other user writes there
  }
  const std::string args = "batch " + yaml.string() + " --jobs 2 --only big,small --json --out-dir ";
  const CliResult free = kdmesh(args + free_dir.string());
  ASSERT_EQ(free.code, 0) << free.err;
  // The limit counts every process of the user: a user id of this test alone (ctest runs
  // tests at once), one that no one else uses.
  const std::string user = std::to_string(50000 + ::getpid() % 10000);
  const CliResult r = kdmesh::test::run_kdmesh(
      args + dir.string(), tmpdir(), "prlimit --nproc=2:2 setpriv --reuid=" + user + " --regid=" + user + " --clear-groups");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("cannot start another job process"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("running 1 job(s) at a time"), std::string::npos) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["succeeded"], 2);
  for (const char* f : {"big.xyz", "small.xyz"}) EXPECT_EQ(slurp(dir / f), slurp(free_dir / f)) << f;
  EXPECT_FALSE(slurp(dir / "big.xyz").empty());
  EXPECT_FALSE(has_temp_leftovers(dir));
}

TEST(CliBatch, HumanTableNamesTheFailedJob) {
  const fs::path yaml = write_three_job_batch();
  const fs::path dir = tmpdir() / "batch-human";
  fs::remove_all(dir);
  const CliResult r = kdmesh("batch " + yaml.string() + " --out-dir " + dir.string() + " -q --only broken,small");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.out.find("min dihedral"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("FAILED (input)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("job 'broken' failed"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("big"), std::string::npos) << r.out;  // --only left it out
  EXPECT_TRUE(fs::exists(dir / "small.vtu"));
  EXPECT_FALSE(fs::exists(dir / "big.vtu"));
  EXPECT_EQ(kdmesh("batch " + yaml.string() + " --only nosuch -q").code, 2);
}

TEST(CliBatch, ConfigErrorsStopBeforeAnyJobRuns) {
  write_cube("cfg-cube.stl", 2);
  const fs::path yaml = tmpdir() / "bad.yaml";
  std::ofstream(yaml) << "jobs:\n  - name: a\n    input: cfg-cube.stl\n    size: 1\n    output: {vtu: a.vtu}\n"
                         "  - name: b\n    input: cfg-cube.stl\n    sise: 1\n";
  const fs::path dir = tmpdir() / "batch-cfg";
  fs::remove_all(dir);
  const CliResult r = kdmesh("batch " + yaml.string() + " --out-dir " + dir.string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find(yaml.string() + ":8:"), std::string::npos) << r.err;  // "sise:" is line 8
  EXPECT_NE(r.err.find("did you mean 'size'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "a.vtu"));  // job a never ran
}

TEST(CliBatch, AllSucceedingExitsZero) {
  KDMESH_REQUIRE_TETGEN();
  write_cube("ok-cube.stl", 3);
  const fs::path yaml = tmpdir() / "ok.yaml";
  // Both jobs run TetGen at the same time (-j 2): TetGen's global state must not be shared.
  std::ofstream(yaml) << "jobs:\n  - {name: one, input: ok-cube.stl, size: 0.5, check: [tetgen]}\n"
                         "  - {name: two, input: ok-cube.stl, size: 0.6, check: [delaunay, tetgen]}\n";
  const CliResult r = kdmesh("batch " + yaml.string() + " -j 2 --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["succeeded"], 2);
  for (int i : {0, 1}) {
    EXPECT_TRUE(j["jobs"][i]["delaunay_check"]["pass"].get<bool>()) << i;
    EXPECT_TRUE(j["jobs"][i]["delaunay_check"]["tetgen"]["pass"].get<bool>()) << i;
  }
}

}  // namespace
