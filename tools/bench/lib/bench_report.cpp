// kdmesh bench — reports: results.csv, tables.md in the paper's layout, gnuplot PNG plots.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tools/bench/lib/bench.h"
#include "tools/bench/lib/bench_paper.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {

namespace {

/// Fixed column order of the runs: kernels, then the orders of the issue.
const std::vector<std::string> kKernelOrder = {"kdmesh", "cgal", "cgal-plain", "tetgen"};
const std::vector<std::string> kOrderOrder = {"kd-bfs", "kd-bfs-hilbert", "kd-bfs-alt", "hilbert",
                                              "brio",   "random",         "input",      "cgal",
                                              "tetgen"};

std::size_t rank_of(const std::vector<std::string>& v, const std::string& s) {
  return std::size_t(std::find(v.begin(), v.end(), s) - v.begin());
}

/// A (kernel, order) pair, i.e. one column of Tables 1-7 or one line of the plots.
struct Series {
  std::string kernel, order;
  bool operator<(const Series& o) const {
    const auto a = std::make_pair(rank_of(kKernelOrder, kernel), rank_of(kOrderOrder, order));
    const auto b = std::make_pair(rank_of(kKernelOrder, o.kernel), rank_of(kOrderOrder, o.order));
    return a != b ? a < b : std::tie(kernel, order) < std::tie(o.kernel, o.order);
  }
  bool operator==(const Series& o) const { return kernel == o.kernel && order == o.order; }
  std::string label() const {
    if (kernel == "tetgen") return "tetgen";
    if (kernel == "cgal" && order == "cgal") return "cgal range";
    if (kernel == "cgal-plain") return "stock cgal range";
    return kernel + " " + order;
  }
};

bool is_run(const BenchRecord& r) { return r.kernel != "order-only"; }

std::string csv_num(double x, int prec) {
  if (std::isnan(x)) return "";
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

std::string csv_text(const std::string& t) {
  if (t.find_first_of(",\"\n") == std::string::npos) return t;
  std::string q = "\"";
  for (char c : t) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return q + "\"";
}

/// 3 significant digits, no exponent for the magnitudes of interest.
std::string sig3(double x) {
  if (std::isnan(x)) return "-";
  const double a = std::fabs(x);
  const int decimals = a >= 100 ? 0 : a >= 10 ? 1 : a >= 1 ? 2 : a >= 0.1 ? 3 : a >= 0.01 ? 4 : 5;
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << x;
  return s.str();
}

std::string fixed(double x, int prec) {
  if (std::isnan(x)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(prec) << x;
  return s.str();
}

/// "1 050 000" like the paper.
std::string size_str(std::size_t n) {
  std::string d = std::to_string(n), out;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (i && (d.size() - i) % 3 == 0) out += ' ';
    out += d[i];
  }
  return out;
}

/// A cell for a run that did not produce a number.
std::string status_cell(const BenchRecord& r) {
  if (r.status == "timeout") return "timeout";
  if (r.status == "skipped") return "skip";
  return "fail";
}

struct Index {
  std::map<std::tuple<std::string, std::size_t, std::string, std::string>, const BenchRecord*> by_key;
  const BenchRecord* find(const std::string& d, std::size_t n, const Series& s) const {
    const auto it = by_key.find({d, n, s.kernel, s.order});
    return it == by_key.end() ? nullptr : it->second;
  }
};

std::string md_row(const std::vector<std::string>& cells) {
  std::string s = "|";
  for (const std::string& c : cells) s += " " + c + " |";
  return s + "\n";
}

std::string md_rule(std::size_t columns, std::size_t left_columns = 1) {
  std::string s = "|";
  for (std::size_t i = 0; i < columns; ++i) s += i < left_columns ? " --- |" : " ---: |";
  return s + "\n";
}

std::string capitalised(std::string s) {
  if (!s.empty()) s[0] = char(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0) {
      const std::size_t c = line.find(':');
      if (c != std::string::npos) return line.substr(c + 2);
    }
  }
  return "unknown CPU";
}

const char* kDefinitions = R"(## Definitions

- **Runs.** Each (distribution, size, kernel, order) is one child process (`kdmesh bench-run`),
  one after the other. The child generates the points from (distribution, n, seed) (not timed),
  builds the order, and triangulates.
  - `kdmesh <order>`: kdmesh's Bowyer-Watson kernel, each point located from its hint
    (the kd-tree parent for kd-bfs, kd-bfs-hilbert and kd-bfs-alt, the previous point
    otherwise). kd-bfs-hilbert (not in the paper) is kd-bfs with each level visited in
    Hilbert order instead of left to right.
  - `cgal <order>`: CGAL 5.5 `Delaunay_triangulation_3` on Epick, `insert(p, start)` one point
    at a time, `start` a cell of the hint's vertex (as the paper's Kd-tree and BRIO columns).
  - `cgal range`: CGAL's own `insert(first, last)` (its spatial sort, Hilbert mixed with
    BRIO, is inside its time; as the paper's "Hilbert" column), on pairs (point, id) into
    vertices that carry the id.
  - `stock cgal range`: the honest baseline, stock CGAL: a plain
    `Delaunay_triangulation_3<Epick>` (no vertex info) inserting a `std::vector<Point_3>`
    range; not instrumented.
  - `tetgen`: TetGen 1.5 `tetrahedralize("zQJF")` (its own BRIO + Hilbert sort inside its time).
