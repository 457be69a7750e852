// kdmesh — how many CPUs this process may use: its default thread count.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

namespace kdmesh {

/// The CPUs this process may run on, read once per process (count_available_cpus). Every
/// default thread count uses it.
unsigned available_cpus();

/// The CPUs of this process's affinity mask (sched_getaffinity: taskset, a batch system's
/// cpuset), at most its cgroup's CPU quota rounded up (the least over its cgroup and its
/// ancestors; v2 cpu.max or v1 cpu.cfs_quota_us: docker --cpus, systemd's CPUQuota), at least
/// 1. std::thread::hardware_concurrency() counts the machine's online CPUs: on a 128-core node
/// that gives a job four, it made kdmesh start 128 threads on four CPUs.
unsigned count_available_cpus();

namespace detail {
/// A CPU quota in CPUs, rounded up (at least 1), from a quota and a period as written in
/// cgroup files; 0 for no quota ("max", -1) or text that is not a number.
unsigned quota_cpus(const std::string& quota, const std::string& period);
}  // namespace detail

}  // namespace kdmesh
