// The kdmesh executable end to end: exit codes, messages, JSON, outputs, and that failures
// write nothing.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/cpu_count.h"
#include "tests/support/run_cli.h"
#include "tests/support/tetgen.h"

namespace {

namespace fs = std::filesystem;

using kdmesh::test::CliResult;
using kdmesh::test::slurp;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli"); }

CliResult kdmesh(const std::string& args) { return kdmesh::test::run_kdmesh(args, tmpdir()); }

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = tmpdir() / name;
  std::ofstream(p) << text;
  return p;
}

bool has_temp_leftovers(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  return false;
}

TEST(Cli, HelpForEverySubcommand) {
  EXPECT_EQ(kdmesh("--help").code, 0);
  for (const char* sub : {"points", "delaunay"}) {
    const CliResult r = kdmesh(std::string(sub) + " --help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_NE(r.out.find("--json"), std::string::npos) << sub;
  }
  EXPECT_EQ(kdmesh("no-such-command").code, 2);
}

TEST(Cli, PointsAreDeterministicForASeed) {
  const fs::path a = tmpdir() / "a.xyz", b = tmpdir() / "b.xyz", c = tmpdir() / "c.xyz";
  ASSERT_EQ(kdmesh("points --dist spiral -n 500 --seed 4 -q -o " + a.string()).code, 0);
  ASSERT_EQ(kdmesh("points --dist spiral -n 500 --seed 4 -q -o " + b.string()).code, 0);
  ASSERT_EQ(kdmesh("points --dist spiral -n 500 --seed 5 -q -o " + c.string()).code, 0);
  EXPECT_EQ(slurp(a), slurp(b));
  EXPECT_NE(slurp(a), slurp(c));
  EXPECT_EQ(kdmesh("points --dist nowhere -n 5 -o " + a.string()).code, 2);
}

TEST(Cli, DelaunayCheckJsonAndVtu) {
  KDMESH_REQUIRE_TETGEN();
  const fs::path pts = tmpdir() / "axes.xyz", vtu = tmpdir() / "axes.vtu";
  ASSERT_EQ(kdmesh("points --dist axes -n 3000 --seed 2 -q -o " + pts.string()).code, 0);
  fs::remove(vtu);
  const CliResult r = kdmesh("delaunay " + pts.string() + " --order kd-bfs --check --json -o " + vtu.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);  // stdout is exactly one JSON document
  EXPECT_EQ(j["points"], 3000);
  EXPECT_TRUE(j["check"]["pass"].get<bool>());
  EXPECT_TRUE(j["check"]["validity"]["pass"].get<bool>());
  EXPECT_TRUE(j["check"]["tetgen"]["identical"].get<bool>());
  EXPECT_TRUE(j["check"]["cgal"]["identical"].get<bool>());
  EXPECT_EQ(j["tets"], j["check"]["tetgen"]["reference_tets"]);
  EXPECT_GT(j["counts"]["orient_tests_per_point"].get<double>(), 1.0);
  EXPECT_GT(j["counts"]["conflicts_per_point"].get<double>(), 1.0);
  // The walk histogram: its bins' tests add up to the per-point count, one walk per point but
  // the first four.
  ASSERT_TRUE(j["walk_histogram"].is_array());
  double walks = 0, tests = 0;
  for (const auto& bin : j["walk_histogram"]) {
    walks += bin["walks"].get<double>();
    tests += bin["tests"].get<double>();
  }
  EXPECT_EQ(walks, 3000 - 4);
  EXPECT_NEAR(tests / 3000, j["counts"]["orient_tests_per_point"].get<double>(), 1e-9);
  EXPECT_TRUE(j["walk_histogram"].back()["tests_max"].is_null());  // the open last bin
  for (const char* stage : {"read", "order", "delaunay", "check", "write", "total"})
    EXPECT_TRUE(j["seconds"].contains(stage)) << stage;
  const std::string xml = slurp(vtu);
  EXPECT_NE(xml.find("UnstructuredGrid"), std::string::npos);
  EXPECT_NE(xml.find("insertion_rank"), std::string::npos);
  EXPECT_NE(xml.find("kd_level"), std::string::npos);
  EXPECT_NE(xml.find("vtkZLibDataCompressor"), std::string::npos);
}

TEST(Cli, CgalKernelAndOrders) {
  const fs::path pts = tmpdir() / "disk.xyz";
  ASSERT_EQ(kdmesh("points --dist disk -n 2000 -q -o " + pts.string()).code, 0);
  const CliResult own = kdmesh("delaunay " + pts.string() + " --kernel cgal --order cgal --check --json -q");
  ASSERT_EQ(own.code, 0) << own.err;
  EXPECT_TRUE(nlohmann::json::parse(own.out)["check"]["kdmesh"]["identical"].get<bool>());
  EXPECT_EQ(kdmesh("delaunay " + pts.string() + " --kernel cgal --order brio -q").code, 0);
  const CliResult bad = kdmesh("delaunay " + pts.string() + " --order cgal -q");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--kernel cgal"), std::string::npos) << bad.err;
  // Stock CGAL (issue 22's baseline): no vertex info, a Point_3 range; the same tets, checked.
  const CliResult stock = kdmesh("delaunay " + pts.string() + " --kernel cgal-plain --order cgal --check --json -q");
  ASSERT_EQ(stock.code, 0) << stock.err;
  const auto js = nlohmann::json::parse(stock.out);
  EXPECT_TRUE(js["check"]["kdmesh"]["identical"].get<bool>());
  EXPECT_EQ(js["kernel"], "cgal-plain");
  EXPECT_GT(js["seconds"]["delaunay"].get<double>(), 0.0);
  const CliResult plain_order = kdmesh("delaunay " + pts.string() + " --kernel cgal-plain --order kd-bfs -q");
  EXPECT_EQ(plain_order.code, 2);
  EXPECT_NE(plain_order.err.find("needs --order cgal"), std::string::npos) << plain_order.err;
}

// --threads 2 on 50k points: rounds ran (reported in the JSON and the human summary), the
// check passes, and the tet count is the sequential run's; --threads is refused for CGAL.
TEST(Cli, DelaunayOnTwoThreadsChecksAndReportsItsRounds) {
  const fs::path pts = tmpdir() / "cube-threads.xyz";
  ASSERT_EQ(kdmesh("points --dist cube -n 50000 --seed 3 -q -o " + pts.string()).code, 0);
  const CliResult one = kdmesh("delaunay " + pts.string() + " --json -q");
  const CliResult two = kdmesh("delaunay " + pts.string() + " --threads 2 --check --json");
  ASSERT_EQ(one.code, 0) << one.err;
  ASSERT_EQ(two.code, 0) << two.err;
  const auto j1 = nlohmann::json::parse(one.out), j2 = nlohmann::json::parse(two.out);
  EXPECT_TRUE(j2["check"]["pass"].get<bool>());
  EXPECT_EQ(j1["tets"], j2["tets"]);
  EXPECT_EQ(j1["counts"]["parallel_rounds"], 0);
  EXPECT_GE(j2["counts"]["parallel_rounds"].get<unsigned>(), 1u);
  EXPECT_NE(two.err.find("rounds on 2 threads"), std::string::npos) << two.err;
  const CliResult bad = kdmesh("delaunay " + pts.string() + " --kernel cgal --order cgal --threads 2 -q");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--threads applies to --kernel kdmesh"), std::string::npos) << bad.err;
}

// --threads 0 means one thread per CPU the process may use: bound to one CPU (taskset, as a
// batch system's cpuset binds a job), the run is sequential, with the same tets. Regression:
// the count was the machine's (std::thread::hardware_concurrency), whatever the binding.
TEST(Cli, RegressionDefaultThreadsFollowTheAffinityMask) {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  if (kdmesh::available_cpus() < 2) GTEST_SKIP() << "needs two CPUs to tell one from all";
  if (std::system("command -v taskset >/dev/null") != 0) GTEST_SKIP() << "needs taskset (util-linux)";
  int first = 0;
  while (!CPU_ISSET(first, &mask)) ++first;
  const fs::path pts = tmpdir() / "cube-affinity.xyz";
  ASSERT_EQ(kdmesh("points --dist cube -n 100000 --seed 5 -q -o " + pts.string()).code, 0);
  const CliResult all = kdmesh("delaunay " + pts.string() + " --threads 0 --json -q");
  const CliResult bound = kdmesh::test::run_kdmesh("delaunay " + pts.string() + " --threads 0 --json -q", tmpdir(),
                                                   "taskset -c " + std::to_string(first));
  ASSERT_EQ(all.code, 0) << all.err;
  ASSERT_EQ(bound.code, 0) << bound.err;
  const auto ja = nlohmann::json::parse(all.out), jb = nlohmann::json::parse(bound.out);
  EXPECT_EQ(ja["counts"]["threads"].get<unsigned>(), kdmesh::available_cpus());
  EXPECT_EQ(jb["counts"]["threads"], 1);
  EXPECT_EQ(jb["counts"]["parallel_rounds"], 0);
  EXPECT_EQ(ja["tets"], jb["tets"]);
}

// --count on a point file (used for Tables 16-17 on the pipeline's node sets): CGAL, given
// kdmesh's kd-bfs order and hints, removes exactly the cells kdmesh finds in conflict, since
// both build the same Delaunay triangulations in the same insertion order.
TEST(Cli, CgalCountsOnAPointFileMatchTheKernelsConflicts) {
  const fs::path pts = tmpdir() / "cube-count.xyz";
  ASSERT_EQ(kdmesh("points --dist cube -n 3000 -q -o " + pts.string()).code, 0);
  const CliResult cg = kdmesh("delaunay " + pts.string() + " --kernel cgal --order kd-bfs --count --json -q");
  ASSERT_EQ(cg.code, 0) << cg.err;
  const CliResult kd = kdmesh("delaunay " + pts.string() + " --order kd-bfs --json -q");
  ASSERT_EQ(kd.code, 0) << kd.err;
  const auto c = nlohmann::json::parse(cg.out)["counts"], k = nlohmann::json::parse(kd.out)["counts"];
  EXPECT_EQ(c["conflicts_per_point"].get<double>(), k["conflicts_per_point"].get<double>());
  // Location with the same hints: CGAL's walk tries faces in random order, kdmesh's in the
  // order of a direction heuristic (mesher/delaunay/delaunay.cpp, locate), which needs fewer tests.
  EXPECT_LT(k["orient_tests_per_point"].get<double>(), c["orient_tests_per_point"].get<double>());
  EXPECT_GT(k["orient_tests_per_point"].get<double>(), 0.5 * c["orient_tests_per_point"].get<double>());
  EXPECT_GE(c["all_orient_tests_per_point"].get<double>(), c["orient_tests_per_point"].get<double>());
  const CliResult bad = kdmesh("delaunay " + pts.string() + " --count -q");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--kernel cgal"), std::string::npos) << bad.err;
}

TEST(Cli, LatticeCheckPassesWithTies) {
  std::string text;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) text += std::to_string(i) + " " + std::to_string(j) + " " + std::to_string(k) + "\n";
  const fs::path p = write_file("lattice.xyz", text);
  const CliResult r = kdmesh("delaunay " + p.string() + " --check --json -q");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["check"]["general_position"].get<bool>());
  EXPECT_GT(j["check"]["validity"]["tie_faces"].get<int>(), 0);
  EXPECT_NEAR(j["check"]["validity"]["volume"].get<double>(), 125.0, 1e-9);
}