- **Time** (Tables 1-7) = order building + Delaunay insertion, wall-clock seconds, as the
  paper's (which include order building). The Delaunay part is the insertion loop only
  (kdmesh: `DelaunayStats::seconds`; CGAL: the `insert` calls; TetGen: `tetrahedralize`),
  not the copies of the input into CGAL's or TetGen's types.
- **Orientation tests per point** (Tables 8-14) = orientation tests made by point location,
  divided by n.
  - kdmesh: `DelaunayStats::orient_tests` (the walk from the hint to the tet containing the point;
    it tries a tet's faces in the order of a direction heuristic, not randomly as CGAL's walk).
  - CGAL: calls of the traits' `Orientation_3` inside `locate()`, counted in a separate child on
    counting traits (Epick with counting `Orientation_3` and `Side_of_oriented_sphere_3`).
    Plain Epick walks first with inexact double tests outside the traits (structural
    filtering) and then confirms with a short exact walk. The counting traits do not enable that
    filter, so the whole walk (CGAL's remembering stochastic walk from the hint's cell) is
    exact and counted. Each insertion is CGAL's own `insert(p, start)`, split into its two public halves
    `locate(p, lt, li, lj, start)` and `insert(p, lt, c, li, lj)`.
- **Conflicts per point** = tets (cells) in conflict with the inserted point, i.e. its cavity,
  infinite ones included, summed over all insertions, divided by n. kdmesh: `DelaunayStats::conflicts`;
  CGAL: cells destroyed by the insertions (a counting cell type), which are exactly the cells
  `find_conflicts()` found.
- **CGAL's other counts** (CSV columns `orient_all_per_point`, `sphere_tests_per_point`):
  all `Orientation_3` calls of the insertion (location, plus infinite cells' conflict tests and
  perturbation tie-breaks), and `Side_of_oriented_sphere_3` calls (one per finite cell tested
  for conflict: the cavity and the cells across its boundary).
- **Peak memory** = `ru_maxrss` of the timed child (from `wait4`), including the points and
  the order. **Bytes per point** = (peak - the peak of an idle child) / n.
- `timeout`: killed after `--timeout` seconds. `skip`: not run, because the same kernel and
  order timed out at a smaller size, or would time out extrapolated from the smaller sizes
  (t ~ n^e, e fitted on the last two sizes, else 2 for random order and 1.2 otherwise), or is
  random order above `--random-max-n` (150 000 by default). The paper aborted random
  insertion too (its Table 16). CGAL's counting pass is skipped by the same rules, alone.
- Paper columns: )";

template <std::size_t K>
bool overlaps(const std::set<std::size_t>& ours, const std::array<std::size_t, K>& paper_sizes) {
  for (std::size_t n : paper_sizes)
    if (ours.count(n)) return true;
  return false;
}

/// The note printed instead of the paper's columns when no size is in common.
template <std::size_t K>
std::string no_overlap_note(const std::array<std::size_t, K>& paper_sizes) {
  std::string s = std::string("`") + paper::kLabel + "`: no size in common; the paper ran ";
  for (std::size_t i = 0; i < K; ++i) s += (i ? ", " : "") + size_str(paper_sizes[i]);
  return s + " points (`--full`).\n";
}

}  // namespace

