// `kdmesh bench` end to end through the real executable: a tiny run of all three kernels,
// its CSV, tables and plots; the per-run timeout; bad selections.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/support/run_cli.h"
#include "tests/support/tetgen.h"
#include <vector>

namespace {

namespace fs = std::filesystem;

using kdmesh::test::CliResult;
using kdmesh::test::slurp;

fs::path tmpdir() { return kdmesh::test::process_tmpdir("cli-bench"); }

CliResult kdmesh(const std::string& args) { return kdmesh::test::run_kdmesh(args, tmpdir()); }

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> v;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, sep)) v.push_back(cell);
  if (!line.empty() && line.back() == sep) v.emplace_back();
  return v;
}

/// results.csv as rows of column name -> text (no quoted cells expected in these runs).
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p, std::vector<std::string>& header) {
  std::istringstream in(slurp(p));
  std::string line;
  std::getline(in, line);
  header = split(line, ',');
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line, ',');
    EXPECT_EQ(cells.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

double positive(const std::map<std::string, std::string>& row, const std::string& col) {
  const std::string& text = row.at(col);
  EXPECT_FALSE(text.empty()) << col << " of " << row.at("dist") << " " << row.at("kernel") << " "
                             << row.at("order");
  const double x = text.empty() ? 0.0 : std::stod(text);
  EXPECT_TRUE(std::isfinite(x) && x > 0) << col << " = " << text;
  return x;
}

TEST(CliBench, SmokeRunAllKernels) {
  KDMESH_REQUIRE_TETGEN();
  const fs::path out = tmpdir() / "smoke";
  const CliResult r = kdmesh("bench --dists cube,axes --sizes 2000 --orders kd-bfs,kd-bfs-hilbert,hilbert,cgal --out " +
                             out.string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);  // stdout is exactly one JSON document
  EXPECT_EQ(j["command"], "bench");

  // Per distribution: kdmesh x {kd-bfs, kd-bfs-hilbert, hilbert}, cgal x {the same, range},
  // stock cgal (range), tetgen; plus Table 15's order-only runs (kd-bfs, hilbert,
  // kd-bfs-hilbert) on the cube.
  std::vector<std::string> header;
  const auto rows = read_csv(out / "results.csv", header);
  const std::vector<std::string> expected_header = {
      "dist", "n", "kernel", "order", "status", "order_seconds", "delaunay_seconds", "total_seconds",
      "orient_per_point", "conflicts_per_point", "sphere_tests_per_point", "orient_all_per_point",
      "peak_rss_bytes", "bytes_per_point", "tets", "wall_seconds", "count_wall_seconds", "note"};
  EXPECT_EQ(header, expected_header);
  ASSERT_EQ(rows.size(), 21u);
  EXPECT_EQ(j["runs"], 21);
  std::map<std::string, int> runs_per_kernel;
  std::map<std::string, std::string> tets_of_dist;
  for (const auto& row : rows) {
    SCOPED_TRACE(row.at("dist") + " " + row.at("kernel") + " " + row.at("order"));
    EXPECT_EQ(row.at("status"), "ok") << row.at("note");
    EXPECT_EQ(row.at("n"), "2000");
    ++runs_per_kernel[row.at("kernel")];
    const std::string& kernel = row.at("kernel");
    if (kernel == "order-only") {
      positive(row, "order_seconds");
      EXPECT_TRUE(row.at("delaunay_seconds").empty());
      continue;
    }
    positive(row, "delaunay_seconds");
    const double total = positive(row, "total_seconds");
    EXPECT_GE(total, std::stod(row.at("delaunay_seconds")));
    EXPECT_GT(positive(row, "peak_rss_bytes"), 1e6);
    EXPECT_GE(std::stod(row.at("bytes_per_point")), 0.0);
    positive(row, "tets");
    // General position: every kernel and order yields the same Delaunay tetrahedralization.
    if (tets_of_dist.count(row.at("dist"))) {
      EXPECT_EQ(row.at("tets"), tets_of_dist[row.at("dist")]);
    }
    tets_of_dist[row.at("dist")] = row.at("tets");
    if (kernel == "tetgen" || kernel == "cgal-plain") {
      EXPECT_TRUE(row.at("orient_per_point").empty());  // TetGen and stock CGAL are not instrumented
      continue;
    }
    EXPECT_GT(positive(row, "orient_per_point"), 1.0);
    EXPECT_GT(positive(row, "conflicts_per_point"), 1.0);
    if (kernel == "cgal") {
      EXPECT_GE(positive(row, "orient_all_per_point"), std::stod(row.at("orient_per_point")));
      positive(row, "sphere_tests_per_point");
    } else {
      EXPECT_TRUE(row.at("sphere_tests_per_point").empty());
      positive(row, "order_seconds");
    }
  }
  EXPECT_EQ(runs_per_kernel["kdmesh"], 6);
  EXPECT_EQ(runs_per_kernel["cgal"], 8);
  EXPECT_EQ(runs_per_kernel["cgal-plain"], 2);
  EXPECT_EQ(runs_per_kernel["tetgen"], 2);
  EXPECT_EQ(runs_per_kernel["order-only"], 3);

  const std::string md = slurp(out / "tables.md");
  for (const char* heading : {"### Table 1 Cube", "### Table 7 Axes", "### Table 8 Cube", "### Table 14 Axes",
                              "## Table 15", "cgal range", "stock cgal range", "tetgen"})
    EXPECT_NE(md.find(heading), std::string::npos) << heading;
  EXPECT_EQ(md.find("Table 2 "), std::string::npos);  // planes did not run
  // Plots when gnuplot is installed (a warning, not an error, without it).
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    for (const char* png : {"time_per_point.png", "cube.png", "axes.png"})
      EXPECT_GT(fs::file_size(out / "plots" / png), 1000u) << png;
  } else {
    EXPECT_NE(r.err.find("gnuplot"), std::string::npos);
  }
  // One progress line per run on stderr.
  EXPECT_NE(r.err.find("[ 21/21]"), std::string::npos) << r.err;
}

TEST(CliBench, TimeoutKillsTheRun) {
  const fs::path out = tmpdir() / "timeout";
  const CliResult r = kdmesh("bench --dists cube --sizes 300000 --kernels kdmesh --orders random "
                             "--order-sizes 0 --timeout 0.3 --no-plots -q --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<std::string> header;
  const auto rows = read_csv(out / "results.csv", header);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].at("status"), "timeout");
  EXPECT_TRUE(rows[0].at("total_seconds").empty());
  EXPECT_NE(slurp(out / "tables.md").find("timeout"), std::string::npos);
}

TEST(CliBench, BadSelectionsAreUsageErrors) {
  const CliResult help = kdmesh("bench --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("--json"), std::string::npos);
  EXPECT_NE(help.out.find("--full"), std::string::npos);
  EXPECT_EQ(kdmesh("--help").out.find("bench-run"), std::string::npos);  // hidden
  EXPECT_EQ(kdmesh("bench --kernels nope -q --out " + (tmpdir() / "bad").string()).code, 2);
  EXPECT_EQ(kdmesh("bench --dists moon -q --out " + (tmpdir() / "bad").string()).code, 2);
  EXPECT_EQ(kdmesh("bench-run --dist cube -n 100 --kernel kdmesh --order cgal").code, 2);
}

}  // namespace
