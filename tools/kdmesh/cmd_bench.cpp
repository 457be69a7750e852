// kdmesh bench — reproduce the paper's Tables 1-15 (kdmesh kernel, CGAL 5.5, TetGen 1.5), and
// the hidden `bench-run` that performs one measurement in a child process.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <unistd.h>

#include <climits>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "tools/kdmesh/cli.h"
#include "tools/bench/lib/bench.h"

namespace kdmesh::cli {

namespace {

struct BenchCmdOptions {
  BenchOptions bench;
  bool no_plots = false;
  bool no_cgal_counts = false;
  Output out;
};

struct BenchRunOptions {
  RunSpec spec;
  bool baseline = false;
  Output out;
};

nlohmann::json num(double x) { return std::isnan(x) ? nlohmann::json(nullptr) : nlohmann::json(x); }

/// The executable the children run: this very binary. Each forked child execs its own
/// /proc/self/exe, i.e. the parent's image even if the file is rebuilt during a long run.
std::string self_exe() {
  char buf[PATH_MAX];
  if (::readlink("/proc/self/exe", buf, sizeof buf - 1) <= 0)
    throw Error("bench: cannot find the kdmesh executable (/proc/self/exe)");
  return "/proc/self/exe";
}

nlohmann::json record_json(const BenchRecord& r) {
  return {{"dist", r.dist},
          {"n", r.n},
          {"kernel", r.kernel},
          {"order", r.order},
          {"status", r.status},
          {"order_seconds", num(r.order_seconds)},
          {"delaunay_seconds", num(r.delaunay_seconds)},
          {"total_seconds", num(r.total_seconds)},
          {"orient_per_point", num(r.orient_per_point)},
          {"conflicts_per_point", num(r.conflicts_per_point)},
          {"sphere_tests_per_point", num(r.sphere_tests_per_point)},
          {"orient_all_per_point", num(r.orient_all_per_point)},
          {"peak_rss_bytes", num(r.peak_rss_bytes)},
          {"bytes_per_point", num(r.bytes_per_point)},
          {"tets", r.tets},
          {"wall_seconds", num(r.wall_seconds)},
          {"count_wall_seconds", num(r.count_wall_seconds)},
          {"note", r.note}};
}

int run_bench_cmd(BenchCmdOptions& o) {
  o.bench.exe = self_exe();
  o.bench.plots = !o.no_plots;
  o.bench.count_cgal = !o.no_cgal_counts;
  const Output& out = o.out;
  const BenchSummary sum = run_bench(o.bench, [&out](const std::string& line) { out.stage("bench " + line); });

  std::map<std::string, int> by_status;
  for (const BenchRecord& r : sum.records) ++by_status[r.status];
  out.human() << "bench: " << sum.records.size() << " runs (";
  bool first = true;
  for (const auto& [status, count] : by_status) {
    out.human() << (first ? "" : ", ") << count << " " << status;
    first = false;
  }
  out.human() << ") in " << sum.wall_seconds << " s\n  " << sum.csv_path << "\n  " << sum.tables_path << "\n";
  for (const std::string& p : sum.plot_paths) out.human() << "  " << p << "\n";

  nlohmann::json j = {{"command", "bench"},
                      {"out_dir", o.bench.out_dir},
                      {"csv", sum.csv_path},
                      {"tables", sum.tables_path},
                      {"plots", sum.plot_paths},
                      {"warnings", sum.warnings},
                      {"wall_seconds", sum.wall_seconds},
                      {"baseline_rss_bytes", sum.baseline_rss_bytes},
                      {"runs", sum.records.size()},
                      {"status", by_status},
                      {"records", nlohmann::json::array()}};
  for (const BenchRecord& r : sum.records) j["records"].push_back(record_json(r));
  out.emit_json(j);
  return 0;
}

int run_bench_run(const BenchRunOptions& o) {
  if (o.baseline) {  // the memory of a child that does nothing
    o.out.emit_json({{"command", "bench-run"}, {"baseline", true}});
    return 0;
  }
  const RunMeasurement m = measure_run(o.spec);
  const RunSpec& s = o.spec;
  o.out.human() << "bench-run: " << s.dist << " n=" << s.n << " " << s.kernel << " " << s.order
                << (s.count ? " (counting)" : "") << ": order "
                << (std::isnan(m.order_seconds) ? std::string("-") : std::to_string(m.order_seconds) + " s")
                << ", delaunay "
                << (std::isnan(m.delaunay_seconds) ? std::string("-") : std::to_string(m.delaunay_seconds) + " s")
                << ", " << m.tets << " tets\n";
  o.out.emit_json({{"command", "bench-run"},
                   {"dist", s.dist},
                   {"n", s.n},
                   {"kernel", s.kernel},
                   {"order", s.order},
                   {"count", s.count},
                   {"order_seconds", num(m.order_seconds)},
                   {"delaunay_seconds", num(m.delaunay_seconds)},
                   {"orient_tests", num(m.orient_tests)},
                   {"orient_all", num(m.orient_all)},
                   {"sphere_tests", num(m.sphere_tests)},
                   {"conflicts", num(m.conflicts)},
                   {"tets", m.tets}});
  return 0;
}

}  // namespace

void add_bench_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<BenchCmdOptions>();
  BenchOptions& b = o->bench;
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Benchmark kernels and insertion orders on the paper's distributions: results.csv, "
      "tables.md (the paper's Tables 1-15) and plots");
  cmd->add_option("--out", b.out_dir, "Output directory")->capture_default_str();
  cmd->add_option("--dists", b.dists, "Distributions, comma-separated (default: all seven)")
      ->delimiter(',')
      ->check(CLI::IsMember({"cube", "planes", "paraboloid", "spiral", "disk", "cylinder", "axes"}));
  cmd->add_option("--sizes", b.sizes,
                  "Point counts, comma-separated (default: per distribution, the paper's first size "
                  "and 1/2, 1/4, 1/8 of it)")
      ->delimiter(',')
      ->check(CLI::Range(std::size_t(4), std::size_t(1) << 27));
  cmd->add_option("--kernels", b.kernels, "Kernels: kdmesh, cgal, tetgen (default: all)")
      ->delimiter(',')
      ->check(CLI::IsMember({"kdmesh", "cgal", "tetgen"}));
  cmd->add_option("--orders", b.orders,
                  "Orders: kd-bfs, kd-bfs-hilbert, kd-bfs-alt, hilbert, brio, random, input, cgal (CGAL's "
                  "insert(range)) (default: all but input)")
      ->delimiter(',')
      ->check(CLI::IsMember(
          {"kd-bfs", "kd-bfs-hilbert", "kd-bfs-alt", "hilbert", "brio", "random", "input", "cgal"}));
  cmd->add_option("--order-sizes", b.order_sizes,
                  "Table 15 sizes (order building only, cube and cylinder); 0 for none (default: "
                  "500000,1000000; the paper's with --full; --sizes when given)")
      ->delimiter(',');
  cmd->add_option("--seed", b.seed, "Seed of the points (and, mixed, of the random and brio orders)")
      ->capture_default_str();
  cmd->add_flag("--full", b.full,
                "The paper's sizes: Tables 1-7 (up to 2.16M points) and Table 15 (up to 3.5M)");
  cmd->add_option("--timeout", b.timeout, "Seconds per run before it is killed (0: none)")
      ->capture_default_str();
  cmd->add_option("--random-max-n", b.random_max_n,
                  "Run random order only up to this many points, 0: no limit (default: 150000 with "
                  "the default sizes, no limit with --full or --sizes)");
  cmd->add_flag("--no-plots", o->no_plots, "Do not run gnuplot");
  cmd->add_flag("--no-cgal-counts", o->no_cgal_counts,
                "Skip CGAL's counting pass (no CGAL numbers in Tables 8-14)");
  add_output_flags(cmd, o->out);
  cmd->callback([o, &run] { run = [o] { return run_bench_cmd(*o); }; });

  // One measurement, run by `bench` in a child process; hidden from --help.
  auto r = std::make_shared<BenchRunOptions>();
  CLI::App* one = app.add_subcommand("bench-run", "One benchmark measurement (internal, used by bench)");
  one->group("");
  one->add_option("--dist", r->spec.dist, "Distribution");
  one->add_option("-n", r->spec.n, "Number of points")->check(CLI::Range(std::size_t(4), std::size_t(1) << 28));
  one->add_option("--seed", r->spec.seed, "Seed");
  one->add_option("--kernel", r->spec.kernel, "kdmesh, cgal, tetgen or order-only");
  one->add_option("--order", r->spec.order, "Insertion order (cgal: insert(range); tetgen: TetGen's)");
  one->add_flag("--count", r->spec.count, "CGAL: count predicates (counting traits)");
  one->add_flag("--baseline", r->baseline, "Do nothing (the memory baseline)");
  add_output_flags(one, r->out);
  one->callback([r, &run] { run = [r] { return run_bench_run(*r); }; });
}

}  // namespace kdmesh::cli
