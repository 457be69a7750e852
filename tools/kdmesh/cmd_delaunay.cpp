// kdmesh delaunay — tetrahedralize a point set, optionally verify it three ways, write VTU.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/timer.h"
#include "io/points_io.h"
#include "io/vtu_writer.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/order/order.h"
#include "mesher/reference/reference_delaunay.h"
#include "core/memory_amount.h"
#include "mesher/reference/tet_adjacency.h"
#include "mesher/reference/tet_compare.h"
#include "tools/kdmesh/cli.h"
#include "tools/app/delaunay_verify.h"
#include "tools/app/job_paths.h"

namespace kdmesh::cli {

namespace {

struct Options {
  std::string input;
  std::string order = "kd-bfs-hilbert";
  std::string kernel = "kdmesh";
  std::uint64_t seed = 1;
  bool check = false;
  unsigned threads = 1;  ///< kdmesh kernel: inserting threads (0 = one per CPU the process may use)
  bool count = false;  ///< CGAL kernel: count predicates (counting traits; slower)
  std::string max_memory;  ///< empty: the machine's memory
  std::string output;
  Output out;
};

/// Peak bytes per point of `kdmesh delaunay`, measured with /usr/bin/time -v on uniform
/// points (docs/robustness.md, "Memory"): the kernel alone, and what -o and --check add.
constexpr double kDelaunayBytesPerPoint = 300, kOutputBytesPerPoint = 720, kCheckBytesPerPoint = 1100;

/// Prints the memory estimate and refuses (ResourceError) a run that would exceed the limit.
void check_memory(const Options& o, std::size_t n, nlohmann::json& j) {
  const double limit_option = o.max_memory.empty() ? 0 : parse_memory_amount(o.max_memory, "--max-memory");
  const double limit = effective_memory_limit(limit_option);
  const double per_point = kDelaunayBytesPerPoint + (o.output.empty() ? 0 : kOutputBytesPerPoint) +
                           (o.check ? kCheckBytesPerPoint : 0);
  const double bytes = 16e6 + per_point * double(n);
  const std::string limit_text = limit > 0 ? format_bytes(limit) : std::string("none");
  j["estimate"] = {{"peak_bytes", bytes}, {"limit_bytes", limit}};
  o.out.stage("estimate: ~" + format_bytes(bytes) + " peak memory (limit " + limit_text + ")");
  if (limit > 0 && bytes > limit)
    throw ResourceError(o.input + ": " + std::to_string(n) + " points need an estimated " + format_bytes(bytes) +
                        " of memory but the limit is " + limit_text +
                        (limit_option > 0 ? " (--max-memory)" : " (the machine's memory)") +
                        "; raise it with --max-memory (none = no limit)");
}

nlohmann::json run_checks(const Options& o, const PointSet& pts, const Triangulation& tri,
                          const std::vector<std::uint32_t>& canon_tets) {
  DelaunayVerifyOptions v;
  v.compare_kdmesh_kernel = o.kernel != "kdmesh";
  v.seed = o.seed;
  v.stage = [&o](const std::string& s) { o.out.stage(s); };
  DelaunayVerification r = verify_delaunay(pts, tri, canon_tets, v);
  o.out.human() << r.report;
  return std::move(r.json);
}

/// The kdmesh kernel's counts (returned), its walk histogram and duplicates (into j), and the
/// first duplicates for the reader.
nlohmann::json kernel_counts(const DelaunayStats& st, const Output& out, nlohmann::json& j) {
  const double k = double(std::max<std::uint64_t>(st.inserted, 1));
  const nlohmann::json counts = {{"inserted", st.inserted},
                                 {"threads", st.threads},
                                 {"duplicates", st.duplicates.size()},
                                 {"orient_tests_per_point", double(st.orient_tests) / k},
                                 {"conflicts_per_point", double(st.conflicts) / k},
                                 {"exact_fallbacks", st.exact_fallbacks},
                                 {"parallel_rounds", st.parallel_rounds},
                                 {"deferrals", st.deferrals}};
  // The walks by orientation tests (DelaunayStats::walks): bins [lo, hi], hi null for the
  // open last bin.
  nlohmann::json bins = nlohmann::json::array();
  for (std::size_t b = 0; b < kWalkBins; ++b) {
    const std::uint64_t lo = b == 0 ? 0 : std::uint64_t(1) << (b - 1);
    const nlohmann::json hi = b == 0 ? nlohmann::json(0)
                              : b + 1 == kWalkBins ? nlohmann::json(nullptr)
                                                  : nlohmann::json((std::uint64_t(1) << b) - 1);
    bins.push_back({{"tests_min", lo}, {"tests_max", hi}, {"walks", st.walks[b]},
                    {"tests", st.walk_tests[b]}});
  }
  j["walk_histogram"] = bins;
  for (std::size_t i = 0; i < st.duplicates.size(); ++i) {
    if (i == 10) {
      out.human() << "  ... " << st.duplicates.size() - 10 << " more duplicates\n";
      break;
    }
    out.human() << "  duplicate: point " << st.duplicates[i] << " repeats point "
                << st.duplicate_of[i] << " (skipped)\n";
  }
  j["duplicates"] = nlohmann::json::array();
  for (std::size_t i = 0; i < std::min<std::size_t>(st.duplicates.size(), 1000); ++i)
    j["duplicates"].push_back({st.duplicates[i], st.duplicate_of[i]});
  return counts;
}

/// The run's counts for the reader: tets, tests per point, the walks' tail, parallel rounds.
void print_counts(const Output& out, const nlohmann::json& counts, const nlohmann::json& j,
                  std::size_t n, std::size_t num_tets, const Options& o) {
  out.human() << "delaunay: " << n << " points, " << num_tets << " tets, kernel " << o.kernel
              << ", order " << o.order << "\n";
  if (counts.contains("orient_tests_per_point")) {
    out.human() << "  orientation tests per point " << std::setprecision(4)
                << counts["orient_tests_per_point"].get<double>() << ", conflicts per point "
                << counts["conflicts_per_point"].get<double>();
    if (counts.contains("exact_fallbacks"))
      out.human() << ", exact fallbacks " << counts["exact_fallbacks"].get<std::uint64_t>();
    out.human() << "\n";
  }
  if (j.contains("walk_histogram")) {
    // The tail a mean hides: walks of 64 tests or more (bins 7 and up).
    double walks = 0, tests = 0, long_walks = 0, long_tests = 0;
    for (std::size_t b = 0; b < kWalkBins; ++b) {
      const double w = j["walk_histogram"][b]["walks"].get<double>();
      const double t = j["walk_histogram"][b]["tests"].get<double>();
      walks += w;
      tests += t;
      if (b >= 7) {
        long_walks += w;
        long_tests += t;
      }
    }
    if (walks > 0 && tests > 0)
      out.human() << "  walks of 64+ orientation tests: " << std::setprecision(3)
                  << 100 * long_walks / walks << "% of the walks, " << 100 * long_tests / tests
                  << "% of the tests\n";
  }
  if (counts.value("parallel_rounds", 0u) > 0)
    out.human() << "  parallel: " << counts["parallel_rounds"].get<unsigned>() << " rounds on "
                << counts["threads"].get<unsigned>() << " threads, " << counts["deferrals"].get<std::uint64_t>()
                << " points deferred to a later round\n";
}

int run_delaunay(const Options& o) {
  const Output& out = o.out;
  Stopwatch total, clock;
  nlohmann::json j = {{"command", "delaunay"}, {"input", o.input}, {"order", o.order}, {"kernel", o.kernel}};

  check_run_paths(o.input, {{"-o", o.output}});  // before any work
  out.stage("reading " + o.input);
  const PointSet pts = read_points(o.input);
  const double t_read = clock.seconds();
  const std::size_t n = pts.size();
  out.stage(std::to_string(n) + " points");
  check_memory(o, n, j);

  clock.reset();
  const bool cgal_sort = o.order == "cgal";
  const bool plain = o.kernel == "cgal-plain";
  if (cgal_sort && o.kernel == "kdmesh")
    throw UsageError("--order cgal means CGAL's own insert(range) order and needs --kernel cgal");
  if (plain && !cgal_sort)
    throw UsageError("--kernel cgal-plain is stock CGAL inserting a Point_3 range in its own order: "
                     "it needs --order cgal");
  if (o.count && o.kernel != "cgal")
    throw UsageError("--count applies to --kernel cgal (the kdmesh kernel always counts)");
  if (o.threads != 1 && o.kernel != "kdmesh")
    throw UsageError("--threads applies to --kernel kdmesh (CGAL and TetGen run sequentially here)");
  Ordering ord;
  if (!cgal_sort) {
    OrderOptions oo{parse_order_kind(o.order), o.seed, 0.125};
    oo.threads = o.threads == 1 ? 1 : 0;  // --threads 1: the order too is built on one thread
    ord = make_order(pts, oo);
  }
  const double t_order = clock.seconds();

  clock.reset();
  out.stage("tetrahedralizing (" + o.kernel + " kernel, " + o.order + " order)");
  std::vector<std::uint32_t> tets;
  Triangulation tri;
  nlohmann::json counts;
  double kernel_seconds = -1;  // when the kernel's own call is timed apart
  if (o.kernel == "kdmesh") {
    DelaunayOptions opt;
    opt.progress = out.progress("delaunay");
    opt.threads = o.threads;
    DelaunayResult r = delaunay(pts, ord, opt);
    tri = std::move(r.tri);
    counts = kernel_counts(r.stats, out, j);
  } else {
    CgalOptions co;
    co.count = o.count;
    co.plain = plain;
    const ReferenceResult r = cgal_delaunay(pts, cgal_sort ? nullptr : &ord, co);
    if (plain) kernel_seconds = r.seconds;  // insert(range) alone, not the id lookup after it
    tets = r.tets;
    counts = {{"inserted", r.num_vertices}, {"duplicates", n - r.num_vertices}};
    if (r.counted) {
      // The paper's counts, as kdmesh bench takes them: orientation tests of point location,
      // and cells in conflict, per inserted point.
      const double k = double(std::max<std::size_t>(r.num_vertices, 1));
      counts["orient_tests_per_point"] = double(r.locate_orient_tests) / k;
      counts["conflicts_per_point"] = double(r.conflicts) / k;
      counts["all_orient_tests_per_point"] = double(r.orient_tests) / k;
      counts["sphere_tests_per_point"] = double(r.sphere_tests) / k;
    }
  }
  const double t_del = kernel_seconds >= 0 ? kernel_seconds : clock.seconds();
  std::size_t num_tets = tets.size() / 4;
  if (o.kernel == "kdmesh") {
    // The finite tets are copied out only when an output or a check needs them: the copy is
    // 16 bytes per tet, a third of the peak memory of a plain run.
    num_tets = count_finite_tets(tri);
    if (o.check || !o.output.empty()) tets = finite_tets(tri);
  }
  if (num_tets == 0)
    throw GeometryError("no tetrahedra: the points span no volume (coplanar or fewer than 4)");

  print_counts(out, counts, j, n, num_tets, o);
  out.human() << std::setprecision(4) << "  time: read " << t_read << " s, order " << t_order
              << " s, delaunay " << t_del << " s\n";

  double t_check = 0;
  if (o.check) {
    clock.reset();
    std::vector<std::uint32_t> canon_tets = tets;
    const auto canon = canonical_point_ids(pts);
    for (auto& x : canon_tets) x = canon[x];
    if (o.kernel != "kdmesh") tri = triangulation_from_tets(canon_tets);
    j["check"] = run_checks(o, pts, tri, canon_tets);
    t_check = clock.seconds();
  }

  double t_write = 0;
  if (!o.output.empty() && (!o.check || j["check"]["pass"].get<bool>())) {
    clock.reset();
    out.stage("writing " + o.output);
    TetMesh mesh;
    mesh.points = pts;
    mesh.tets = std::move(tets);
    if (!cgal_sort) {
      DataArray rank{"insertion_rank", std::vector<std::int32_t>(n), {}};
      for (std::size_t k = 0; k < n; ++k) rank.ints[ord.order[k]] = std::int32_t(k);
      mesh.point_data.push_back(std::move(rank));
    }
    if (!ord.level.empty()) {
      DataArray level{"kd_level", std::vector<std::int32_t>(n), {}};
      for (std::size_t k = 0; k < n; ++k) level.ints[ord.order[k]] = ord.level[k];
      mesh.point_data.push_back(std::move(level));
    }
    write_vtu(mesh, o.output);
    t_write = clock.seconds();
    j["output"] = o.output;
  }
  j["points"] = n;
  j["tets"] = num_tets;
  j["counts"] = counts;
  j["seconds"] = {{"read", t_read}, {"order", t_order}, {"delaunay", t_del},
                  {"check", t_check}, {"write", t_write}, {"total", total.seconds()}};
  out.emit_json(j);
  if (o.check && !j["check"]["pass"].get<bool>())
    throw CheckError("verification failed (see above); no mesh was written");
  return 0;
}

}  // namespace

void add_delaunay_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("delaunay", "Delaunay tetrahedralization of a point set (.xyz, .node, .ply)");
  cmd->add_option("input", o->input, "Point file")->required();
  std::vector<std::string> orders = order_kind_names();
  orders.push_back("cgal");
  cmd->add_option("--order", o->order, "Insertion order (cgal: CGAL's own, with --kernel cgal or cgal-plain)")
      ->check(CLI::IsMember(orders))
      ->capture_default_str();
  cmd->add_option("--kernel", o->kernel,
                  "Delaunay kernel (cgal: CGAL's Delaunay_triangulation_3 with point ids as vertex info; "
                  "cgal-plain: stock CGAL, no vertex info, inserting a Point_3 range, timed alone)")
      ->check(CLI::IsMember({"kdmesh", "cgal", "cgal-plain"}))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the random and brio orders")->capture_default_str();
  cmd->add_option("--threads", o->threads,
                  "kdmesh kernel: inserting threads (0 = one per CPU the process may use); the tets are "
                  "the same for any count. With 1, the insertion order is built on one thread too")
      ->capture_default_str();
  cmd->add_flag("--check", o->check,
                "Verify: exact validity, then compare with TetGen 1.5 and CGAL 5.5; exit 5 on mismatch");
  cmd->add_flag("--count", o->count,
                "With --kernel cgal: count orientation tests and conflicting cells (counting "
                "traits; its time is not CGAL's normal speed)");
  cmd->add_option("--max-memory", o->max_memory,
                  "Refuse the run (exit 7) if its estimated peak memory exceeds this, e.g. 8G, "
                  "none (default: the machine's memory)");
  cmd->add_option("-o,--output", o->output, "Output .vtu file (binary, compressed)")->check(non_empty_path());
  add_output_flags(cmd, o->out);
  cmd->callback([o, &run] { run = [o] { return run_delaunay(*o); }; });
}

}  // namespace kdmesh::cli