// A slab 1e-12 thick is valid input, but thinner than TetGen 1.5's tolerance: the check
// says TetGen was skipped and still passes on the exact check and CGAL.
TEST(Cli, CheckSkipsTetgenOnSlabsItCannotTake) {
  std::string text;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      text += std::to_string(i * 0.05 + 0.001 * j) + " " + std::to_string(j * 0.05) + " " +
              std::to_string((i * 7 + j * 13) % 11) + "e-13\n";  // exact text, no rounding
  const fs::path p = write_file("slab.xyz", text);
  const CliResult r = kdmesh("delaunay " + p.string() + " --check --json -q");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["check"]["validity"]["pass"].get<bool>());
  EXPECT_TRUE(j["check"]["tetgen"].contains("skipped"));
  EXPECT_TRUE(j["check"]["cgal"]["pass"].get<bool>());
}

TEST(Cli, DuplicatesAreReportedByIndex) {
  const fs::path p = write_file("dups.xyz", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0\n1 1 1\n0 0 1\n");
  const CliResult r = kdmesh("delaunay " + p.string() + " --order input --check");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("point 4 repeats point 1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("point 6 repeats point 3"), std::string::npos) << r.out;
}

TEST(Cli, ErrorsHaveTheirExitCodesAndWriteNothing) {
  const fs::path out = tmpdir() / "never.vtu";
  fs::remove(out);
  // all coplanar -> 4
  const fs::path flat = write_file("flat.xyz", "0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 3 0\n");
  CliResult r = kdmesh("delaunay " + flat.string() + " -o " + out.string());
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("coplanar"), std::string::npos) << r.err;
  // empty -> 4
  r = kdmesh("delaunay " + write_file("empty.xyz", "# nothing\n").string() + " -o " + out.string());
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("empty"), std::string::npos) << r.err;
  // over the memory limit -> 7, before tetrahedralizing (16 MB base + 300 B per point > 1 MB)
  r = kdmesh("delaunay " + flat.string() + " --max-memory 1M -o " + out.string());
  EXPECT_EQ(r.code, 7);
  EXPECT_NE(r.err.find("the limit is 1 MB (--max-memory)"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("tetrahedralizing"), std::string::npos) << r.err;
  // malformed -> 3, names file and line
  r = kdmesh("delaunay " + write_file("bad.xyz", "0 0 0\n1 0 0\n0 1 oops\n").string() + " -o " + out.string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("bad.xyz:3"), std::string::npos) << r.err;
  // missing -> 3
  r = kdmesh("delaunay " + (tmpdir() / "missing.xyz").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("missing.xyz"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // unwritable output -> 6, no temp file left behind
  const fs::path pts = tmpdir() / "small.xyz";
  ASSERT_EQ(kdmesh("points -n 100 -q -o " + pts.string()).code, 0);
  r = kdmesh("delaunay " + pts.string() + " -q -o " + (tmpdir() / "no-such-dir" / "x.vtu").string());
  EXPECT_EQ(r.code, 6) << r.err;
  EXPECT_FALSE(has_temp_leftovers(tmpdir()));
}

}  // namespace