void write_bench_csv(const std::vector<BenchRecord>& records, const std::string& path) {
  AtomicFile file(path);
  {
    std::ofstream f(file.temp_path());
    if (!f) throw OutputError(path, "cannot write");
    f << "dist,n,kernel,order,status,order_seconds,delaunay_seconds,total_seconds,"
         "orient_per_point,conflicts_per_point,sphere_tests_per_point,orient_all_per_point,"
         "peak_rss_bytes,bytes_per_point,tets,wall_seconds,count_wall_seconds,note\n";
    for (const BenchRecord& r : records) {
      f << r.dist << ',' << r.n << ',' << r.kernel << ',' << r.order << ',' << r.status << ','
        << csv_num(r.order_seconds, 6) << ',' << csv_num(r.delaunay_seconds, 6) << ','
        << csv_num(r.total_seconds, 6) << ',' << csv_num(r.orient_per_point, 6) << ','
        << csv_num(r.conflicts_per_point, 6) << ',' << csv_num(r.sphere_tests_per_point, 6)
        << ',' << csv_num(r.orient_all_per_point, 6) << ',' << csv_num(r.peak_rss_bytes, 15)
        << ',' << csv_num(r.bytes_per_point, 6) << ',' << (r.status == "ok" ? std::to_string(r.tets) : "")
        << ',' << csv_num(r.wall_seconds, 4) << ',' << csv_num(r.count_wall_seconds, 4) << ','
        << csv_text(r.note) << '\n';
    }
    f.flush();
    if (!f) throw OutputError(path, "write failed");
  }
  file.commit();
}

