// kdmesh CLI — the options of one meshing job and their MeshJob.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/kdmesh/mesh_options.h"

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>

#include "core/error.h"
#include "core/memory_amount.h"
#include "mesher/order/order.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/surface/surface_repair.h"

namespace kdmesh::cli {

MeshJobCallbacks job_callbacks(const Output& out) {
  MeshJobCallbacks cb;
  cb.log = [&out](const std::string& s) { out.stage(s); };
  auto bars = std::make_shared<std::map<std::string, std::function<void(double)>>>();
  auto mutex = std::make_shared<std::mutex>();  // stages may report from worker threads
  cb.progress = [&out, bars, mutex](const std::string& stage, double f) {
    std::lock_guard<std::mutex> lock(*mutex);
    auto it = bars->find(stage);
    if (it == bars->end()) it = bars->emplace(stage, out.progress(stage)).first;
    if (it->second) it->second(f);
  };
  return cb;
}

MeshJob make_mesh_job(const MeshCliOptions& o) {
  MeshJob job;
  job.name = std::filesystem::path(o.input).stem().string();
  job.input = o.input;
  for (const std::string& b : o.bodies) {  // NAME=PATH; the names are checked by mesh_solid
    const std::size_t eq = b.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == b.size())
      throw UsageError("--body '" + b + "': expected NAME=PATH, e.g. --body housing=housing.stl");
    job.bodies.push_back({b.substr(0, eq), b.substr(eq + 1)});
  }
  if (!job.bodies.empty()) {
    if (!o.input.empty()) throw UsageError("give either a surface file or --body NAME=PATH options, not both");
    job.name = "bodies";
    job.input.clear();
    for (const BodyInput& b : job.bodies) job.input += (job.input.empty() ? "" : " + ") + b.input;
  }
  job.scale = o.scale;
  job.sharp_angle = o.sharp_angle;
  job.sizing.max_size = o.size;
  job.sizing.min_size = o.min_size > 0 ? o.min_size : o.size / 1000;
  if (job.sizing.min_size > job.sizing.max_size)
    throw UsageError("--min-size " + std::to_string(o.min_size) + " exceeds --size " + std::to_string(o.size));
  job.sizing.gradation = o.gradation;
  if (o.edge_size > 0 && o.refine_edges <= 0)
    throw UsageError("--edge-size needs --refine-edges ANGLE");
  if (o.refine_edges > 0) {
    SizingZone z;
    z.kind = SizingZone::Kind::sharp_edges;
    z.name = "sharp_edges";
    z.size = o.edge_size > 0 ? o.edge_size : o.size / 4;
    z.angle_deg = o.refine_edges;
    job.sizing.zones.push_back(z);
  }
  job.order.kind = parse_order_kind(o.order);
  job.seed = o.seed;
  job.order.seed = o.seed;
  for (const std::string& c : o.checks) {
    if (c == "tetgen" && !tetgen_available()) throw UsageError(without_tetgen_message("--check tetgen"));
    if (c == "tetgen") job.check_tetgen = true;
    if (c == "delaunay") job.check_delaunay = true;
  }
  if (!o.max_memory.empty()) job.max_memory = parse_memory_amount(o.max_memory, "--max-memory");
  job.repair = parse_surface_repairs(o.repair, "--repair");
  job.improve = !o.no_improve;
  job.curvature_angle = o.curvature_angle;
  job.chordal_deviation = o.chordal_deviation;
  job.auto_creases = !o.no_auto_creases;
  job.thickness_layers = o.thickness_layers;
  job.check.hausdorff_tolerance = o.hausdorff_tolerance;
  job.check.volume_tolerance = o.volume_tolerance;
  job.max_refinements = o.max_refinements;
  job.msh = o.msh;
  job.inp = o.inp;
  job.medit = o.medit;
  job.boundary_vtu = o.boundary_vtu;
  job.xdmf = o.xdmf;
  job.exodus = o.exodus;
  job.element_order = o.element_order;
  job.msh_version = o.msh_version == "2.2" ? 22 : 41;
  job.group_options.patch_groups = job.group_options.curve_groups = o.patch_groups;
  job.vtu = o.output;
  job.summary = o.summary;
  job.nodes = o.nodes;
  return job;
}

