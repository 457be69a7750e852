// kdmesh compare-tetgen end to end (both meshes, their measures, JSON, errors) and the pieces
// of tools/compare/tetgen_compare.h it is made of (switches, background mesh).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/surface_mesh.h"
#include "io/surface_io.h"
#include "mesher/tet_quality.h"
#include "sizing/sizing_field.h"
#include "tests/support/run_cli.h"
#include "tools/compare/tetgen_compare.h"
#include "tests/support/tetgen.h"

namespace {

namespace fs = std::filesystem;

using kdmesh::test::CliResult;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli_compare_tetgen"); }

CliResult kdmesh(const std::string& args) { return kdmesh::test::run_kdmesh(args, tmpdir()); }

const std::string kBlock = std::string(KDMESH_SOURCE_DIR) + "/models/block/block.stl";

/// The cube [lo, hi]^3 as 12 triangles appended to `m` (outward for outward = true).
void add_cube(kdmesh::SurfaceMesh& m, double lo, double hi, bool outward = true) {
  const std::uint32_t base = std::uint32_t(m.points.size());
  for (int i = 0; i < 8; ++i)
    m.points.push_back(i & 1 ? hi : lo, (i >> 1) & 1 ? hi : lo, (i >> 2) & 1 ? hi : lo);
  // Point i = (x, y, z) bits (1, 2, 4). Faces as quads, counter-clockwise from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    const int t[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
    for (int k = 0; k < 6; k += 3) {
      m.tris.push_back(base + std::uint32_t(t[k]));
      m.tris.push_back(base + std::uint32_t(t[outward ? k + 1 : k + 2]));
      m.tris.push_back(base + std::uint32_t(t[outward ? k + 2 : k + 1]));
    }
  }
}

std::size_t count_lines(const std::string& text) {
  std::size_t n = 0;
  std::istringstream s(text);
  for (std::string line; std::getline(s, line);) n += !line.empty();
  return n;
}

/// Properties every successful side must have: tets, no inverted ones, the solid's volume,
/// histogram-consistent dihedral counts, and edge lengths that follow the sizing field.
void expect_sound_side(const nlohmann::json& side, double volume, const std::string& who) {
  SCOPED_TRACE(who);
  ASSERT_EQ(side.value("status", std::string()), "ok");
  const nlohmann::json& m = side["measures"];
  EXPECT_GT(m["tets"].get<std::uint64_t>(), 0u);
  EXPECT_GT(m["nodes"].get<std::uint64_t>(), 3u);
  EXPECT_EQ(m["quality"]["tets"], m["tets"]);
  EXPECT_EQ(m["quality"]["inverted"].get<std::uint64_t>(), 0u);
  EXPECT_GT(m["quality"]["min_dihedral"].get<double>(), 0.0);
  EXPECT_NEAR(m["volume"]["solid"].get<double>(), volume, 1e-9 * volume);
  EXPECT_NEAR(m["volume"]["mesh"].get<double>(), volume, 1e-6 * volume);
  // The 18 histogram bins are 5 degrees wide: "< 5" is bin 0 and "< 10" bins 0 and 1.
  const auto& bins = m["quality"]["min_dihedral_hist"]["counts"];
  const auto below = [&](const char* k) { return m["min_dihedral_below"][k].get<std::uint64_t>(); };
  EXPECT_EQ(below("5"), bins[0].get<std::uint64_t>());
  EXPECT_EQ(below("10"), bins[0].get<std::uint64_t>() + bins[1].get<std::uint64_t>());
  EXPECT_LE(below("10"), below("12"));
  EXPECT_LE(below("12"), m["tets"].get<std::uint64_t>());
  // Both sides were sized by h(x): without it TetGen's block at --size 20 has edges ~ 5 h.
  const double r = m["size_fidelity"]["mean_ratio"].get<double>();
  EXPECT_GT(r, 0.7);
  EXPECT_LT(r, 1.5);
}