namespace {

/// What the tables are made of: the records by (distribution, size, kernel, order), and the
/// sizes and series run per distribution.
struct TableData {
  Index idx;
  std::map<std::string, std::set<std::size_t>> sizes;  // per distribution, Tables 1-14
  std::map<std::string, std::set<Series>> series;      // per distribution
  std::set<std::size_t> order_sizes;
};

/// Tables 1-7: time.
void time_tables(std::ostringstream& md, const TableData& t) {
  // ---- Tables 1-7: time ----
  md << "## Tables 1-7: time in seconds (order building + Delaunay)\n\n";
  for (const paper::TimeTable& pt : paper::kTimes) {
    const std::string d = pt.dist;
    if (!t.sizes.count(d)) continue;
    md << "### Table " << pt.number << " " << capitalised(d) << ", time in seconds\n\n";
    const bool with_paper = overlaps(t.sizes.at(d), pt.sizes);
    std::vector<std::string> head = {"Datasize"};
    for (const Series& s : t.series.at(d)) head.push_back(s.label());
    if (with_paper)
      for (const char* p : {"Kd-tree", "BRIO", "Hilbert"}) head.push_back(std::string("paper ") + p);
    md << md_row(head) << md_rule(head.size());
    for (std::size_t n : t.sizes.at(d)) {
      std::vector<std::string> row = {size_str(n)};
      for (const Series& s : t.series.at(d)) {
        const BenchRecord* r = t.idx.find(d, n, s);
        row.push_back(!r ? "" : r->status == "ok" ? sig3(r->total_seconds) : status_cell(*r));
      }
      const auto it = std::find(pt.sizes.begin(), pt.sizes.end(), n);
      for (int k = 0; with_paper && k < 3; ++k)
        row.push_back(it == pt.sizes.end() ? "" : fixed(pt.seconds[std::size_t(it - pt.sizes.begin())][k], 0));
      md << md_row(row);
    }
    md << "\n";
    if (!with_paper) md << no_overlap_note(pt.sizes) << "\n";
  }
}

/// Tables 8-14: orientation tests and conflicts per point.
void count_tables(std::ostringstream& md, const TableData& t) {
  // ---- Tables 8-14: counts ----
  md << "## Tables 8-14: orientation tests and conflicting tets per point\n\n";
  for (const paper::CountTable& pt : paper::kCounts) {
    const std::string d = pt.dist;
    if (!t.sizes.count(d)) continue;
    md << "### Table " << pt.number << " " << capitalised(d)
       << ": the number of orientation tests and conflicting elements per point\n\n";
    std::vector<std::string> head = {"Data size", ""};
    for (std::size_t n : t.sizes.at(d)) head.push_back(size_str(n));
    md << md_row(head) << md_rule(head.size(), 2);
    for (const Series& s : t.series.at(d)) {
      if (s.kernel == "tetgen" || s.kernel == "cgal-plain") continue;  // not instrumented
      for (int what = 0; what < 2; ++what) {
        std::vector<std::string> row = {what == 0 ? s.label() : "", what == 0 ? "Orientation" : "Conflicts"};
        for (std::size_t n : t.sizes.at(d)) {
          const BenchRecord* r = t.idx.find(d, n, s);
          if (!r) row.push_back("");
          else if (r->status != "ok") row.push_back(status_cell(*r));
          else row.push_back(fixed(what == 0 ? r->orient_per_point : r->conflicts_per_point, 3));
        }
        md << md_row(row);
      }
    }
    const char* names[3] = {"paper Kd-tree", "paper BRIO", "paper Hilbert"};
    const bool with_paper = overlaps(t.sizes.at(d), pt.sizes);
    for (int k = 0; with_paper && k < 3; ++k) {
      for (int what = 0; what < 2; ++what) {
        std::vector<std::string> row = {what == 0 ? names[k] : "", what == 0 ? "Orientation" : "Conflicts"};
        for (std::size_t n : t.sizes.at(d)) {
          const auto it = std::find(pt.sizes.begin(), pt.sizes.end(), n);
          const std::size_t j = std::size_t(it - pt.sizes.begin());
          row.push_back(it == pt.sizes.end() ? ""
                                             : fixed(what == 0 ? pt.orient[k][j] : pt.conflicts[k][j], 3));
        }
        md << md_row(row);
      }
    }
    if (!with_paper) md << "\n" << no_overlap_note(pt.sizes);
    else if (*pt.note) md << "\nPaper: " << pt.note << ".\n";
    md << "\n";
  }
}

/// Table 15: order building.
void order_table(std::ostringstream& md, const TableData& t) {
  // ---- Table 15: order building ----
  md << "## Table 15: order building time in seconds, kd-tree (kd-bfs) and Hilbert orders\n\n"
        "(and kd-bfs-hilbert, not in the paper)\n\n";
  if (t.order_sizes.empty()) {
    md << "Not run (needs the cube or the cylinder distribution).\n\n";
  } else {
    md << "Building the order alone (`order-only` runs; kdmesh builds the kd-tree's two halves below "
          "the root on two threads for large inputs).\n\n";
    const paper::OrderTable& pt = paper::kOrderBuild;
    const bool with_paper = overlaps(t.order_sizes, pt.sizes);
    std::vector<std::string> head = {"Datasize",         "cube kd-bfs",      "cube hilbert",
                                     "cube kd-bfs-hilbert", "cylinder kd-bfs", "cylinder hilbert",
                                     "cylinder kd-bfs-hilbert"};
    if (with_paper)
      for (const char* h : {"paper cube Kd-tree", "paper cube Hilbert", "paper cylinder Kd-tree",
                            "paper cylinder Hilbert"})
        head.push_back(h);
    md << md_row(head) << md_rule(head.size());
    for (std::size_t n : t.order_sizes) {
      std::vector<std::string> row = {size_str(n)};
      for (const char* d : {"cube", "cylinder"}) {
        for (const char* o : {"kd-bfs", "hilbert", "kd-bfs-hilbert"}) {
          const BenchRecord* r = t.idx.find(d, n, {"order-only", o});
          row.push_back(!r ? "" : r->status == "ok" ? sig3(r->order_seconds) : status_cell(*r));
        }
      }
      const auto it = std::find(pt.sizes.begin(), pt.sizes.end(), n);
      const std::size_t j = std::size_t(it - pt.sizes.begin());
      for (const auto* col : {&pt.cube_kd, &pt.cube_hilbert, &pt.cylinder_kd, &pt.cylinder_hilbert})
        if (with_paper) row.push_back(it == pt.sizes.end() ? "" : fixed((*col)[j], 0));
      md << md_row(row);
    }
    md << "\n";
    if (!with_paper) md << no_overlap_note(pt.sizes) << "\n";
  }
}

/// Peak memory per point, and CGAL's other counts (not in the paper).
void memory_tables(std::ostringstream& md, const TableData& t) {
  // ---- memory and CGAL's other counts (not in the paper) ----
  std::set<Series> all_series;
  for (const auto& [d, ss] : t.series) all_series.insert(ss.begin(), ss.end());
  md << "## Peak memory, bytes per point (not in the paper)\n\n"
        "(peak RSS - idle child) / n; the points (24 B) and the order are included.\n\n";
  {
    std::vector<std::string> head = {"Distribution", "Datasize"};
    for (const Series& s : all_series) head.push_back(s.label());
    md << md_row(head) << md_rule(head.size(), 2);
    for (const paper::TimeTable& pt : paper::kTimes) {
      if (!t.sizes.count(pt.dist)) continue;
      for (std::size_t n : t.sizes.at(pt.dist)) {
        std::vector<std::string> row = {pt.dist, size_str(n)};
        for (const Series& s : all_series) {
          const BenchRecord* r = t.idx.find(pt.dist, n, s);
          row.push_back(!r ? "" : r->status == "ok" ? fixed(r->bytes_per_point, 0) : status_cell(*r));
        }
        md << md_row(row);
      }
    }
    md << "\n";
  }
  md << "## CGAL's other counts per point (not in the paper)\n\n"
        "All `Orientation_3` calls / `Side_of_oriented_sphere_3` calls, per point.\n\n";
  {
    std::vector<Series> cg;
    for (const Series& s : all_series)
      if (s.kernel == "cgal") cg.push_back(s);
    std::vector<std::string> head = {"Distribution", "Datasize"};
    for (const Series& s : cg) head.push_back(s.label());
    md << md_row(head) << md_rule(head.size(), 2);
    for (const paper::TimeTable& pt : paper::kTimes) {
      if (!t.sizes.count(pt.dist)) continue;
      for (std::size_t n : t.sizes.at(pt.dist)) {
        std::vector<std::string> row = {pt.dist, size_str(n)};
        for (const Series& s : cg) {
          const BenchRecord* r = t.idx.find(pt.dist, n, s);
          row.push_back(!r ? "" : r->status != "ok" ? status_cell(*r)
                                : fixed(r->orient_all_per_point, 1) + " / " + fixed(r->sphere_tests_per_point, 1));
        }
        md << md_row(row);
      }
    }
    md << "\n";
  }
}

}  // namespace

