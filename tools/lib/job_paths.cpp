// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/lib/job_paths.h"

#include "core/atomic_file.h"
#include "core/error.h"

namespace kdmesh {

namespace {

void check_uses(const std::vector<PathUse>& uses, const std::string& who) {
  for (const PathUse& u : uses)
    if (u.output) check_output_target(u.path);
  if (const auto clash = find_path_clash(uses))
    throw UsageError(who + describe_path_clash(uses, *clash));
}

}  // namespace

std::vector<PathUse> job_path_uses(const MeshJob& job) {
  std::vector<PathUse> uses{{job.input, false, "input"}};
  for (const auto& [path, label] : {std::pair<const std::string*, const char*>{&job.vtu, "vtu output"},
                                    {&job.summary, "summary output"},
                                    {&job.nodes, "nodes output"},
                                    {&job.msh, "msh output"},
                                    {&job.inp, "inp output"},
                                    {&job.medit, "MEDIT (mesh) output"},
                                    {&job.boundary_vtu, "boundary_vtu output"}})
    if (!path->empty()) uses.push_back({*path, true, label});
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
