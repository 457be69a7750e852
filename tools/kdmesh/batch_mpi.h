// kdmesh — a batch's jobs spread over the ranks of an MPI run (`mpirun -np N kdmesh batch`).
// The MPI types stay in batch_mpi.cpp; a build without MPI (KDMESH_WITH_MPI off) refuses.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "tools/app/mesh_job.h"

namespace kdmesh::cli {

/// Ranks of the run this process belongs to, read from the launcher's environment
/// (OMPI_COMM_WORLD_SIZE / _RANK, PMI_SIZE / _RANK, PMIX_RANK) without initialising MPI:
/// {1, 0} when not started by mpirun.
struct MpiWorld {
  int size = 1, rank = 0;
};
MpiWorld mpi_world_from_environment();

/// Whether this kdmesh was built with MPI.
bool mpi_available();

/// Before the ranks split the work: every rank's set-up outcome (true: it can go on),
/// agreed over MPI_COMM_WORLD. Returns -1 when every rank can go on, else the lowest rank
/// whose set-up failed, after finalising MPI. Initialises MPI (run_jobs_over_mpi then does
/// not again). A build without MPI returns -1.
int mpi_first_failed_rank(bool ok);
/// Runs the jobs over MPI_COMM_WORLD (size >= 2): rank 0 hands out job indices in `order`
/// (largest estimated first), each to whichever worker rank asks next, and collects the
/// results; ranks 1.. run one job at a time, each in a child process
/// (run_jobs_in_processes: a job that fails or crashes fails alone). Returns, on rank 0, the
/// results in job order and sets *root; on the other ranks an empty vector. `done(i, r)` is
/// called on rank 0 as results arrive. MPI is initialised here (unless mpi_first_failed_rank
/// did) and finalised. Throws
/// UsageError if built without MPI.
std::vector<MeshJobResult> run_jobs_over_mpi(const std::vector<MeshJob>& jobs, const std::vector<std::size_t>& order,
                                             const std::function<MeshJobCallbacks(std::size_t)>& callbacks,
                                             const std::function<void(std::size_t, const MeshJobResult&)>& done,
                                             bool* root);

}  // namespace kdmesh::cli