void add_mesh_job_options(CLI::App* cmd, MeshCliOptions& o, const MeshCliSpec& spec) {
  CLI::Option* input = cmd->add_option("input", o.input, "Closed surface (.stl, .ply, .obj or .off)");
  CLI::Option* size = cmd->add_option("--size", o.size, "Target edge length far from every zone (h_max)");
  if (spec.input_required) {
    if (!spec.bodies) input->required();  // else input or --body, checked by make_mesh_job
    size->required();
  }
  if (spec.bodies)
    cmd->add_option("--body", o.bodies,
                    "A named solid meshed with the others, NAME=PATH (repeatable; instead of INPUT): "
                    "region k is the k-th body, its volume groups carry the names; bodies must lie "
                    "apart (touching or overlapping ones are refused)")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  size->check(CLI::PositiveNumber);
  cmd->add_option("--refine-edges", o.refine_edges,
                  "Refine along surface edges sharper than ANGLE degrees (a sharp_edges zone)")
      ->check(CLI::Range(0.0, 180.0).description("in (0, 180)") & CLI::PositiveNumber);
  cmd->add_option("--edge-size", o.edge_size, "Size on the --refine-edges zone (default size/4)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--min-size", o.min_size, "Floor of the target size (default size/1000)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gradation", o.gradation, "Size growth per unit distance from a zone")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--sharp-angle", o.sharp_angle,
                  "Feature edges kept in the mesh: dihedral deviation >= this (degrees; 0 = none)")
      ->check(CLI::Range(0.0, 179.999))
      ->capture_default_str();
  cmd->add_option("--curvature-angle", o.curvature_angle,
                  "Size on curved surface parts at most this angle (degrees, as radians) times the "
                  "radius of curvature (0 = off)")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--chordal-deviation", o.chordal_deviation,
                  "Mean depth of boundary faces below the curved surface, in model units (default: "
                  "derived from --volume-tolerance; 0 = off)");
  cmd->add_flag("--no-auto-creases", o.no_auto_creases,
                "Do not keep surface edges bent by less than --sharp-angle as feature edges, even "
                "where a boundary face across them would leave --hausdorff-tolerance");
  cmd->add_option("--thickness-layers", o.thickness_layers,
                  "Walls get at least this many tets across, gaps boundary nodes no farther apart "
                  "than their width (0 = off)")
      ->check(CLI::Range(0.0, 16.0))
      ->capture_default_str();
  cmd->add_option("--hausdorff-tolerance", o.hausdorff_tolerance,
                  "Mesh check: every boundary face within this many local sizes h of the surface")
      ->check(CLI::Range(1e-6, 1.0))
      ->capture_default_str();
  cmd->add_option("--volume-tolerance", o.volume_tolerance,
                  "Mesh check: mesh volume within this fraction of the solid's")
      ->check(CLI::Range(1e-9, 1.0))
      ->capture_default_str();
  cmd->add_option("--max-refinements", o.max_refinements,
                  "Local refinements (size halved where the boundary is not recovered or not "
                  "within tolerance, then meshed again) before giving up; also bounds the (at most 2) "
                  "refinements around isolated tets left below 12 deg")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  cmd->add_option("--scale", o.scale, "Multiply the coordinates by this")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--order", o.order, "Insertion order of the nodes")
      ->check(CLI::IsMember(order_kind_names()))
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "Seed of node placement and the random orders")->capture_default_str();
  cmd->add_option("--check", o.checks,
                  "Also verify the nodes' Delaunay tetrahedralization: tetgen (exact validity + "
                  "TetGen 1.5 + CGAL 5.5) and/or delaunay (exact validity); repeatable")
      ->check(CLI::IsMember({"tetgen", "delaunay"}))
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->delimiter(',');
  cmd->add_option("--max-memory", o.max_memory,
                  "Refuse the job (exit 7) if its estimated peak memory exceeds this, e.g. 8G, "
                  "512M, none (default: the machine's memory)");
  cmd->add_option("--repair", o.repair,
                  "Opt-in safe surface repairs, comma-separated: degenerate (zero-area facets), "
                  "duplicates (same-orientation copies), orientation (flip facets against their "
                  "shell), all; each change is reported");
  if (spec.outputs) {
    cmd->add_option("-o,--output", o.output, "Output mesh (.vtu)")->check(non_empty_path());
    cmd->add_option("--summary", o.summary, "Output summary (.json)")->check(non_empty_path());
    cmd->add_option("--nodes", o.nodes, "Output nodes (.xyz)")->check(non_empty_path());
    cmd->add_option("--msh", o.msh, "Output Gmsh mesh (.msh) with physical groups")->check(non_empty_path());
    cmd->add_option("--inp", o.inp, "Output Abaqus/CalculiX input (.inp) with ELSET/NSET/SURFACE groups")->check(non_empty_path());
    cmd->add_option("--medit", o.medit, "Output MEDIT mesh (.mesh) with references")->check(non_empty_path());
    cmd->add_option("--boundary-vtu", o.boundary_vtu,
                    "Output boundary faces and feature edges (.vtu) with patch/curve ids and a 0/1 "
                    "cell array per group")
        ->check(non_empty_path());
    cmd->add_option("--xdmf", o.xdmf,
                    "Output XDMF (.xdmf, data in the .h5 beside it) for FEniCSx with cell_tags (regions) "
                    "and facet_tags (boundary groups)")
        ->check(non_empty_path());
    cmd->add_option("--exodus", o.exodus,
                    "Output Exodus II (.exo) for MOOSE: an element block per region, a side set per "
                    "surface group, a node set per group")
        ->check(non_empty_path());
    cmd->add_option("--element-order", o.element_order,
                    "1: linear tets; 2: quadratic (C3D10), mid-edge nodes on the surface")
        ->check(CLI::IsMember({1, 2}))
        ->capture_default_str();
    cmd->add_option("--msh-version", o.msh_version, "MSH format version")
        ->check(CLI::IsMember({"4.1", "2.2"}))
        ->capture_default_str();
  }
  cmd->add_flag("--no-improve", o.no_improve,
                "Skip the quality improvement (flips and smoothing): keep the Delaunay tets");
  if (spec.outputs)
    cmd->add_flag("--patch-groups", o.patch_groups,
                  "Name every surface patch and feature curve as a group (patch_<i>, curve_<i>)");
}

}  // namespace kdmesh::cli
