// kdmesh points — generate one of the paper's seven point distributions.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <string>

#include "core/timer.h"
#include "io/points_io.h"
#include "tools/kdmesh/cli.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh::cli {

namespace {

struct PointsOptions {
  std::string dist = "cube";
  std::size_t n = 100000;
  std::uint64_t seed = 1;
  std::string output;
  Output out;
};

int run_points(const PointsOptions& o) {
  Stopwatch clock;
  const Distribution d = parse_distribution(o.dist);
  const PointSet pts = generate_points(d, o.n, o.seed);
  const double t_gen = clock.seconds();
  clock.reset();
  write_xyz(pts, o.output);
  const double t_write = clock.seconds();
  o.out.human() << "points: " << pts.size() << " (" << o.dist << ", seed " << o.seed << ") -> "
                << o.output << "  [generate " << t_gen << " s, write " << t_write << " s]\n";
  o.out.emit_json({{"command", "points"},
                   {"distribution", o.dist},
                   {"points", pts.size()},
                   {"seed", o.seed},
                   {"output", o.output},
                   {"seconds", {{"generate", t_gen}, {"write", t_write}}}});
  return 0;
}

}  // namespace

void add_points_command(CLI::App& app, Runner& run) {
  auto opts = std::make_shared<PointsOptions>();
  CLI::App* cmd = app.add_subcommand("points", "Generate a point distribution of the paper (Fig. 6)");
  cmd->add_option("--dist", opts->dist, "Distribution")
      ->check(CLI::IsMember({"cube", "planes", "paraboloid", "spiral", "disk", "cylinder", "axes",
                             "constrained-cube", "refined-constrained-cube"}))
      ->capture_default_str();
  cmd->add_option("-n", opts->n, "Number of points")->check(CLI::Range(std::size_t(1), std::size_t(1) << 28))->capture_default_str();
  cmd->add_option("--seed", opts->seed, "Random seed (same seed, same points)")->capture_default_str();
  cmd->add_option("-o,--output", opts->output, "Output .xyz file")->required()->check(non_empty_path());
  add_output_flags(cmd, opts->out);
  cmd->callback([opts, &run] { run = [opts] { return run_points(*opts); }; });
}

}  // namespace kdmesh::cli
