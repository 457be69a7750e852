// kdmesh batch — run the meshing jobs of a YAML batch file, concurrently, each one isolated.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/timer.h"
#include "core/memory_amount.h"
#include "tools/kdmesh/cli.h"
#include "tools/app/batch_schedule.h"
#include "tools/app/job_config.h"
#include "tools/app/job_process.h"
#include "tools/app/mesh_job.h"
#include "tools/kdmesh/batch_mpi.h"

namespace kdmesh::cli {

namespace {

struct Options {
  std::string file;
  unsigned jobs = 1;
  std::string out_dir;
  std::vector<std::string> only;
  std::string max_memory;  ///< for jobs that set none
  double timeout = 0;      ///< for jobs that set none (seconds; 0 = none)
  bool allow_outside = false;
  std::string shard;       ///< "i/N": run only that share of the jobs
  Output out;
};

/// The jobs --only selects, in file order. Unknown names are a usage error.
std::vector<MeshJob> select_jobs(BatchConfig config, const std::vector<std::string>& only) {
  if (only.empty()) return std::move(config.jobs);
  std::vector<std::string> names;
  for (const MeshJob& j : config.jobs) names.push_back(j.name);
  for (const std::string& n : only)
    if (std::find(names.begin(), names.end(), n) == names.end()) {
      const std::string near = closest_match(n, names);
      std::string all;
      for (const std::string& x : names) all += (all.empty() ? "" : ", ") + x;
      throw UsageError("--only " + n + ": no such job in " + config.file +
                       (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; jobs: " + all);
    }
  std::vector<MeshJob> out;
  for (MeshJob& j : config.jobs)
    if (std::find(only.begin(), only.end(), j.name) != only.end()) out.push_back(std::move(j));
  return out;
}

std::string fixed(double x, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

/// The summary table: job, status, nodes, tets, min dihedral, mean edge/target, time.
void print_table(std::ostream& os, const std::vector<MeshJobResult>& results) {
  std::size_t w = 3;
  for (const MeshJobResult& r : results) w = std::max(w, r.summary.value("job", std::string()).size());
  os << std::left << std::setw(int(w) + 2) << "job" << std::setw(16) << "status" << std::right
     << std::setw(10) << "nodes" << std::setw(11) << "tets" << std::setw(14) << "min dihedral"
     << std::setw(18) << "mean edge/target" << std::setw(10) << "time (s)" << "\n";
  for (const MeshJobResult& r : results) {
    const nlohmann::json& j = r.summary;
    const std::string status =
        r.ok() ? "ok" : "FAILED (" + j["error"].value("type", std::string("internal")) + ")";
    auto count = [&](const char* k) {
      return j.contains("counts") && j["counts"].contains(k) ? std::to_string(j["counts"][k].get<std::uint64_t>())
                                                              : std::string("-");
    };
    const bool q = r.ok() && j.contains("quality");
    os << std::left << std::setw(int(w) + 2) << j.value("job", std::string()) << std::setw(16) << status
       << std::right << std::setw(10) << count("nodes") << std::setw(11) << count("tets")
       << std::setw(14) << (q ? fixed(j["quality"]["min_dihedral"].get<double>(), 2) : "-")
       << std::setw(18) << (q ? fixed(j["size_fidelity"]["mean_ratio"].get<double>(), 3) : "-")
       << std::setw(10)
       << (j.contains("seconds") ? fixed(j["seconds"].value("total", 0.0), 2) : std::string("-")) << "\n";
  }
}

/// The batch as rank `world.rank` of `world.size`; sets *agreed once the ranks of an MPI run
/// have agreed that their set-up succeeded (run_batch).
int run_batch_as(const Options& o, const MpiWorld& world, bool* agreed) {
  const Output& out = o.out;
  Stopwatch total;
  BatchLoadOptions lo;
  lo.out_dir = o.out_dir;
  lo.allow_outside_out_dir = o.allow_outside;
  const double limit = o.max_memory.empty() ? 0 : parse_memory_amount(o.max_memory, "--max-memory");
  lo.max_memory = limit;
  const std::optional<Shard> shard = o.shard.empty() ? std::nullopt : std::optional(parse_shard(o.shard, "--shard"));
  if (world.size > 1 && !mpi_available())
    throw UsageError("started by mpirun with " + std::to_string(world.size) +
                     " ranks, but this kdmesh was built without MPI (libopenmpi-dev was missing): every "
                     "rank would run every job; run it without mpirun, or split the batch with --shard i/N");
  const BatchConfig config = load_batch_config(o.file, lo);  // InputError: exit 3
  std::vector<MeshJob> jobs = select_jobs(config, o.only);
  for (MeshJob& j : jobs) {
    if (j.max_memory == 0) j.max_memory = limit;
    if (j.timeout == 0) j.timeout = o.timeout;
  }
  const std::size_t listed = jobs.size();
  if (shard) {  // a deterministic share, balanced by estimated size: the same on every task
    std::vector<MeshJob> mine;
    for (const std::size_t i : shard_jobs(estimate_job_costs(jobs), *shard)) mine.push_back(std::move(jobs[i]));
    jobs = std::move(mine);
  }
  const bool mpi = world.size > 1;
  const unsigned workers = mpi ? unsigned(world.size - 1) : std::max(1u, std::min<unsigned>(o.jobs, unsigned(jobs.size())));
  if (world.rank == 0)
    out.stage(std::to_string(jobs.size()) + " job" + (jobs.size() == 1 ? "" : "s") + " from " + o.file +
              (shard ? " (shard " + o.shard + " of its " + std::to_string(listed) + ")" : std::string()) + ", " +
              (mpi ? std::to_string(workers) + " MPI worker ranks, largest first"
                   : std::to_string(workers) + " at a time"));

  std::mutex log_mutex;
  const bool tty = !out.quiet && isatty(STDERR_FILENO);
  auto log = [&](const std::string& name, const std::string& msg) {
    if (out.quiet) return;
    std::lock_guard<std::mutex> lock(log_mutex);
    std::cerr << ("kdmesh: [" + name + "] " + msg + "\n") << std::flush;  // one write (print_error)
  };

  // Each job in its own process: a crash (a bug, the OOM killer) fails that job only.
  auto callbacks = [&](std::size_t i) {
    const MeshJob& job = jobs[i];
    // Whole progress lines: one per 10% step on a terminal, one per 25% in logs.
    auto last = std::make_shared<std::map<std::string, int>>();
    MeshJobCallbacks cb;
    cb.log = [&, name = job.name](const std::string& s) { log(name, s); };
    if (!out.quiet)
      cb.progress = [&, last, name = job.name](const std::string& stage, double f) {
        const int unit = tty ? 10 : 25;
        const int percent = int(f * 100) / unit * unit;
        {  // stages may report from worker threads
          std::lock_guard<std::mutex> lock(log_mutex);
          int& prev = last->try_emplace(stage, -1).first->second;
          if (percent <= prev) return;
          prev = percent;
        }
        log(name, stage + " " + std::to_string(percent) + "%");
      };
    return cb;
  };
  auto done = [&](std::size_t i, const MeshJobResult& r) {
    if (r.ok())
      log(jobs[i].name, "done");
    else
      log(jobs[i].name, "FAILED: " + r.summary["error"].value("message", std::string()));
  };
  std::vector<MeshJobResult> results;
  if (mpi) {
    bool root = false;
    const std::vector<std::size_t> order =
        world.rank == 0 ? largest_first(estimate_job_costs(jobs)) : std::vector<std::size_t>{};
    *agreed = true;
    if (mpi_first_failed_rank(true) >= 0) return 0;  // the rank that failed reports it
    results = run_jobs_over_mpi(jobs, order, callbacks, done, &root);
    if (!root) return 0;  // rank 0 reports the batch and its exit code
  } else {
    results = run_jobs_in_processes(jobs, workers, callbacks, done);
  }

  // Exit code: 0 if all succeeded; the failed jobs' code if they all share one; else 1.
  std::size_t failed = 0;
  int code = 0;
  for (const MeshJobResult& r : results) {
    if (r.ok()) continue;
    code = failed++ == 0 ? int(r.code) : (code == int(r.code) ? code : int(ExitCode::failure));
  }

  print_table(out.human(), results);
  for (const MeshJobResult& r : results)
    if (!r.ok())
      out.human() << "job '" << r.summary.value("job", std::string()) << "' failed (exit "
                  << int(r.code) << "): " << r.summary["error"].value("message", std::string()) << "\n";
  out.human() << jobs.size() - failed << " of " << jobs.size() << " jobs succeeded in "
              << fixed(total.seconds(), 2) << " s\n";
  nlohmann::json j = {{"command", "batch"},
                      {"file", o.file},
                      {"workers", workers},
                      {"succeeded", jobs.size() - failed},
                      {"failed", failed},
                      {"exit_code", code},
                      {"seconds", total.seconds()},
                      {"jobs", nlohmann::json::array()}};
  for (const MeshJobResult& r : results) j["jobs"].push_back(r.summary);
  out.emit_json(j);
  if (code != 0)
    print_error(std::to_string(failed) + " of " + std::to_string(jobs.size()) + " jobs failed");
  return code;
}

/// Under mpirun every rank reads the same command line and configuration, so an error before
/// the ranks split the work is usually the same on each (N copies of one message before).
/// The ranks agree on the outcome of their set-up (mpi_first_failed_rank): the lowest rank
/// that failed reports its error and exits with its code; the others exit 0, quietly, so that
/// mpirun's exit code is the error's and no rank's exit ends the job before the report is out
/// (the others exiting with the code first let mpirun kill rank 0 before it wrote: 1 run in
/// ~20 on CI's 2 cores). Without MPI, rank 0 reports and the others exit with the code.
int run_batch(const Options& o) {
  const MpiWorld world = mpi_world_from_environment();
  bool agreed = false;
  try {
    return run_batch_as(o, world, &agreed);
  } catch (const Error& e) {
    if (world.size > 1 && mpi_available() && !agreed) {
      if (mpi_first_failed_rank(false) != world.rank) return 0;
      throw;
    }
    if (world.size > 1 && world.rank != 0) return int(e.code());
    throw;
  }
}

}  // namespace

void add_batch_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("batch", "Run the meshing jobs of a YAML batch file");
  cmd->add_option("file", o->file, "Batch file (.yaml)")->required();
  cmd->add_option("-j,--jobs", o->jobs, "Jobs run at the same time")
      ->check(CLI::Range(1u, 1024u))
      ->capture_default_str();
  cmd->add_option("--out-dir", o->out_dir,
                  "Directory the outputs are written in: relative output paths are resolved against it "
                  "and must stay inside it (default: the batch file's directory)")
      ->check(non_empty_path());
  cmd->add_flag("--allow-outside-out-dir", o->allow_outside,
                "Accept output paths outside --out-dir (absolute, '..', symbolic links leading out)");
  cmd->add_option("--timeout", o->timeout,
                  "Stop a job that sets no timeout after this many seconds; it fails with exit 7 (0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--shard", o->shard,
                  "Run only share i of N of the jobs (0 <= i < N), e.g. one Slurm array task: "
                  "--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT. The shares are balanced by "
                  "estimated size, the same on every task, and together hold each job once");
  cmd->add_option("--only", o->only, "Run only the named jobs (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->delimiter(',');
  cmd->add_option("--max-memory", o->max_memory,
                  "Memory limit of each job that sets no max_memory, e.g. 8G, none (default: the "
                  "machine's memory); a job whose estimate exceeds it fails with exit 7");
  add_output_flags(cmd, o->out);
  cmd->footer(
      "Config errors (exit 3) name the file, line and key, and stop the batch before any job\n"
      "runs. Each job runs in its own process: a job that fails, or crashes, is reported and\n"
      "the others continue. Under `mpirun -np N` (N >= 2) rank 0 hands the jobs, largest\n"
      "first, to the N - 1 other ranks as each becomes free, and reports. Exit code: 0 if every job\n"
      "succeeded; otherwise the failed jobs' code when they all share one, else 1.\n"
      "Schema: tools/app/job_config.h.");
  cmd->callback([o, &run] { run = [o] { return run_batch(*o); }; });
}

}  // namespace kdmesh::cli