void write_bench_tables(const std::vector<BenchRecord>& records, const BenchReportInfo& info,
                        const std::string& path) {
  TableData t;
  for (const BenchRecord& r : records) {
    t.idx.by_key[{r.dist, r.n, r.kernel, r.order}] = &r;
    if (is_run(r)) {
      t.sizes[r.dist].insert(r.n);
      t.series[r.dist].insert({r.kernel, r.order});
    } else {
      t.order_sizes.insert(r.n);
    }
  }
  std::ostringstream md;
  md << "# kdmesh bench: the paper's Tables 1-15\n\n";
  md << "Generated by `kdmesh bench`";
  if (info.options) {
    md << " (seed " << info.options->seed << ", timeout " << info.options->timeout << " s"
       << (info.options->full ? ", --full" : "") << ")";
  }
  md << " on " << cpu_model() << ", " << std::thread::hardware_concurrency()
     << " hardware threads, in " << fixed(info.wall_seconds / 60.0, 1)
     << " min. kdmesh 0.1.0, CGAL 5.5, TetGen 1.5. An idle child process peaks at "
     << fixed(info.baseline_rss_bytes / 1048576.0, 1)
     << " MB. Raw data: `results.csv`; plots: `plots/time_per_point.png`.\n\n";
  md << kDefinitions << "`" << paper::kLabel
     << "`: the paper's numbers where it ran the same size. Its Kd-tree and BRIO columns\n"
        "  compare with `cgal kd-bfs` and `cgal brio`, its Hilbert column with `cgal range`.\n\n";

  time_tables(md, t);
  count_tables(md, t);
  order_table(md, t);
  memory_tables(md, t);

  AtomicFile file(path);
  {
    std::ofstream f(file.temp_path());
    f << md.str();
    f.flush();
    if (!f) throw OutputError(path, "write failed");
  }
  file.commit();
}

