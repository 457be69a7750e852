// core/cpu_count.h: the default thread count follows the CPUs the process may use (its
// affinity mask, its cgroup's CPU quota), not the machine's. Regression
// (CpuCount.AffinityMaskBoundsTheCount): with std::thread::hardware_concurrency(), a job given
// 4 CPUs of a 128-core node started 128 threads.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "core/cpu_count.h"

namespace kdmesh {
namespace {

TEST(CpuCount, AffinityMaskBoundsTheCount) {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  EXPECT_GE(available_cpus(), 1u);
  EXPECT_LE(count_available_cpus(), unsigned(CPU_COUNT(&mask)));
  EXPECT_EQ(available_cpus(), count_available_cpus());  // read once, and nothing moved since
  int first = 0;
  while (!CPU_ISSET(first, &mask)) ++first;
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // a child bound to one CPU counts one
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0) _exit(2);
    _exit(count_available_cpus() == 1 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the child bound to one CPU counted more; 2: it could not bind";
}

TEST(CpuCount, QuotaIsRoundedUpAndNoQuotaIsZero) {
  EXPECT_EQ(detail::quota_cpus("200000", "100000"), 2u);  // docker --cpus 2
  EXPECT_EQ(detail::quota_cpus("150000", "100000"), 2u);  // 1.5 CPUs: two threads
  EXPECT_EQ(detail::quota_cpus("50000", "100000"), 1u);   // half a CPU: one
  EXPECT_EQ(detail::quota_cpus("max", "100000"), 0u);     // cgroup v2: no quota
  EXPECT_EQ(detail::quota_cpus("-1", "100000"), 0u);      // cgroup v1: no quota
  EXPECT_EQ(detail::quota_cpus("", ""), 0u);              // unreadable
  EXPECT_EQ(detail::quota_cpus("100000", "0"), 0u);
}

}  // namespace
}  // namespace kdmesh
