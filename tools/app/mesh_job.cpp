// kdmesh — one meshing job: the whole pipeline, its summary, and all-or-nothing outputs.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/mesh_job.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <map>
#include <memory>
#include <exception>
#include <new>
#include <vector>

#include "core/atomic_file.h"
#include "core/timer.h"
#include "io/boundary_vtu_writer.h"
#include "io/file_io.h"
#include "io/inp_writer.h"
#include "io/medit_writer.h"
#include "io/msh_writer.h"
#include "io/exodus_writer.h"
#include "io/xdmf_writer.h"
#include "io/points_io.h"
#include "io/surface_io.h"
#include "io/vtu_writer.h"
#include "mesher/fe/boundary_groups.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/mesh_solid.h"
#include "mesher/tet_quality.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/reference/tet_compare.h"
#include "tools/app/delaunay_verify.h"
#include "tools/app/job_paths.h"

namespace kdmesh {

std::string format_job_report(const nlohmann::json& j) {
  std::ostringstream s;
  s << std::setprecision(4);
  auto num = [&](const nlohmann::json& o, const char* k) -> double {
    return o.contains(k) && o[k].is_number() ? o[k].get<double>() : 0.0;
  };
  auto cnt = [&](const nlohmann::json& o, const char* k) -> std::uint64_t {
    return o.contains(k) && o[k].is_number() ? o[k].get<std::uint64_t>() : 0;
  };
  s << "job " << j.value("job", std::string()) << ": " << j.value("status", std::string()) << "\n";
  if (j.contains("counts")) {
    const nlohmann::json& c = j["counts"];
    if (c.contains("surface_facets"))
      s << "  surface       " << cnt(c, "surface_points") << " points, " << cnt(c, "surface_facets")
        << " facets, " << cnt(c, "bodies") << (cnt(c, "bodies") == 1 ? " body, " : " bodies, ") << cnt(c, "feature_edges")
        << " feature edges\n";
    if (c.contains("nodes_by_kind")) {
      const nlohmann::json& k = c["nodes_by_kind"];
      s << "  nodes         " << cnt(c, "nodes") << " (corner " << cnt(k, "corner") << ", edge "
        << cnt(k, "edge") << ", surface " << cnt(k, "surface") << ", interior "
        << cnt(k, "interior") << "), Steiner " << cnt(c, "steiner_points") << ", dropped "
        << cnt(c, "dropped_nodes") << "\n";
      s << "  tets          " << cnt(c, "tets") << ", boundary faces " << cnt(c, "boundary_faces")
        << "\n";
    }
  }
  if (j.contains("quality")) {
    const nlohmann::json& q = j["quality"];
    s << "  quality       dihedral " << num(q, "min_dihedral") << " .. " << num(q, "max_dihedral")
      << " deg, radius ratio mean " << num(q, "mean_radius_ratio") << ", min "
      << num(q, "min_radius_ratio") << "\n";
  }
  if (j.contains("size_fidelity")) {
    const nlohmann::json& f = j["size_fidelity"];
    s << "  size          mean edge/target " << num(f, "mean_ratio") << ", "
      << 100 * num(f, "fraction_in_range") << "% of " << cnt(f, "edges")
      << " edges in [0.7, 1.4]";
    if (cnt(f, "away_edges") > 0)
      s << "; away from refinement " << num(f, "away_mean_ratio") << " of the size asked ("
        << cnt(f, "away_edges") << " edges)";
    s << "\n";
  }
  if (j.contains("delaunay_check"))
    s << "  delaunay      " << (j["delaunay_check"].value("pass", false) ? "ok" : "FAIL") << "\n";
  if (j.contains("mesh_check")) {
    const nlohmann::json& m = j["mesh_check"];
    s << "  mesh check    " << (m.value("pass", false) ? "ok" : "FAIL") << " (volume error "
      << num(m, "volume_error") << ", max Hausdorff " << num(m, "max_hausdorff") << " h)\n";
  }
  if (j.contains("seconds")) {
    s << "  time          ";
    bool first = true;
    for (const char* k : {"read", "prepare", "features", "sizing", "estimate", "place", "mesh", "improve",
                          "delaunay_check", "mesh_check", "quality", "write", "total"})
      if (j["seconds"].contains(k)) {
        s << (first ? "" : ", ") << k << " " << std::fixed << std::setprecision(3)
          << num(j["seconds"], k) << std::defaultfloat << std::setprecision(4);
        first = false;
      }
    s << " s\n";
  }
  if (j.contains("outputs") && !j["outputs"].empty()) {
    s << "  wrote        ";
    for (const auto& [k, v] : j["outputs"].items()) s << " " << v.get<std::string>();
    s << "\n";
  }
  if (j.contains("error"))
    s << "  error         " << j["error"].value("type", std::string()) << " (exit "
      << j["error"].value("exit_code", 1) << "): " << j["error"].value("message", std::string())
      << "\n";
  return s.str();
}

std::string error_type_name(ExitCode code) {
  switch (code) {
    case ExitCode::ok: return "none";
    case ExitCode::usage: return "usage";
    case ExitCode::input: return "input";
    case ExitCode::geometry: return "geometry";
    case ExitCode::check: return "check";
    case ExitCode::output: return "output";
    case ExitCode::resource: return "resource";
    case ExitCode::cancelled: return "cancelled";
    case ExitCode::failure: break;
  }
  return "internal";
}

namespace {

nlohmann::json histogram_json(const Histogram& h) {
  return {{"lo", h.lo}, {"hi", h.hi}, {"counts", h.counts}};
}

}  // namespace

nlohmann::json quality_json(const QualitySummary& q) {
  return {{"tets", q.tets},
          {"inverted", q.inverted},
          {"min_dihedral", q.min_dihedral},
          {"max_dihedral", q.max_dihedral},
          {"mean_radius_ratio", q.mean_radius_ratio},
          {"min_radius_ratio", q.min_radius_ratio},
          {"max_radius_edge", q.max_radius_edge},
          {"mean_volume_length", q.mean_volume_length},
          {"min_volume_length", q.min_volume_length},
          {"min_dihedral_hist", histogram_json(q.min_dihedral_hist)},
          {"radius_ratio_hist", histogram_json(q.radius_ratio_hist)}};
}

nlohmann::json size_fidelity_json(const SizeFidelity& f) {
  return {{"edges", f.edges},
          {"mean_ratio", f.mean_ratio},
          {"fraction_in_range", f.in_range},
          {"range", {0.7, 1.4}},
          {"short_fraction", f.short_fraction},
          {"long_fraction", f.long_fraction},
          {"min_ratio", f.min_ratio},
          {"max_ratio", f.max_ratio},
          {"away_edges", f.away_edges},
          {"away_mean_ratio", f.away_mean_ratio}};
}

namespace {

nlohmann::json mesh_check_json(const MeshCheck& c) {
  return {{"pass", c.ok()},
          {"tets", c.tets},
          {"boundary_faces", c.boundary_faces},
          {"nonpositive_tets", c.nonpositive_tets},
          {"flat_tets", c.flat_tets},
          {"outside_tets", c.outside_tets},
          {"offsurface_vertices", c.offsurface_vertices},
          {"offsurface_faces", c.offsurface_faces},
          {"max_hausdorff", c.max_hausdorff},
          {"open_edges", c.open_edges},
          {"nonmanifold_vertices", c.nonmanifold_vertices},
          {"interface_faces", c.interface_faces},
          {"straddling_tets", c.straddling_tets},
          {"offinterface_vertices", c.offinterface_vertices},
          {"offinterface_faces", c.offinterface_faces},
          {"max_interface_hausdorff", c.max_interface_hausdorff},
          {"mesh_volume", c.mesh_volume},
          {"solid_volume", c.solid_volume},
          {"volume_error", c.volume_error},
          {"failures", c.failures}};
}


/// The summary's groups: name, dim, how many entities each lists and how many elements of its
/// dimension (tets, boundary faces, feature-edge segments) those entities have.
nlohmann::json groups_json(const FeMesh& fe) {
  nlohmann::json groups = nlohmann::json::array();
  for (const FeGroup& g : fe.groups) {
    std::vector<std::uint32_t> ids = g.entities;
    std::sort(ids.begin(), ids.end());
    const std::vector<std::uint32_t>& of =
        g.dim == 3 ? fe.tet_entity : g.dim == 2 ? fe.face_entity : fe.edge_entity;
    const std::size_t elements = std::size_t(std::count_if(of.begin(), of.end(), [&](std::uint32_t e) {
      return std::binary_search(ids.begin(), ids.end(), e);
    }));
    groups.push_back(
        {{"name", g.name}, {"dim", g.dim}, {"entities", g.entities.size()}, {"elements", elements}});
  }
  return groups;
}

/// The Delaunay tetrahedralization of the final nodes, verified as `kdmesh delaunay --check`
/// does (validity; with `references` also TetGen 1.5 and CGAL 5.5).
DelaunayVerification check_nodes_delaunay(const MeshJob& job, const PointSet& pts,
                                          const std::function<void(const std::string&)>& log) {
  const DelaunayResult r = delaunay(pts, make_order(pts, job.order));
  std::vector<std::uint32_t> tets = finite_tets(r.tri);
  const std::vector<std::uint32_t> canon = canonical_point_ids(pts);
  for (auto& x : tets) x = canon[x];
  DelaunayVerifyOptions o;
  o.references = job.check_tetgen;
  o.seed = job.seed;
  o.stage = log;
  return verify_delaunay(pts, r.tri, tets, o);
}

/// Writes `text` to `path` (no atomicity here: the caller passes a temporary path); errors
/// name `target`, the path the user asked for.
void write_text(const std::string& path, const std::string& text, const std::string& target) {
  FileWriter f(path, target);
  f.write(text.data(), text.size());
  f.close();
}

void make_parent_dirs(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec) throw OutputError(path, "cannot create directory '" + parent.string() + "': " + ec.message());
}

/// The summary's "improve" block.
nlohmann::json improve_json(const ImproveStats& imp) {
  return {{"edge_removals", imp.edge_removals}, {"face_removals", imp.face_removals},
          {"relaxed", imp.relaxed}, {"smoothed", imp.smoothed},
          {"boundary_changes", imp.boundary_changes}, {"caps_removed", imp.caps_removed}, {"splits", imp.splits},
          {"boundary_splits", imp.boundary_splits}, {"insertions", imp.insertions},
          {"rounds", imp.rounds}, {"feature_slides", imp.feature_slides},
          {"boundary_flips", imp.boundary_flips}, {"below_target", imp.below_target}};
}

/// The summary's "counts" block: the figures of the stages reached.
nlohmann::json counts_json(const MeshReport& r) {
  const MeshReport::Counts& c = r.counts;
  nlohmann::json j = nlohmann::json::object();
  if (r.has_surface) {
    j["surface_points"] = c.surface_points;
    j["surface_facets"] = c.surface_facets;
    j["shells"] = c.shells;
    j["bodies"] = c.bodies;
    if (c.interface_facets) j["interface_facets"] = c.interface_facets;
  }
  if (r.has_features) {
    j["feature_edges"] = c.feature_edges;
    j["feature_corners"] = c.feature_corners;
  }
  if (r.has_estimate && c.placed_nodes) j["placed_nodes"] = c.placed_nodes;
  if (r.has_mesh) {
    j["nodes"] = c.nodes;
    j["nodes_by_kind"] = {{"corner", c.nodes_by_kind[0]}, {"edge", c.nodes_by_kind[1]},
                          {"surface", c.nodes_by_kind[2]}, {"interior", c.nodes_by_kind[3]}};
    j["tets"] = c.tets;
    j["boundary_faces"] = c.boundary_faces;
    j["steiner_points"] = c.steiner_points;
    j["dropped_nodes"] = c.dropped_nodes;
    j["buried_nodes"] = c.buried_nodes;
    if (c.interface_facets > 0) j["interface_slivers"] = c.interface_slivers;
    j["steiner_rounds"] = c.steiner_rounds;
    j["refinements"] = c.refinements;
  }
  if (r.has_groups || r.boundary) {
    j["patches"] = c.patches;
    j["curves"] = c.curves;
    j["mesh_feature_edges"] = c.mesh_feature_edges;
  }
  return j;
}

/// Reads the surface, runs the front door, checks the nodes' Delaunay tetrahedralization when
/// asked, and writes the outputs; fills `j` as it goes, so a failure still reports what was
/// measured. Throws.
MeshResult run_pipeline(const MeshJob& job, const MeshJobCallbacks& cb, nlohmann::json& j,
                        const SurfaceMesh* in_memory) {
  auto log = [&](const std::string& s) {
    if (cb.log) cb.log(s);
  };
  MeshParams params = job;
  params.fe_groups = job.fe_groups || has_solver_outputs(job);
  check_mesh_params(params);  // usage errors before the file is read
  // before any work, not after minutes of meshing
  if (job.check_tetgen && !tetgen_available())
    throw UsageError("job '" + job.name + "': " + without_tetgen_message("check tetgen"));
  check_job_paths(job);         // outputs may be written, none is an input or shared
  Stopwatch total, clock;
  j["notices"] = nlohmann::json::array();

  SurfaceMesh raw;
  std::vector<NamedSurface> bodies;
  if (in_memory) {
    raw = *in_memory;
  } else if (job.bodies.empty()) {
    log("reading " + job.input);
    raw = read_surface(job.input);
  } else {
    for (const BodyInput& b : job.bodies) {
      log("reading " + b.input + " (body " + b.name + ")");
      bodies.push_back({b.name, b.input, read_surface(b.input)});
    }
  }
  const double read_seconds = clock.seconds();
  MeshReport report;
  MeshResult result;
  try {
    result = bodies.empty() ? mesh_solid(std::move(raw), params, cb, &report)
                            : mesh_solid(std::move(bodies), params, cb, &report);
  } catch (...) {
    report.seconds["read"] = read_seconds;
    add_report_json(report, nullptr, j);
    throw;
  }
  report.seconds["read"] = read_seconds;
  const VolumeMesh& mesh = result.mesh;

  if (job.check_tetgen || job.check_delaunay) {
    clock.reset();
    log("checking the Delaunay tetrahedralization of the nodes");
    DelaunayVerification v = check_nodes_delaunay(job, mesh.nodes.points, log);
    report.seconds["delaunay_check"] = clock.seconds();
    j["delaunay_check"] = std::move(v.json);
    j["delaunay_check"]["report"] = v.report;
    if (!v.pass) {
      add_report_json(report, nullptr, j);
      throw CheckError("job '" + job.name +
                       "': the Delaunay tetrahedralization of the nodes failed its check:\n" +
                       j["delaunay_check"]["report"].get<std::string>() + "no output was written");
    }
  }
  add_report_json(report, params.fe_groups ? &result.fe : nullptr, j);
  nlohmann::json& sec = j["seconds"];
  const FeMesh& fe = result.fe;

  // Outputs: every file to a temporary first; all renamed into place (all or nothing) only once
  // all are written. Errors name the user's path, not the temporary one.
  clock.reset();
  AtomicFileSet files;
  nlohmann::json outputs = nlohmann::json::object();
  std::map<std::string, std::string> user_path;  // temporary -> the user's path
  auto add_file = [&](const std::string& path, const char* key) {
    make_parent_dirs(path);
    const std::string temp = files.add(path);
    outputs[key] = path;
    user_path[temp] = path;
    return temp;
  };
  auto output = [&](const std::string& path, const char* key, const auto& write) {
    if (path.empty()) return;
    log("writing " + path);
    const std::string temp = add_file(path, key);
    try {
      write(temp);
    } catch (const OutputError& e) {
      const auto it = user_path.find(e.file());
      if (it == user_path.end()) throw;
      throw OutputError(it->second, e.reason());
    }
  };
  output(job.vtu, "vtu", [&](const std::string& t) { write_vtu(result.tet_mesh, t); });
  output(job.nodes, "nodes", [&](const std::string& t) { write_xyz(mesh.nodes.points, t); });
  output(job.msh, "msh", [&](const std::string& t) {
    MshOptions mo;
    mo.version = job.msh_version;
    write_msh(fe, t, mo);
  });
  output(job.inp, "inp", [&](const std::string& t) {
    InpOptions io;
    io.heading = "kdmesh job " + job.name + " (" + job.input + ")";
    write_inp(fe, t, io);
  });
  output(job.medit, "medit", [&](const std::string& t) { write_medit(fe, t); });
  output(job.boundary_vtu, "boundary_vtu", [&](const std::string& t) { write_boundary_vtu(fe, t); });
  output(job.xdmf, "xdmf", [&](const std::string& t) {
    const std::string h5 = xdmf_hdf5_path(job.xdmf);
    write_xdmf_files(fe, t, add_file(h5, "xdmf_h5"), std::filesystem::path(h5).filename().string());
  });
  output(job.exodus, "exodus", [&](const std::string& t) { write_exodus(fe, t); });
  if (!job.summary.empty()) outputs["summary"] = job.summary;
  j["outputs"] = outputs;
  j["status"] = "ok";
  sec["write"] = clock.seconds();
  sec["total"] = total.seconds();
  output(job.summary, "summary", [&](const std::string& t) { write_text(t, j.dump(2) + "\n", job.summary); });
  files.commit();
  return result;
}

}  // namespace

