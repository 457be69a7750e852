// kdmesh — a batch's jobs spread over MPI ranks (tools/kdmesh/batch_mpi.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Protocol (MPI_COMM_WORLD, rank 0 the scheduler, every other rank a worker):
//   worker -> 0  kAsk     (no data): ready for a first job
//   0 -> worker  kJob     int: a job index, or -1: no more jobs, stop
//   worker -> 0  kResult  bytes "<exit code>\n<index>\n<summary JSON>": the job's result, and
//                         ready for the next one
// Rank 0 does not mesh: it stays free to answer at once, and a crash of a job's child process
// never reaches it (the worker reports the crash as that job's result).
#include "tools/kdmesh/batch_mpi.h"

#include <cstdlib>
#include <string>

#include <limits>
#include <utility>

#include "core/error.h"
#include "tools/app/job_process.h"

#ifdef KDMESH_WITH_MPI
#define OMPI_SKIP_MPICXX 1  // the C API only: no C++ bindings library to link
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace kdmesh::cli {

namespace {

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  return end && *end == '\0' && x >= 0 && x < (1L << 30) ? int(x) : fallback;
}

#ifdef KDMESH_WITH_MPI
constexpr int kAsk = 1, kJob = 2, kResult = 3;

std::string encode(std::size_t index, const MeshJobResult& r) {
  return std::to_string(int(r.code)) + "\n" + std::to_string(index) + "\n" + r.summary.dump();
}

std::size_t decode(const std::string& text, MeshJobResult& r) {
  const std::size_t a = text.find('\n'), b = a == std::string::npos ? a : text.find('\n', a + 1);
  if (b == std::string::npos) throw Error("MPI batch: a malformed result message");
  r.code = ExitCode(std::stoi(text.substr(0, a)));
  r.summary = nlohmann::json::parse(text.substr(b + 1));
  return std::size_t(std::stoull(text.substr(a + 1, b - a - 1)));
}

void check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw Error(std::string("MPI batch: ") + what + " failed (MPI error " + std::to_string(rc) + ")");
}

std::vector<MeshJobResult> schedule(const std::vector<MeshJob>& jobs, const std::vector<std::size_t>& order, int size,
                                    const std::function<void(std::size_t, const MeshJobResult&)>& done) {
  std::vector<MeshJobResult> results(jobs.size());
  std::size_t next = 0;
  int stopped = 0;
  std::string buffer;
  while (stopped < size - 1) {
    MPI_Status st;
    check(MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &st), "MPI_Probe");
    if (st.MPI_TAG == kResult) {
      int n = 0;
      check(MPI_Get_count(&st, MPI_CHAR, &n), "MPI_Get_count");
      buffer.assign(std::size_t(n), '\0');
      check(MPI_Recv(buffer.data(), n, MPI_CHAR, st.MPI_SOURCE, kResult, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
      MeshJobResult r;
      const std::size_t i = decode(buffer, r);
      if (i >= jobs.size()) throw Error("MPI batch: a result for job " + std::to_string(i) + " of " + std::to_string(jobs.size()));
      results[i] = std::move(r);
      if (done) done(i, results[i]);
    } else {
      check(MPI_Recv(nullptr, 0, MPI_CHAR, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
    }
    const int job = next < order.size() ? int(order[next++]) : -1;
    check(MPI_Send(&job, 1, MPI_INT, st.MPI_SOURCE, kJob, MPI_COMM_WORLD), "MPI_Send");
    if (job < 0) ++stopped;
  }
  return results;
}

void work(const std::vector<MeshJob>& jobs, const std::function<MeshJobCallbacks(std::size_t)>& callbacks) {
  check(MPI_Send(nullptr, 0, MPI_CHAR, 0, kAsk, MPI_COMM_WORLD), "MPI_Send");
  for (;;) {
    int job = -1;
    check(MPI_Recv(&job, 1, MPI_INT, 0, kJob, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
    if (job < 0 || std::size_t(job) >= jobs.size()) return;
    const std::vector<MeshJob> one{jobs[std::size_t(job)]};
    const std::vector<MeshJobResult> r = run_jobs_in_processes(
        one, 1, [&](std::size_t) { return callbacks(std::size_t(job)); }, [](std::size_t, const MeshJobResult&) {});
    const std::string msg = encode(std::size_t(job), r.at(0));
    check(MPI_Send(msg.data(), int(msg.size()), MPI_CHAR, 0, kResult, MPI_COMM_WORLD), "MPI_Send");
  }
}
#endif

}  // namespace

MpiWorld mpi_world_from_environment() {
  MpiWorld w;
  w.size = env_int("OMPI_COMM_WORLD_SIZE", env_int("PMI_SIZE", 1));
  w.rank = env_int("OMPI_COMM_WORLD_RANK", env_int("PMI_RANK", env_int("PMIX_RANK", 0)));
  if (w.size < 1) w.size = 1;
  return w;
}

bool mpi_available() {
#ifdef KDMESH_WITH_MPI
  return true;
#else
  return false;
#endif
}

#ifdef KDMESH_WITH_MPI
namespace {
/// MPI_COMM_WORLD's rank and size, initialising MPI once (both entry points below may).
std::pair<int, int> init_world() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) check(MPI_Init(nullptr, nullptr), "MPI_Init");
  int size = 1, rank = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return {rank, size};
}
}  // namespace
#endif

int mpi_first_failed_rank(bool ok) {
#ifdef KDMESH_WITH_MPI
  const int rank = init_world().first;
  int first = 0;
  const int mine = ok ? std::numeric_limits<int>::max() : rank;
  check(MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  if (first == std::numeric_limits<int>::max()) return -1;
  MPI_Finalize();
  return first;
#else
  (void)ok;
  return -1;
#endif
}

std::vector<MeshJobResult> run_jobs_over_mpi(const std::vector<MeshJob>& jobs, const std::vector<std::size_t>& order,
                                             const std::function<MeshJobCallbacks(std::size_t)>& callbacks,
                                             const std::function<void(std::size_t, const MeshJobResult&)>& done,
                                             bool* root) {
#ifdef KDMESH_WITH_MPI
  const auto [rank, size] = init_world();
  *root = rank == 0;
  std::vector<MeshJobResult> results;
  try {
    if (size < 2) throw UsageError("MPI batch: needs at least 2 ranks (one schedules, the others mesh)");
    if (rank == 0) results = schedule(jobs, order, size, done);
    else work(jobs, callbacks);
  } catch (...) {
    MPI_Abort(MPI_COMM_WORLD, int(ExitCode::failure));  // a rank lost: the others would wait forever
  }
  MPI_Finalize();
  return results;
#else
  (void)jobs, (void)order, (void)callbacks, (void)done, (void)root;
  throw UsageError("this kdmesh was built without MPI (libopenmpi-dev was missing): run the batch "
                   "without mpirun, or split it with --shard i/N");
#endif
}

}  // namespace kdmesh::cli
