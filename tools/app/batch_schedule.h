// kdmesh — how a batch's jobs are spread: their estimated costs, the largest-first order of
// dynamic scheduling (MPI ranks), and deterministic shards (Slurm array tasks, --shard i/N).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "tools/app/mesh_job.h"

namespace kdmesh {

/// A rough cost of each job, for ordering only (it never changes a job's result): the number
/// of nodes its size would give the bounding box of its surface(s), (extent / size)^3 plus
/// the facet count. A surface that cannot be read costs 0 (the job reports the error itself
/// when it runs). Reads every input once.
std::vector<double> estimate_job_costs(const std::vector<MeshJob>& jobs);

/// Job indices by decreasing cost, ties in job order.
std::vector<std::size_t> largest_first(const std::vector<double>& costs);

/// "i/N" (0 <= i < N, N >= 1) -> {i, N}; UsageError naming `what` otherwise.
struct Shard {
  std::size_t index = 0, count = 1;
};
Shard parse_shard(const std::string& text, const std::string& what);

/// The jobs of shard `s`, in job order: the jobs, largest first, go one by one to the shard
/// with the least cost so far (the lowest index on ties). Deterministic for the same costs:
/// every shard of an array job computes the same split; together the shards hold each job
/// once.
std::vector<std::size_t> shard_jobs(const std::vector<double>& costs, Shard s);

}  // namespace kdmesh