std::vector<std::string> output_paths(const MeshJob& job) {
  std::vector<std::string> paths;
  for (const JobOutput& o : job_outputs(job)) paths.push_back(o.path);
  return paths;
}

bool has_solver_outputs(const MeshJob& job) {
  return !job.msh.empty() || !job.inp.empty() || !job.medit.empty() || !job.boundary_vtu.empty() ||
         !job.xdmf.empty() || !job.exodus.empty();
}

void add_report_json(const MeshReport& r, const FeMesh* fe, nlohmann::json& j) {
  j["counts"] = counts_json(r);
  nlohmann::json& sec = j["seconds"];
  for (const auto& [k, v] : r.seconds) sec[k] = v;
  if (!r.mesh_stages.empty()) {
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [k, v] : r.mesh_stages) stages[k] = v;
    sec["mesh_stages"] = stages;
  }
  if (!r.interface_stages.empty()) {
    nlohmann::json stages = nlohmann::json::object();
    double sum = 0;
    for (const auto& [k, v] : r.interface_stages) stages[k] = v, sum += v;
    stages["total"] = sum;
    sec["interface_stages"] = stages;
  }
  nlohmann::json notices = nlohmann::json::array();
  for (const std::string& n : r.notices) notices.push_back(n);
  j["notices"] = notices;
  if (r.has_surface) {
    j["solid_volume"] = r.solid_volume;
    j["bbox"] = {{"min", r.bbox_min}, {"max", r.bbox_max}};
  }
  if (!r.bodies.empty()) {
    nlohmann::json bodies = nlohmann::json::array();
    for (std::size_t k = 0; k < r.bodies.size(); ++k) {
      const MeshReport::Body& b = r.bodies[k];
      bodies.push_back({{"name", b.name}, {"input", b.input}, {"region", k}, {"solid_volume", b.solid_volume}});
      if (r.has_check)
        bodies.back().update({{"mesh_volume", b.mesh_volume}, {"volume_error", b.volume_error}, {"tets", b.tets}});
      if (r.has_quality) bodies.back().update({{"min_dihedral", b.min_dihedral}, {"max_dihedral", b.max_dihedral}});
    }
    j["bodies"] = bodies;
  }
  if (r.repairs)
    j["repairs"] = {{"removed_collapsed", r.repairs->removed_collapsed}, {"split_caps", r.repairs->split_caps},
                    {"removed_duplicates", r.repairs->removed_duplicates}, {"flipped", r.repairs->flipped}};
  if (r.has_auto_sizing)
    j["automatic_sizing"] = {{"curvature_angle", r.curvature_angle},
                             {"chordal_deviation", r.chordal_deviation},
                             {"feature_angle", r.feature_angle},
                             {"curvature_places", r.auto_sizing.curvature_places},
                             {"min_curvature_size", r.auto_sizing.min_curvature_size},
                             {"min_radius", r.auto_sizing.min_radius}};
  if (r.thickness)
    j["thickness"] = {{"walls", r.thickness->walls}, {"gaps", r.thickness->gaps},
                      {"min_wall", r.thickness->min_wall}, {"min_gap", r.thickness->min_gap}};
  if (r.has_estimate) {
    const ResourceEstimate& e = r.estimate;
    j["estimate"] = {{"nodes", e.nodes}, {"surface_nodes", e.surface_nodes}, {"interior_nodes", e.interior_nodes},
                     {"peak_bytes", e.peak_bytes}, {"capped", e.capped}, {"limit_bytes", r.memory_limit}};
  }
  if (r.improve) j["improve"] = improve_json(*r.improve);
  if (r.has_check) j["mesh_check"] = mesh_check_json(r.check);
  if (r.has_quality) {
    j["quality"] = quality_json(r.quality);
    j["size_fidelity"] = size_fidelity_json(r.size_fidelity);
  }
  if (r.boundary) {
    const BoundaryGroupsSummary& b = *r.boundary;
    j["boundary"] = {{"pass", b.pass}, {"topological_faces", b.topological_faces},
                     {"geometric_faces", b.geometric_faces}, {"verified_faces", b.verified_faces},
                     {"ambiguous_faces", b.ambiguous_faces},
                     {"missing_curve_edges", b.missing_curve_edges}, {"stray_patch_edges", b.stray_patch_edges},
                     {"empty_patches", b.empty_patches}, {"empty_curves", b.empty_curves},
                     {"problems", b.problems}};
  }
  if (fe && r.has_groups) j["groups"] = groups_json(*fe);
  if (r.quadratic) {
    const QuadraticStats& qs = *r.quadratic;
    j["quadratic"] = {{"mid_nodes", qs.mid_nodes}, {"moved", qs.moved_mid_nodes},
                      {"reduced_elements", qs.reduced_elements},
                      {"straightened_elements", qs.straightened_elements},
                      {"far_projections", qs.far_projections}, {"min_jacobian_ratio", qs.min_jacobian_ratio}};
  }
}

