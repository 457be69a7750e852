// kdmesh — under a limit on processes and threads (a batch system's task limit, ulimit -u),
// the jobs of a parallel step whose threads cannot be started run on the calling thread, with
// the same results. Regression (ThreadLimit.*): parallel_for and the Delaunay kernel's
// workers threw std::system_error out of the pipeline ("internal error: Resource temporarily
// unavailable"), and where one thread had started before another failed, its unjoined
// std::thread ended the process in std::terminate (`kdmesh delaunay --threads 4` under
// `prlimit --nproc=2` aborted).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <grp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <vector>

#include "core/parallel_for.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/mesh_solid.h"
#include "mesher/order/order.h"
#include "tests/support/box_surface.h"
#include "tools/bench/lib/distributions.h"

namespace kdmesh {
namespace {

constexpr int kSkip = 77;

/// Runs `body` in a child process that can start `extra` threads and no more: RLIMIT_NPROC
/// 1 + extra for an unprivileged user (root first becomes an unused one; the limit does not
/// bind root). Returns the child's exit code (body's result; 2 if it threw; kSkip if the limit
/// could not be set up or did not hold), or 128 + the signal that ended it.
int with_thread_limit(unsigned extra, const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid < 0) return kSkip;
  if (pid == 0) {
    // The limit counts every process and thread of the user: a user id of this test alone
    // (ctest runs tests at once), one that no one else uses.
    const uid_t user = 50000 + uid_t(::getpid() % 10000);
    if (::geteuid() == 0 && (::setgroups(0, nullptr) != 0 || ::setgid(user) != 0 || ::setuid(user) != 0))
      ::_exit(kSkip);
    const rlimit limit{1 + extra, 1 + extra};
    if (::setrlimit(RLIMIT_NPROC, &limit) != 0) ::_exit(kSkip);
    {  // the limit must hold: `extra` threads start at once, one more does not
      std::atomic<bool> go{false};
      std::vector<std::thread> held;
      bool over = false;
      try {
        for (unsigned k = 0; k <= extra; ++k) held.emplace_back([&go] { while (!go.load()) std::this_thread::yield(); });
      } catch (const std::system_error&) {
        over = held.size() == extra;
      }
      go = true;
      for (std::thread& t : held) t.join();
      if (!over) ::_exit(kSkip);
    }
    int code = 2;
    try {
      code = body();
    } catch (...) {
    }
    ::_exit(code);  // no exit handlers: they may start threads (LeakSanitizer's)
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

/// body() passes (returns 0) with no thread to start and with one.
void expect_passes_under_thread_limits(const std::function<int()>& body) {
  for (const unsigned extra : {0u, 1u}) {
    const int code = with_thread_limit(extra, body);
    if (code == kSkip) GTEST_SKIP() << "cannot limit threads here (RLIMIT_NPROC)";
    EXPECT_EQ(code, 0) << "exit code of the child that may start " << extra
                       << " thread(s) (2: it threw; 134: std::terminate)";
  }
}

TEST(ThreadLimit, ParallelForAndRunWorkersRunEveryChunkOnTheCallingThread) {
  expect_passes_under_thread_limits([] {
    std::vector<int> hits(100000, 0);
    std::vector<unsigned> by_worker(8, 0);
    parallel_for(hits.size(), [&](std::size_t b, std::size_t e, unsigned w) {
      for (std::size_t i = b; i < e; ++i) ++hits[i];
      by_worker[w] += unsigned(e - b);
    }, 1, 8);
    for (int h : hits)
      if (h != 1) return 10;
    unsigned total = 0;
    for (unsigned n : by_worker) total += n;
    if (total != hits.size()) return 11;
    std::vector<int> ran(5, 0);
    run_workers(5, [&](unsigned w) { ++ran[w]; });
    if (ran != std::vector<int>(5, 1)) return 12;
    // A job's exception still reaches the caller, after every job ran.
    std::fill(ran.begin(), ran.end(), 0);
    try {
      run_workers(5, [&](unsigned w) {
        ++ran[w];
        if (w == 3) throw std::runtime_error("job 3");
      });
      return 13;
    } catch (const std::runtime_error&) {
    }
    return ran == std::vector<int>(5, 1) ? 0 : 14;
  });
}

TEST(ThreadLimit, DelaunayOnFourThreadsGivesTheSameTriangulation) {
  const PointSet pts = generate_points(Distribution::cube, 60000, 3);
  const Ordering order = make_order(pts, OrderOptions{});
  DelaunayOptions o;
  o.threads = 4;
  const DelaunayResult expected = delaunay(pts, order, o);
  ASSERT_GT(expected.stats.parallel_rounds, 0u) << "the run must take the parallel path";
  expect_passes_under_thread_limits([&] {
    const DelaunayResult got = delaunay(pts, make_order(pts, OrderOptions{}), o);
    if (got.stats.parallel_rounds != expected.stats.parallel_rounds) return 10;
    return finite_tets(got.tri) == finite_tets(expected.tri) ? 0 : 11;
  });
}

TEST(ThreadLimit, MeshSolidGivesTheSameMesh) {
  MeshParams p;
  p.name = "box";
  p.sizing.max_size = 0.15;
  p.sizing.min_size = 0.15 / 1000;
  const MeshResult expected = mesh_solid(test::box_surface({0, 0, 0}, {1, 2, 3}), p);
  ASSERT_GT(expected.tet_mesh.num_tets(), 10000u);
  expect_passes_under_thread_limits([&] {
    const MeshResult got = mesh_solid(test::box_surface({0, 0, 0}, {1, 2, 3}), p);
    if (got.tet_mesh.tets != expected.tet_mesh.tets) return 10;
    return got.tet_mesh.points.xyz == expected.tet_mesh.points.xyz ? 0 : 11;
  });
}

}  // namespace
}  // namespace kdmesh