std::vector<std::string> write_bench_plots(const std::vector<BenchRecord>& records,
                                           const std::string& dir, std::vector<std::string>& warnings) {
  namespace fs = std::filesystem;
  const std::string gnuplot = find_program("gnuplot");
  if (gnuplot.empty()) {
    warnings.push_back("gnuplot not found: no plots (apt-get install gnuplot-nox)");
    return {};
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir, "cannot create the plot directory: " + ec.message());
  const std::string abs = fs::absolute(dir).string();
  auto quoted = [](const std::string& s) {  // gnuplot single-quoted string
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
  };

  // Series (lines) per distribution, and a style per series shared by all panels:
  // colour = order, dash = kernel.
  std::vector<std::string> dists;
  std::map<std::string, std::map<Series, std::vector<std::pair<double, double>>>> data;
  std::set<Series> all;
  for (const BenchRecord& r : records) {
    if (!is_run(r) || r.status != "ok" || !(r.total_seconds > 0)) continue;
    if (std::find(dists.begin(), dists.end(), r.dist) == dists.end()) dists.push_back(r.dist);
    data[r.dist][{r.kernel, r.order}].emplace_back(double(r.n), 1e6 * r.total_seconds / double(r.n));
    all.insert({r.kernel, r.order});
  }
  if (dists.empty()) {
    warnings.push_back("no successful runs: no plots");
    return {};
  }
  const char* colours[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#a6761d", "#e6ab02", "#000000"};
  auto style = [&](const Series& s) {
    const std::size_t c = std::min<std::size_t>(rank_of(kOrderOrder, s.order), 7);
    const int dash = s.kernel == "kdmesh" ? 1 : s.kernel == "cgal" ? 2 : 3;
    const char* marker = s.kernel == "kdmesh" ? "7" : s.kernel == "cgal" ? "5" : "9";
    return std::string("lw 2 pt ") + marker + " ps 0.8 dt " + std::to_string(dash) + " lc rgb '" + colours[c] + "'";
  };

  std::ostringstream gp;
  gp << "# Generated by kdmesh bench: time per point against N (gnuplot " << "5).\n";
  int block = 0;
  std::map<std::pair<std::string, Series>, std::string> block_of;
  for (const std::string& d : dists) {
    for (auto& [s, pts] : data[d]) {
      std::sort(pts.begin(), pts.end());
      const std::string name = "$b" + std::to_string(block++);
      block_of[{d, s}] = name;
      gp << name << " << EOD\n";
      for (const auto& [n, us] : pts) gp << n << " " << us << "\n";
      gp << "EOD\n";
    }
  }
  auto panel = [&](const std::string& d, bool key) {
    gp << "set title " << quoted(d) << "\n" << (key ? "set key outside right top\n" : "unset key\n");
    gp << "plot ";
    bool first = true;
    for (const auto& [s, pts] : data[d]) {
      gp << (first ? "" : ", \\\n     ") << block_of[{d, s}] << " using 1:2 with linespoints " << style(s)
         << " title " << quoted(s.label());
      first = false;
    }
    gp << "\n";
  };
  const std::string common =
      "set logscale xy\nset grid\nset format x '%.0s%c'\nset xlabel 'points N (log scale)'\n"
      "set ylabel 'microseconds per point (log scale)'\nset offsets graph 0.05, graph 0.05, 0, 0\n";

  std::vector<std::string> pngs;
  const std::string all_png = abs + "/time_per_point.png";
  const int cols = 3, rows = int((dists.size() + 1 + cols - 1) / cols);  // + 1: the legend panel
  gp << "set terminal pngcairo size " << 600 * cols << "," << 420 * rows << " font ',10'\n"
     << "set output " << quoted(all_png) << "\n" << common
     << "set multiplot layout " << rows << "," << cols
     << " title 'kdmesh bench: time per point (order + Delaunay) against N'\n";
  for (const std::string& d : dists) panel(d, false);
  // The legend panel: every series, no data.
  gp << "unset title\nunset border\nunset tics\nunset xlabel\nunset ylabel\nunset grid\n"
        "unset logscale xy\nset yrange [0:1]\nset xrange [0:1]\nset key center center\nplot ";
  bool first = true;
  for (const Series& s : all) {
    gp << (first ? "" : ", \\\n     ") << "NaN with linespoints " << style(s) << " title " << quoted(s.label());
    first = false;
  }
  gp << "\nunset multiplot\nreset\n";
  pngs.push_back(all_png);
  for (const std::string& d : dists) {
    const std::string png = abs + "/" + d + ".png";
    gp << "set terminal pngcairo size 900,600 font ',10'\nset output " << quoted(png) << "\n" << common;
    panel(d, true);
    gp << "reset\n";
    pngs.push_back(png);
  }
  gp << "set output\n";

  const std::string script = abs + "/time_per_point.gp";
  {
    std::ofstream f(script);
    f << gp.str();
    if (!f) throw OutputError(script, "write failed");
  }
  const ChildResult r = run_child({gnuplot, script}, 120);
  if (r.exit_code != 0 || r.timed_out) {
    warnings.push_back("gnuplot failed on " + script + ": " + r.err.substr(0, 500));
    return {};
  }
  return pngs;
}

}  // namespace kdmesh