MeshResult run_job(const MeshJob& job, const MeshJobCallbacks& callbacks, nlohmann::json& summary,
                   const SurfaceMesh* surface) {
  summary = {{"job", job.name}, {"input", job.input}, {"status", "running"}};
  if (!job.origin.empty()) summary["defined_at"] = job.origin;
  summary["options"] = {{"scale", job.scale},
                        {"size", job.sizing.max_size},
                        {"min_size", job.sizing.min_size},
                        {"gradation", job.sizing.gradation},
                        {"zones", job.sizing.zones.size()},
                        {"sharp_angle", job.sharp_angle},
                        {"order", std::string(order_kind_name(job.order.kind))},
                        {"seed", job.seed},
                        {"check_tetgen", job.check_tetgen},
                        {"check_delaunay", job.check_delaunay}};
  return run_pipeline(job, callbacks, summary, surface);
}

ExitCode record_failure(nlohmann::json& summary, std::exception_ptr error, double seconds) {
  ExitCode code = ExitCode::failure;
  nlohmann::json e;
  try {
    std::rethrow_exception(error);
  } catch (const Error& err) {
    code = err.code();
    e = {{"type", dynamic_cast<const SurfaceError*>(&err) ? "surface" : error_type_name(err.code())},
         {"exit_code", int(err.code())},
         {"message", err.what()}};
  } catch (const std::bad_alloc&) {
    e = {{"type", "internal"}, {"exit_code", 1}, {"message", "out of memory"}};
  } catch (const std::exception& err) {
    e = {{"type", "internal"}, {"exit_code", 1}, {"message", std::string("internal error: ") + err.what()}};
  } catch (...) {
    e = {{"type", "internal"}, {"exit_code", 1}, {"message", "unknown internal error"}};
  }
  // Failed: the summary says so; no output exists (AtomicFile removed every temporary).
  try {
    summary["error"] = std::move(e);
    summary["status"] = "failed";
    summary.erase("outputs");
    summary["seconds"]["total"] = seconds;
  } catch (...) {
  }
  return code;
}

MeshJobResult run_mesh_job(const MeshJob& job, const MeshJobCallbacks& callbacks) {
  MeshJobResult r;
  Stopwatch total;
  try {
    run_job(job, callbacks, r.summary);
    return r;
  } catch (...) {
    r.code = record_failure(r.summary, std::current_exception(), total.seconds());
  }
  return r;
}

}  // namespace kdmesh
