// kdmesh bench — one measurement (in a child process) and the benchmark loop (the parent).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The parent never triangulates: every (distribution, size, kernel, order) is a fresh child
// process (`kdmesh bench-run ... --json`, the executable itself), so that its peak memory
// (ru_maxrss from wait4) is that run's alone, and a run that exceeds --timeout can be killed.
// The child generates its points from (dist, n, seed) (not timed) instead of reading a file.
// CGAL runs get a second child with the counting traits (CgalOptions::count) for Tables 8-14;
// its time is not reported (counting changes CGAL's walk, see mesher/reference/reference_delaunay.h).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/timer.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/order/order.h"
#include "mesher/reference/reference_delaunay.h"
#include "tools/bench/lib/bench.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {

namespace {

const std::vector<std::string> kAllKernels = {"kdmesh", "cgal", "cgal-plain", "tetgen"};
/// Default orders, in table order; "cgal" is CGAL's insert(range) (cgal kernels only;
/// cgal-plain, stock CGAL without vertex info, takes no other).
const std::vector<std::string> kAllOrders = {"kd-bfs", "kd-bfs-hilbert", "kd-bfs-alt", "hilbert",
                                             "brio",   "random",         "cgal"};

/// The insertion orders are seeded apart from the point generator: both start from Rng(seed),
/// and a shuffle drawn from the generator's own stream would be correlated with coordinates.
constexpr std::uint64_t kOrderSeedMix = 0x9E3779B97F4A7C15ULL;

std::vector<std::size_t> steps(std::size_t first, std::size_t last, std::size_t step) {
  std::vector<std::size_t> v;
  for (std::size_t n = first; n <= last; n += step) v.push_back(n);
  return v;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

double nan_if_null(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNotMeasured;
}

std::string fmt(double x, int prec = 3) {
  if (std::isnan(x)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(prec) << x;
  return s.str();
}

/// Last non-empty line of a child's stderr (its error message).
std::string last_line(const std::string& text) {
  std::istringstream s(text);
  std::string line, last;
  while (std::getline(s, line))
    if (!line.empty()) last = line;
  return last;
}

/// One planned run and the series it belongs to (for skip-after-timeout).
struct Planned {
  RunSpec spec;
  std::string series() const { return spec.dist + "/" + spec.kernel + "/" + spec.order; }
};

std::vector<std::string> orders_for(const std::string& kernel, const std::vector<std::string>& orders) {
  if (kernel == "tetgen") return {"tetgen"};
  if (kernel == "cgal-plain") return {"cgal"};
  std::vector<std::string> v;
  for (const std::string& o : orders) {
    if (o == "tetgen") continue;
    if (o == "cgal" && kernel != "cgal") continue;
    v.push_back(o);
  }
  return v;
}

std::vector<Planned> make_plan(const BenchOptions& o, std::vector<std::string>& dists) {
  dists = o.dists;
  if (dists.empty())
    for (Distribution d : all_distributions()) dists.emplace_back(distribution_name(d));
  for (const std::string& d : dists) parse_distribution(d);  // throws UsageError
  std::vector<std::string> kernels = o.kernels.empty() ? kAllKernels : o.kernels;
  if (!tetgen_available()) {  // by default every kernel this build has; asked for, a clear error
    if (o.kernels.empty()) std::erase(kernels, std::string("tetgen"));
    else if (contains(kernels, "tetgen")) throw UsageError(without_tetgen_message("bench --kernels tetgen"));
  }
  for (const std::string& k : kernels)
    if (!contains(kAllKernels, k))
      throw UsageError("bench: unknown kernel '" + k + "' (valid: kdmesh, cgal, cgal-plain, tetgen)");
  const std::vector<std::string> orders = o.orders.empty() ? kAllOrders : o.orders;
  for (const std::string& ord : orders) {
    if (ord != "cgal" && ord != "tetgen") parse_order_kind(ord);  // throws UsageError
  }
  std::vector<Planned> plan;
  for (const std::string& d : dists) {
    std::vector<std::size_t> sizes =
        !o.sizes.empty() ? o.sizes : (o.full ? bench_paper_sizes(d) : bench_default_sizes(d));
    std::sort(sizes.begin(), sizes.end());
    for (std::size_t n : sizes) {
      if (n < 4) throw UsageError("bench: sizes must be at least 4 points");
      for (const std::string& k : kAllKernels) {  // fixed column order
        if (!contains(kernels, k)) continue;
        for (const std::string& ord : orders_for(k, orders)) plan.push_back({{d, n, o.seed, k, ord, false}});
      }
    }
  }
  // Table 15: building the kd-bfs and Hilbert orders alone, on the cube and the cylinder (and
  // kd-bfs-hilbert, not in the paper).
  std::vector<std::size_t> osizes = o.order_sizes;
  if (osizes.empty()) {
    if (!o.sizes.empty()) osizes = o.sizes;
    else if (o.full) osizes = steps(500000, 3500000, 500000);
    else osizes = {500000, 1000000};
  }
  std::sort(osizes.begin(), osizes.end());
  for (const std::string d : {"cube", "cylinder"}) {
    if (!contains(dists, d)) continue;
    for (std::size_t n : osizes) {
      if (n == 0) continue;  // --order-sizes 0: no Table 15 runs
      for (const std::string ord : {"kd-bfs", "hilbert", "kd-bfs-hilbert"})
        plan.push_back({{d, n, o.seed, "order-only", ord, false}});
    }
  }
  return plan;
}

std::vector<std::string> child_args(const BenchOptions& o, const RunSpec& s) {
  std::vector<std::string> a = {o.exe,         "bench-run", "--dist", s.dist,          "-n",
                                std::to_string(s.n), "--seed", std::to_string(s.seed), "--kernel",
                                s.kernel,      "--order",   s.order,  "--json",        "-q"};
  if (s.count) a.push_back("--count");
  return a;
}

/// Runs one child; fills `m` from its JSON. Returns "ok", "timeout" or "failed" (+ note).
std::string run_measurement(const BenchOptions& o, const RunSpec& s, RunMeasurement& m,
                            ChildResult& child, std::string& note) {
  child = run_child(child_args(o, s), o.timeout);
  if (child.timed_out) {
    note = "killed after the " + fmt(o.timeout, 0) + " s timeout";
    return "timeout";
  }
  if (child.exit_code != 0) {
    note = child.signal ? "killed by signal " + std::to_string(child.signal)
                        : "exit " + std::to_string(child.exit_code) + ": " + last_line(child.err);
    return "failed";
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(child.out);
    m.order_seconds = nan_if_null(j, "order_seconds");
    m.delaunay_seconds = nan_if_null(j, "delaunay_seconds");
    m.orient_tests = nan_if_null(j, "orient_tests");
    m.orient_all = nan_if_null(j, "orient_all");
    m.sphere_tests = nan_if_null(j, "sphere_tests");
    m.conflicts = nan_if_null(j, "conflicts");
    m.tets = j.value("tets", std::size_t(0));
  } catch (const nlohmann::json::exception& e) {
    note = std::string("unreadable child output: ") + e.what();
    return "failed";
  }
  return "ok";
}

std::string progress_line(std::size_t i, std::size_t total, const BenchRecord& r) {
  std::ostringstream s;
  s << "[" << std::setw(3) << i << "/" << total << "] " << std::left << std::setw(10) << r.dist
    << std::right << std::setw(8) << r.n << " " << std::left << std::setw(11) << r.kernel
    << std::setw(15) << r.order << std::right;
  if (r.status == "ok") {
    s << (std::isnan(r.order_seconds) ? std::string(" order -") : " order " + fmt(r.order_seconds) + " s");
    if (!std::isnan(r.delaunay_seconds))
      s << ", delaunay " << fmt(r.delaunay_seconds) << " s, total " << fmt(r.total_seconds) << " s";
    if (!std::isnan(r.orient_per_point))
      s << ", " << fmt(r.orient_per_point, 1) << " orient/pt, " << fmt(r.conflicts_per_point, 1)
        << " conflicts/pt";
    if (!std::isnan(r.bytes_per_point)) s << ", " << fmt(r.bytes_per_point, 0) << " B/pt";
    if (!std::isnan(r.count_wall_seconds)) s << " (counting pass " << fmt(r.count_wall_seconds, 1) << " s)";
  }
  s << "  " << r.status;
  if (!r.note.empty()) s << " (" << r.note << ")";
  return s.str();
}

}  // namespace

std::vector<std::size_t> bench_paper_sizes(const std::string& dist) {
  const Distribution d = parse_distribution(dist);
  switch (d) {
    case Distribution::cube: return steps(100000, 600000, 100000);
    case Distribution::planes:
    case Distribution::axes: return steps(300000, 1050000, 150000);
    case Distribution::paraboloid: return {180000, 360000, 540000, 720000, 900000, 1050000};
    case Distribution::spiral:
    case Distribution::disk:
    case Distribution::cylinder: return steps(360000, 2160000, 360000);
    // The practical models (Tables 16-17), emulated by the constrained-cube generators.
    case Distribution::constrained_cube: return {4386533};
    case Distribution::refined_constrained_cube: return {5500000};
  }
  throw UsageError("bench: no sizes for distribution '" + dist + "'");
}

std::vector<std::size_t> bench_default_sizes(const std::string& dist) {
  // The paper's first size, and an eighth, a quarter and a half of it: the default run (7
  // distributions, all kernels and orders, random order up to 150 000 points) then takes
  // about 10 minutes on the 2-core development machine.
  const std::size_t first = bench_paper_sizes(dist).front();
  return {first / 8, first / 4, first / 2, first};
}

RunMeasurement measure_run(const RunSpec& s) {
  const Distribution d = parse_distribution(s.dist);
  const bool own_order = s.order == "cgal" || s.order == "tetgen";
  if (s.kernel == "tetgen"       ? s.order != "tetgen"
      : s.kernel == "cgal-plain" ? s.order != "cgal"
                                 : (s.order == "tetgen" || (s.order == "cgal" && s.kernel != "cgal")))
    throw UsageError("bench-run: order '" + s.order + "' does not go with kernel '" + s.kernel + "'");
  if (!contains({"kdmesh", "cgal", "cgal-plain", "tetgen", "order-only"}, s.kernel))
    throw UsageError("bench-run: unknown kernel '" + s.kernel + "'");
  if (s.count && s.kernel != "cgal") throw UsageError("bench-run: --count is for --kernel cgal");
  OrderOptions oo;
  if (!own_order) oo = {parse_order_kind(s.order), s.seed ^ kOrderSeedMix, 0.125};
  oo.threads = 1;  // the kernels run on one thread here, and so does the order

  const PointSet pts = generate_points(d, s.n, s.seed);
  RunMeasurement m;
  Ordering ord;
  if (!own_order) {
    Stopwatch clock;
    ord = make_order(pts, oo);
    m.order_seconds = clock.seconds();
  }
  if (s.kernel == "order-only") return m;
  if (s.kernel == "tetgen") {
    const ReferenceResult r = tetgen_delaunay(pts);
    m.delaunay_seconds = r.seconds;
    m.tets = r.tets.size() / 4;
  } else if (s.kernel == "cgal" || s.kernel == "cgal-plain") {
    CgalOptions co;
    co.count = s.count;
    co.plain = s.kernel == "cgal-plain";
    const ReferenceResult r = cgal_delaunay(pts, own_order ? nullptr : &ord, co);
    m.delaunay_seconds = r.seconds;
    m.tets = r.tets.size() / 4;
    if (r.counted) {
      m.orient_tests = double(r.locate_orient_tests);
      m.orient_all = double(r.orient_tests);
      m.sphere_tests = double(r.sphere_tests);
      m.conflicts = double(r.conflicts);
    }
  } else {
    const DelaunayResult r = delaunay(pts, ord);
    m.delaunay_seconds = r.stats.seconds;
    m.tets = count_finite_tets(r.tri);  // no copy: it would inflate the peak memory
    m.orient_tests = double(r.stats.orient_tests);
    m.conflicts = double(r.stats.conflicts);
  }
  return m;
}

BenchSummary run_bench(const BenchOptions& o, const std::function<void(const std::string&)>& log) {
  namespace fs = std::filesystem;
  Stopwatch wall;
  BenchSummary sum;
  auto say = [&](const std::string& s) {
    if (log) log(s);
  };
  if (o.exe.empty()) throw UsageError("bench: no executable to run the measurements with");
  if (o.timeout < 0) throw UsageError("bench: --timeout must not be negative");
  std::vector<std::string> dists;
  const std::vector<Planned> plan = make_plan(o, dists);

  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw OutputError(o.out_dir, "cannot create the output directory: " + ec.message());
  sum.csv_path = (fs::path(o.out_dir) / "results.csv").string();
  sum.tables_path = (fs::path(o.out_dir) / "tables.md").string();

  // The memory of a child that does nothing: subtracted before dividing by n.
  {
    const ChildResult base = run_child({o.exe, "bench-run", "--baseline", "--json", "-q"}, 60);
    if (base.exit_code != 0)
      throw Error("bench: the baseline child failed: " + last_line(base.err));
    sum.baseline_rss_bytes = base.peak_rss_bytes;
  }
  say("baseline: an idle child peaks at " + fmt(sum.baseline_rss_bytes / 1048576.0, 1) +
      " MB; " + std::to_string(plan.size()) + " runs, timeout " + fmt(o.timeout, 0) + " s");

  // Random order's cap on n (see BenchOptions::random_max_n).
  std::size_t random_max = o.random_max_n;
  if (random_max == BenchOptions::kAutoRandomMax) random_max = o.full || !o.sizes.empty() ? 0 : 150000;

  // Per series (dist/kernel/order, and the same + "#count" for CGAL's counting child): whether
  // it timed out, and its (n, wall seconds) so far, to skip runs that would time out.
  std::set<std::string> timed_out;
  std::map<std::string, std::vector<std::pair<double, double>>> history;
  auto predicted_seconds = [&](const std::string& key, const RunSpec& s) -> double {
    const auto it = history.find(key);
    if (it == history.end() || it->second.empty()) return 0;
    const auto& h = it->second;
    const auto [n1, t1] = h.back();
    // Growth exponent: fitted on the last two sizes when there are two (clamped to [1, 3]),
    // else 2 for random order (its walks grow like n^(1/3) to n per point) and 1.2 otherwise.
    double e = s.order == "random" ? 2.0 : 1.2;
    if (h.size() >= 2) {
      const auto [n0, t0] = h[h.size() - 2];
      if (n1 > n0 && t0 > 0.5) e = std::clamp(std::log(t1 / t0) / std::log(n1 / n0), 1.0, 3.0);
    }
    return t1 * std::pow(double(s.n) / n1, e);
  };
  auto skip_reason = [&](const std::string& key, const RunSpec& s) -> std::string {
    if (timed_out.count(key)) return "timed out at a smaller size";
    if (s.order == "random" && random_max && s.n > random_max)
      return "random order only up to n=" + std::to_string(random_max) + " (--random-max-n)";
    const double t = o.timeout > 0 ? predicted_seconds(key, s) : 0;
    if (t > o.timeout) return "predicted " + fmt(t, 0) + " s > timeout";
    return {};
  };

  std::size_t i = 0;
  for (const Planned& p : plan) {
    ++i;
    const RunSpec& s = p.spec;
    BenchRecord r;
    r.dist = s.dist;
    r.n = s.n;
    r.kernel = s.kernel;
    r.order = s.order;
    const std::string key = p.series();
    r.note = skip_reason(key, s);
    if (!r.note.empty()) {
      r.status = "skipped";
    } else {
      RunMeasurement m;
      ChildResult child;
      r.status = run_measurement(o, s, m, child, r.note);
      r.wall_seconds = child.wall_seconds;
      if (r.status == "timeout") timed_out.insert(key);
      if (r.status == "ok") {
        history[key].emplace_back(double(s.n), child.wall_seconds);
        const double n = double(s.n);
        r.order_seconds = m.order_seconds;
        r.delaunay_seconds = m.delaunay_seconds;
        r.total_seconds = (std::isnan(m.order_seconds) ? 0.0 : m.order_seconds) +
                          (std::isnan(m.delaunay_seconds) ? 0.0 : m.delaunay_seconds);
        r.orient_per_point = m.orient_tests / n;
        r.conflicts_per_point = m.conflicts / n;
        r.tets = m.tets;
        r.peak_rss_bytes = child.peak_rss_bytes;
        r.bytes_per_point = std::max(0.0, child.peak_rss_bytes - sum.baseline_rss_bytes) / n;
        const std::string ckey = key + "#count";
        const std::string cskip = s.kernel == "cgal" && o.count_cgal ? skip_reason(ckey, s) : "";
        if (!cskip.empty()) {
          r.note = "counting pass skipped: " + cskip;
        } else if (s.kernel == "cgal" && o.count_cgal) {
          // The counting pass: same points and order, counting traits, its own child.
          RunSpec cs = s;
          cs.count = true;
          RunMeasurement cm;
          ChildResult cchild;
          std::string cnote;
          const std::string cstatus = run_measurement(o, cs, cm, cchild, cnote);
          r.count_wall_seconds = cchild.wall_seconds;
          if (cstatus == "timeout") timed_out.insert(ckey);
          if (cstatus == "ok") {
            history[ckey].emplace_back(double(s.n), cchild.wall_seconds);
            r.orient_per_point = cm.orient_tests / n;
            r.orient_all_per_point = cm.orient_all / n;
            r.sphere_tests_per_point = cm.sphere_tests / n;
            r.conflicts_per_point = cm.conflicts / n;
          } else {
            r.note = "counting pass " + cstatus + ": " + cnote;
          }
        }
      }
    }
    say(progress_line(i, plan.size(), r));
    sum.records.push_back(std::move(r));
    write_bench_csv(sum.records, sum.csv_path);  // after every run: partial results survive
  }

  sum.wall_seconds = wall.seconds();
  BenchReportInfo info;
  info.options = &o;
  info.baseline_rss_bytes = sum.baseline_rss_bytes;
  info.wall_seconds = sum.wall_seconds;
  write_bench_tables(sum.records, info, sum.tables_path);
  if (o.plots) {
    sum.plot_paths = write_bench_plots(sum.records, (fs::path(o.out_dir) / "plots").string(), sum.warnings);
  }
  for (const std::string& w : sum.warnings) say("warning: " + w);
  sum.wall_seconds = wall.seconds();
  return sum;
}

}  // namespace kdmesh
