// kdmesh — running meshing jobs in child processes, so that one job cannot take down another.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "tools/app/mesh_job.h"

namespace kdmesh {

/// Runs every job in its own child process (fork), at most `workers` at a time, and returns
/// their results in job order. The child runs run_mesh_job() and hands its summary back
/// through a pipe; its log and progress callbacks write to the inherited stderr.
///
/// Isolation: a child that crashes (a signal such as SIGSEGV or SIGABRT, the kernel's OOM
/// killer, ...) or exits without a result fails its job with ExitCode::failure and a message
/// naming the signal or exit status, and the temporary files it left beside its outputs are
/// removed; the other jobs are unaffected. SIGINT / SIGTERM delivered to this process are
/// forwarded to the running children (which remove their temporaries) before this process
/// dies of the signal.
///
/// Time limits: a job with MeshJob::timeout > 0 still running after that many seconds gets
/// SIGTERM (it removes its temporaries), SIGKILL 5 s later if need be, and fails with
/// ExitCode::resource and a message naming the limit; the other jobs go on.
/// If this process dies, even of SIGKILL, its children get SIGTERM (PR_SET_PDEATHSIG).
///
/// `callbacks(i)` makes the callbacks of job i (called in the child); `done(i, result)` is
/// called in this process as each job finishes, in completion order.
/// Fault injection for tests: KDMESH_INJECT_CRASH=<job> makes that job's child kill itself
/// with SIGSEGV before meshing; <job>@<text> does so at the first log line starting with <text>
/// (e.g. "writing /out/a.xyz", when the job's earlier outputs exist as temporary files).
/// Must be called from a single-threaded process (fork).
std::vector<MeshJobResult> run_jobs_in_processes(
    const std::vector<MeshJob>& jobs, unsigned workers,
    const std::function<MeshJobCallbacks(std::size_t)>& callbacks,
    const std::function<void(std::size_t, const MeshJobResult&)>& done);

}  // namespace kdmesh