TEST(CliCompareTetgen, BlockBothSidesMeasuredTheSameWay) {
  KDMESH_REQUIRE_TETGEN();
  const CliResult r = kdmesh("compare-tetgen " + kBlock + " --size 20 --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);  // stdout is one JSON document
  expect_sound_side(j["kdmesh"], 1e6, "kdmesh");
  expect_sound_side(j["tetgen"], 1e6, "tetgen");
  EXPECT_EQ(j["tetgen"]["switches"], "pqzm");
  EXPECT_EQ(j["method"]["tetgen_sizing"], "mtr");
  EXPECT_GT(j["tetgen"]["counts"]["background_tets"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(j["tetgen"]["counts"]["holes"].get<std::uint64_t>(), 0u);
  EXPECT_GT(j["tetgen"]["seconds"]["tetrahedralize"].get<double>(), 0.0);
  // kdmesh's own summary and the comparison measure its mesh with the same code: equal figures.
  const nlohmann::json& kq = j["kdmesh"]["summary"]["quality"];
  const nlohmann::json& mq = j["kdmesh"]["measures"]["quality"];
  EXPECT_EQ(kq["tets"], mq["tets"]);
  EXPECT_DOUBLE_EQ(kq["min_dihedral"].get<double>(), mq["min_dihedral"].get<double>());
  EXPECT_DOUBLE_EQ(kq["max_radius_edge"].get<double>(), mq["max_radius_edge"].get<double>());
  // With --json the tables go to stderr; both columns are there.
  EXPECT_NE(r.err.find("tets with min dihedral < 12 deg"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("TetGen"), std::string::npos);
}

TEST(CliCompareTetgen, VoidIsAHoleForTetgenAndKeepWritesBothMeshes) {
  KDMESH_REQUIRE_TETGEN();
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 10);
  add_cube(m, 3, 7, false);  // a void: its facets face into it
  const fs::path stl = tmpdir() / "hollow.stl";
  kdmesh::write_stl(m, stl.string());
  const fs::path keep = tmpdir() / "keep";
  fs::remove_all(keep);
  const CliResult r = kdmesh("compare-tetgen " + stl.string() + " --size 2 --json -q --keep " + keep.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["tetgen"]["counts"]["holes"].get<std::uint64_t>(), 1u);
  const double volume = 1000 - 64;  // without the hole point TetGen would also fill the void
  expect_sound_side(j["kdmesh"], volume, "kdmesh");
  expect_sound_side(j["tetgen"], volume, "tetgen");
  EXPECT_GT(fs::file_size(keep / "kdmesh.vtu"), 0u);
  EXPECT_GT(fs::file_size(keep / "tetgen.vtu"), 0u);
}

TEST(CliCompareTetgen, PlainTextTables) {
  KDMESH_REQUIRE_TETGEN();
  const CliResult r = kdmesh("compare-tetgen " + kBlock + " --size 25 -q --tetgen-switches pq1.414/12");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // --quiet: nothing on stderr
  for (const char* s : {"quality", "kdmesh", "TetGen", "min dihedral (deg)", "mean radius ratio gamma",
                        "max radius-edge ratio", "time (s): kdmesh stage", "Refinement", "-pq1.414/12zm"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
}

TEST(CliCompareTetgen, OpenSurfaceFailsWithOneMessage) {
  KDMESH_REQUIRE_TETGEN();
  kdmesh::SurfaceMesh m;
  add_cube(m, 0, 10);
  m.tris.resize(m.tris.size() - 3);  // a hole in the surface
  const fs::path stl = tmpdir() / "open.stl";
  kdmesh::write_stl(m, stl.string());
  const CliResult r = kdmesh("compare-tetgen " + stl.string() + " --size 2 -q");
  EXPECT_EQ(r.code, 4) << r.err;  // geometry: the surface bounds no solid
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind("kdmesh: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("open.stl"), std::string::npos) << r.err;

  const CliResult missing = kdmesh("compare-tetgen " + (tmpdir() / "missing.stl").string() + " --size 2 -q");
  EXPECT_EQ(missing.code, 3) << missing.err;
  EXPECT_EQ(count_lines(missing.err), 1u) << missing.err;
  EXPECT_NE(missing.err.find("missing.stl"), std::string::npos) << missing.err;
}

TEST(CliCompareTetgen, TetgenStoppedIsTetgensFailureNotACrash) {
  KDMESH_REQUIRE_TETGEN();
  // 1 ms cannot fit TetGen's fork and its ~10^4-tet mesh: it is killed, kdmesh reports it.
  const CliResult r = kdmesh("compare-tetgen " + kBlock + " --size 8 --tetgen-timeout 0.001 --json -q");
  EXPECT_EQ(r.code, 1) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kdmesh"]["status"], "ok");
  EXPECT_EQ(j["tetgen"]["status"], "failed");
  EXPECT_EQ(j["tetgen"]["error"]["exit_code"], 1);
  EXPECT_EQ(count_lines(r.err.substr(r.err.find("kdmesh: error:"))), 1u) << r.err;
  EXPECT_NE(r.err.find("kdmesh: error: TetGen did not finish"), std::string::npos) << r.err;
}

TEST(CliCompareTetgen, UsageErrors) {  // exit 2 and one line with or without TetGen
  const std::string config = std::string(KDMESH_SOURCE_DIR) + "/models/block/block.yaml";
  for (const std::string& args : std::vector<std::string>{
           "compare-tetgen -q",                                                    // no surface, no --config
           "compare-tetgen " + kBlock + " -q",                                     // no --size
           "compare-tetgen " + kBlock + " --size 20 --tetgen-switches q -q",       // no p
           "compare-tetgen " + kBlock + " --size 20 --tetgen-switches pqr -q",     // refine
           "compare-tetgen " + kBlock + " --size 20 --tetgen-switches pqa5 -q",    // a volume and mtr
           "compare-tetgen " + kBlock + " --size 20 --tetgen-sizing volume --tetgen-size-factor 2 -q",
           "compare-tetgen --config " + config + " --size 3 -q",    // job options with --config
           "compare-tetgen --config " + config + " --job blok -q",  // no such job
       }) {
    const CliResult r = kdmesh(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << args << "\n" << r.err;
  }
}

// Built without TetGen (KDMESH_WITH_TETGEN=OFF), every TetGen feature asked for by name is
// refused, saying so, before any meshing: a usage error (exit 2), or in a batch file a config
// error at its line (exit 3). `delaunay --check` skips TetGen and still passes.
TEST(CliCompareTetgen, WithoutTetgenTetgenFeaturesAreRefusedClearly) {
  if (kdmesh::tetgen_available()) GTEST_SKIP() << "this kdmesh has TetGen";
  const std::string yaml = (tmpdir() / "check-tetgen.yaml").string();
  std::ofstream(yaml) << "jobs:\n  - {name: one, input: " << kBlock << ", size: 6, check: [tetgen]}\n";
  const std::string says = "built without TetGen (KDMESH_WITH_TETGEN=OFF)";
  for (const auto& [args, code] : std::vector<std::pair<std::string, int>>{
           {"compare-tetgen " + kBlock + " --size 6", 2},
           {"mesh " + kBlock + " --size 6 --check tetgen", 2},
           {"bench --kernels tetgen", 2},
           {"batch " + yaml, 3}}) {
    const CliResult r = kdmesh(args + " -q");
    EXPECT_EQ(r.code, code) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << args << "\n" << r.err;
  }
  const fs::path pts = tmpdir() / "no-tetgen.xyz";
  ASSERT_EQ(kdmesh("points --dist axes -n 500 --seed 2 -q -o " + pts.string()).code, 0);
  const CliResult r = kdmesh("delaunay " + pts.string() + " --check --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["check"]["pass"].get<bool>());
  EXPECT_NE(j["check"]["tetgen"]["skipped"].get<std::string>().find(says), std::string::npos);
}

TEST(TetgenCompare, SwitchStrings) {
  using kdmesh::TetgenSizing;
  using kdmesh::tetgen_switch_string;
  EXPECT_EQ(tetgen_switch_string("pq", TetgenSizing::mtr, 1), "pqzm");
  EXPECT_EQ(tetgen_switch_string("-pq1.414/12", TetgenSizing::mtr, 1), "pq1.414/12zm");
  EXPECT_EQ(tetgen_switch_string("pqzO7", TetgenSizing::none, 1), "pqzO7");
  EXPECT_EQ(tetgen_switch_string("pqa5e", TetgenSizing::none, 1), "pqa5ez");
  // volume: the regular tet of edge h, V = h^3 / (6 sqrt 2), written so that strtod reads it back.
  const std::string v = tetgen_switch_string("pq", TetgenSizing::volume, 2);
  ASSERT_EQ(v.rfind("pqza", 0), 0u) << v;
  EXPECT_DOUBLE_EQ(std::strtod(v.c_str() + 4, nullptr), 8 / (6 * std::sqrt(2.0)));
  for (const char* bad : {"q", "pqm", "pqr", "pqi", "pqN", "pqE", "pqo2", "pqc", "pq#", "pqa1"})
    EXPECT_THROW(tetgen_switch_string(bad, TetgenSizing::mtr, 1), kdmesh::UsageError) << bad;
}

TEST(TetgenCompare, BackgroundMeshCoversTheSurfaceAndCarriesTheSize) {
  kdmesh::SurfaceMesh cube;
  add_cube(cube, 0, 10);
  kdmesh::SizingOptions so;
  so.max_size = 3;
  so.zones.push_back({kdmesh::SizingZone::Kind::point, "p", 1, {0, 0, 0}, 30});
  const kdmesh::SizingField h = kdmesh::build_sizing_field(cube, so);
  kdmesh::PointSet nodes;
  for (int i = 1; i < 10; i += 2)
    for (int j = 1; j < 10; j += 3)
      for (int k = 1; k < 10; k += 4) nodes.push_back(i, j, k);
  nodes.push_back(0, 0, 0);  // a duplicate of a cube corner: merged
  const kdmesh::BackgroundMesh bg = kdmesh::make_background_mesh(nodes, cube, h);
  EXPECT_EQ(bg.points.size(), nodes.size() - 1 + 8);
  ASSERT_EQ(bg.size.size(), bg.points.size());
  for (std::uint32_t i = 0; i < bg.points.size(); ++i) EXPECT_EQ(bg.size[i], h(bg.points.p(i)));
  kdmesh::TetMesh m;
  m.points = bg.points;
  m.tets = bg.tets;
  std::vector<kdmesh::TetQuality> per;
  const kdmesh::QualitySummary q = kdmesh::summarize_quality(m, &per);
  EXPECT_EQ(q.inverted, 0u);
  double volume = 0;
  for (const auto& t : per) volume += t.volume;
  EXPECT_NEAR(volume, 1000.0, 1e-9);  // the hull of the cube's corners: the whole solid
}

TEST(TetgenCompare, ThinningKeepsOneNodePerCellOfTheSizeLevel) {
  kdmesh::SurfaceMesh cube;
  add_cube(cube, 0, 16);
  kdmesh::SizingOptions so;
  so.max_size = 1;  // no zones: h = 1 everywhere
  const kdmesh::SizingField h = kdmesh::build_sizing_field(cube, so);
  kdmesh::PointSet grid;  // the integer points of [0, 15]^3
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j)
      for (int k = 0; k < 16; ++k) grid.push_back(i, j, k);
  EXPECT_EQ(kdmesh::thin_nodes(grid, h, 0).xyz, grid.xyz);
  // spacing 4: 2^2 <= 4 h < 2^3, cells of edge 4; [0, 15] spans 4 cells per axis.
  const kdmesh::PointSet kept = kdmesh::thin_nodes(grid, h, 4);
  ASSERT_EQ(kept.size(), 64u);
  // The first node of each cell in input order is kept: its coordinates are multiples of 4.
  for (std::uint32_t i = 0; i < kept.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(std::fmod(kept.p(i)[k], 4.0), 0.0);
  // spacing 5 rounds down to the same level (2^2 <= 5 < 2^3): the same cells.
  EXPECT_EQ(kdmesh::thin_nodes(grid, h, 5).size(), 64u);
  EXPECT_EQ(kdmesh::thin_nodes(grid, h, 8).size(), 8u);
}

}  // namespace
