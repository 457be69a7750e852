// kdmesh — the CPUs this process may use (affinity mask, cgroup CPU quota).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "core/cpu_count.h"

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <string>
#include <thread>

namespace kdmesh {

namespace {

/// The quota of the cgroup directory `dir`: cgroup v2's cpu.max ("<quota> <period>"), or v1's
/// cpu.cfs_quota_us and cpu.cfs_period_us; 0 for none or unreadable.
unsigned quota_of(const std::string& dir, bool v2) {
  std::string quota, period;
  if (v2) {
    std::ifstream(dir + "/cpu.max") >> quota >> period;
  } else {
    std::ifstream(dir + "/cpu.cfs_quota_us") >> quota;
    std::ifstream(dir + "/cpu.cfs_period_us") >> period;
  }
  return detail::quota_cpus(quota, period);
}

/// The least CPU quota over this process's cgroup and its ancestors (v2, or v1's cpu
/// controller); 0 for none.
unsigned cgroup_quota() {
  std::ifstream f("/proc/self/cgroup");
  unsigned least = 0;
  for (std::string line; std::getline(f, line);) {  // "<id>:<controllers>:<path>"
    const std::size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    std::string path = line.substr(b + 1), root;
    if (controllers.empty()) {
      root = "/sys/fs/cgroup";  // v2
    } else if (("," + controllers + ",").find(",cpu,") != std::string::npos) {
      root = "/sys/fs/cgroup/" + controllers;  // v1: "cpu" or "cpu,cpuacct"
    } else {
      continue;
    }
    if (path.empty() || path[0] != '/') continue;
    for (;;) {  // the cgroup, then each ancestor up to the root
      const unsigned q = quota_of(root + (path == "/" ? std::string() : path), controllers.empty());
      if (q && (!least || q < least)) least = q;
      if (path == "/") break;
      const std::size_t cut = path.find_last_of('/');
      path = cut == 0 ? "/" : path.substr(0, cut);
    }
  }
  return least;
}

}  // namespace

unsigned detail::quota_cpus(const std::string& quota, const std::string& period) {
  try {
    const double q = std::stod(quota), p = std::stod(period);
    return q > 0 && p > 0 ? unsigned(std::max(1.0, std::ceil(q / p))) : 0;
  } catch (const std::exception&) {  // "max", or nothing read
    return 0;
  }
}

unsigned count_available_cpus() {
  unsigned n = std::max(1u, std::thread::hardware_concurrency());
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) n = unsigned(std::max(1, CPU_COUNT(&set)));
  if (const unsigned q = cgroup_quota()) n = std::min(n, q);
  return n;
}

unsigned available_cpus() {
  static const unsigned n = count_available_cpus();
  return n;
}

}  // namespace kdmesh
