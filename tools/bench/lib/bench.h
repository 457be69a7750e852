// kdmesh — the benchmark harness behind `kdmesh bench`: the paper's Tables 1-15 for the kdmesh
// kernel, CGAL 5.5 and TetGen 1.5, each run measured in its own child process.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace kdmesh {

// ---- one measurement (what a child process does) ----

/// One run: the points of (dist, n, seed), ordered by `order`, triangulated by `kernel`.
///  kernel "kdmesh": orders kd-bfs, kd-bfs-alt, hilbert, brio, random, input;
///  kernel "cgal":   the same orders (one point at a time, located from the hint's cell), or
///                   "cgal" = CGAL's own insert(range) (its spatial sort is part of its time);
///  kernel "tetgen": order "tetgen" (TetGen sorts the points itself, inside its time);
///  kernel "order-only": build the order and stop (Table 15).
/// `count` (CGAL only): insert with the counting traits instead (counts, no meaningful time).
struct RunSpec {
  std::string dist;
  std::size_t n = 0;
  std::uint64_t seed = 1;
  std::string kernel;
  std::string order;
  bool count = false;
};

inline constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();

/// What a child reports. Counts are totals over all insertions (NaN when not counted).
struct RunMeasurement {
  double order_seconds = kNotMeasured;     ///< building the insertion order
  double delaunay_seconds = kNotMeasured;  ///< the kernel's insertion (see bench.cpp)
  double orient_tests = kNotMeasured;      ///< orientation tests during point location
  double orient_all = kNotMeasured;        ///< CGAL: all Orientation_3 calls
  double sphere_tests = kNotMeasured;      ///< CGAL: Side_of_oriented_sphere_3 calls
  double conflicts = kNotMeasured;         ///< tets (cells) found in conflict
  std::size_t tets = 0;                    ///< finite tets of the result
};

/// Runs `spec` in this process (the hidden `kdmesh bench-run` subcommand). Point generation is
/// not timed. Throws UsageError for an unknown distribution, kernel or order.
RunMeasurement measure_run(const RunSpec& spec);

// ---- child processes (bench_process.cpp) ----

/// A finished (or killed) child process.
struct ChildResult {
  int exit_code = -1;       ///< exit status; -1 when killed by a signal
  int signal = 0;           ///< the terminating signal, 0 if it exited
  bool timed_out = false;   ///< killed (SIGKILL) after the timeout
  std::string out, err;     ///< everything it wrote on stdout and stderr
  double peak_rss_bytes = 0;  ///< ru_maxrss from wait4()
  double wall_seconds = 0;
};

/// fork + exec of argv[0] (a path) with argv, stdout and stderr captured; waits at most
/// `timeout_seconds` (<= 0: no limit) and then kills it. Throws Error if it cannot start.
ChildResult run_child(const std::vector<std::string>& argv, double timeout_seconds);

/// Full path of `name` in $PATH, "" when not found.
std::string find_program(const std::string& name);

// ---- the whole benchmark (the parent process) ----

struct BenchOptions {
  std::string exe;        ///< the kdmesh executable to run children with (/proc/self/exe)
  std::string out_dir = "out/bench";
  std::vector<std::string> dists;    ///< empty: all seven
  std::vector<std::size_t> sizes;    ///< empty: default (or --full) sizes per distribution
  std::vector<std::string> kernels;  ///< empty: kdmesh, cgal, tetgen
  std::vector<std::string> orders;   ///< empty: all (kd-bfs kd-bfs-alt hilbert brio random cgal)
  std::vector<std::size_t> order_sizes;  ///< Table 15 sizes; empty: default (see bench.cpp)
  std::uint64_t seed = 1;
  bool full = false;        ///< the paper's sizes (Tables 1-7 and 15)
  double timeout = 120;     ///< seconds per child; a run over it is killed, status "timeout"
  /// Random order runs only up to this many points (0: no limit). kAutoRandomMax: 150 000
  /// with the default sizes, no limit with --full or --sizes (the paper aborted random
  /// insertion too, Table 16; the time and the skips below bound it anyway).
  std::size_t random_max_n = kAutoRandomMax;
  static constexpr std::size_t kAutoRandomMax = std::size_t(-1);
  bool count_cgal = true;   ///< also run CGAL's counting pass (a second child per CGAL run)
  bool plots = true;        ///< PNG plots with gnuplot (skipped with a warning if missing)
};

/// One row of results.csv. Seconds and per-point values are NaN when not measured.
struct BenchRecord {
  std::string dist;
  std::size_t n = 0;
  std::string kernel;  ///< kdmesh, cgal, tetgen, order-only
  std::string order;   ///< kd-bfs ... random, cgal (= insert(range)), tetgen
  std::string status;  ///< ok, timeout, failed, skipped
  double order_seconds = kNotMeasured;
  double delaunay_seconds = kNotMeasured;
  double total_seconds = kNotMeasured;
  double orient_per_point = kNotMeasured;
  double conflicts_per_point = kNotMeasured;
  double sphere_tests_per_point = kNotMeasured;  ///< CGAL only
  double orient_all_per_point = kNotMeasured;    ///< CGAL only
  double peak_rss_bytes = kNotMeasured;          ///< ru_maxrss of the timed child
  double bytes_per_point = kNotMeasured;         ///< (peak_rss - baseline) / n
  std::size_t tets = 0;
  double wall_seconds = kNotMeasured;  ///< the timed child's wall time, generation included
  double count_wall_seconds = kNotMeasured;  ///< CGAL's counting child's wall time
  std::string note;                    ///< why a run failed or was skipped
};

struct BenchSummary {
  std::vector<BenchRecord> records;
  double baseline_rss_bytes = 0;  ///< peak RSS of a child that does nothing
  double wall_seconds = 0;
  std::string csv_path, tables_path;
  std::vector<std::string> plot_paths;  ///< empty when gnuplot is missing
  std::vector<std::string> warnings;
};

/// Runs every selected measurement, one child process at a time, writing results.csv after
/// each run, then tables.md and plots/*.png into options.out_dir. `log` receives one progress
/// line per run (may be empty). Throws UsageError for bad selections, OutputError when the
/// output directory cannot be written.
BenchSummary run_bench(const BenchOptions& options,
                       const std::function<void(const std::string&)>& log);

/// The default and the paper's (--full) sizes of Tables 1-7 for a distribution.
std::vector<std::size_t> bench_default_sizes(const std::string& dist);
std::vector<std::size_t> bench_paper_sizes(const std::string& dist);

// ---- reports (bench_report.cpp) ----

struct BenchReportInfo {
  const BenchOptions* options = nullptr;
  double baseline_rss_bytes = 0;
  double wall_seconds = 0;
};

void write_bench_csv(const std::vector<BenchRecord>& records, const std::string& path);
/// tables.md: Tables 1-7 (times), 8-14 (counts), 15 (order building), memory, definitions.
void write_bench_tables(const std::vector<BenchRecord>& records, const BenchReportInfo& info,
                        const std::string& path);
/// plots/time_per_point.png (one panel per distribution) and plots/<dist>.png, with gnuplot.
/// Returns the PNG paths; empty with a warning appended when gnuplot is not installed.
std::vector<std::string> write_bench_plots(const std::vector<BenchRecord>& records,
                                           const std::string& dir,
                                           std::vector<std::string>& warnings);

}  // namespace kdmesh
