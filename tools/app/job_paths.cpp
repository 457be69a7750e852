// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/job_paths.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/xdmf_writer.h"

namespace kdmesh {

namespace {

void check_uses(const std::vector<PathUse>& uses, const std::string& who) {
  for (const PathUse& u : uses)
    if (u.output) check_output_target(u.path);
  if (const auto clash = find_path_clash(uses))
    throw UsageError(who + describe_path_clash(uses, *clash));
}

}  // namespace

std::vector<JobOutput> job_outputs(const MeshJob& job) {
  std::vector<JobOutput> out;
  for (const JobOutput& o : {JobOutput{"vtu", "vtu output", job.vtu},
                             {"summary", "summary output", job.summary},
                             {"nodes", "nodes output", job.nodes},
                             {"msh", "msh output", job.msh},
                             {"inp", "inp output", job.inp},
                             {"mesh", "MEDIT (mesh) output", job.medit},
                             {"boundary_vtu", "boundary_vtu output", job.boundary_vtu},
                             {"xdmf", "xdmf output", job.xdmf}})
    if (!o.path.empty()) out.push_back(o);
  if (!job.xdmf.empty())  // right after the xdmf output
    out.push_back({"xdmf_h5", "xdmf output's HDF5 file", xdmf_hdf5_path(job.xdmf)});
  if (!job.exodus.empty()) out.push_back({"exodus", "exodus output", job.exodus});
  return out;
}

std::vector<PathUse> job_path_uses(const MeshJob& job) {
  std::vector<PathUse> uses;
  if (job.bodies.empty()) uses.push_back({job.input, false, "input"});
  for (const BodyInput& b : job.bodies) uses.push_back({b.input, false, "input of body '" + b.name + "'"});
  for (const JobOutput& o : job_outputs(job)) uses.push_back({o.path, true, o.label});
  return uses;
}

void check_job_paths(const MeshJob& job) {
  check_uses(job_path_uses(job), "job '" + job.name + "': ");
}

void check_run_paths(const std::string& input, const std::vector<std::pair<std::string, std::string>>& outputs) {
  std::vector<PathUse> uses{{input, false, "input"}};
  for (const auto& [label, path] : outputs)
    if (!path.empty()) uses.push_back({path, true, label});
  check_uses(uses, "");
}

}  // namespace kdmesh
