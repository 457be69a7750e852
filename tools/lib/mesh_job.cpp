// kdmesh — one meshing job: the whole pipeline, its summary, and all-or-nothing outputs.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/lib/mesh_job.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <memory>
#include <new>
#include <numbers>
#include <vector>

#include "core/atomic_file.h"
#include "core/timer.h"
#include "io/boundary_vtu_writer.h"
#include "io/file_io.h"
#include "io/inp_writer.h"
#include "io/medit_writer.h"
#include "io/msh_writer.h"
#include "io/points_io.h"
#include "io/surface_io.h"
#include "io/vtu_writer.h"
#include "mesher/boundary_groups.h"
#include "mesher/delaunay.h"
#include "mesher/fe_assembly.h"
#include "mesher/mesh_check.h"
#include "mesher/mesh_improve.h"
#include "mesher/node_placement.h"
#include "mesher/quality.h"
#include "mesher/resource_estimate.h"
#include "mesher/size_fidelity.h"
#include "mesher/surface_prepare.h"
#include "mesher/surface_query.h"
#include "mesher/surface_repair.h"
#include "mesher/thickness_sizes.h"
#include "mesher/tet_compare.h"
#include "mesher/volume_mesh.h"
#include "sizing/features.h"
#include "tools/lib/delaunay_verify.h"
#include "tools/lib/job_paths.h"
#include "tools/lib/numeric_ranges.h"

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
      << " edges in [0.7, 1.4]\n";
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
          {"mesh_volume", c.mesh_volume},
          {"solid_volume", c.solid_volume},
          {"volume_error", c.volume_error},
          {"failures", c.failures}};
}

nlohmann::json size_fidelity_json(const SizeFidelity& f) {
  return {{"edges", f.edges},
          {"mean_ratio", f.mean_ratio},
          {"fraction_in_range", f.in_range},
          {"range", {0.7, 1.4}},
          {"short_fraction", f.short_fraction},
          {"long_fraction", f.long_fraction},
          {"min_ratio", f.min_ratio},
          {"max_ratio", f.max_ratio}};
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

/// prepare_surface, with a hint in the error when an opt-in repair would fix the defect.
PreparedSurface prepare_with_hint(SurfaceMesh raw, const MeshJob& job, const SurfaceOptions& so) {
  try {
    return prepare_surface(std::move(raw), job.input, so);
  } catch (const SurfaceError& e) {
    const char* repair = nullptr;
    switch (e.defect()) {
      case SurfaceError::Defect::degenerate: repair = job.repair.degenerate ? nullptr : "degenerate"; break;
      case SurfaceError::Defect::duplicates: repair = job.repair.duplicates ? nullptr : "duplicates"; break;
      case SurfaceError::Defect::orientation: repair = job.repair.orientation ? nullptr : "orientation"; break;
      case SurfaceError::Defect::other: break;
    }
    if (!repair) throw;
    throw SurfaceError(std::string(e.what()) + " (the opt-in repair '--repair " + repair + "', or 'repair: [" +
                           repair + "]' in a batch file, fixes this)",
                       e.facets(), e.defect());
  }
}

/// Estimates the job's nodes and peak memory, reports them, and refuses the job (ResourceError)
/// when the estimate exceeds its memory limit — before anything large is allocated.
template <class Log>
void check_memory_estimate(const MeshJob& job, const PreparedSurface& surface, const SurfaceQuery& query,
                           const SizingField& sizing, nlohmann::json& j, const Log& log) {
  Stopwatch clock;
  const double limit = effective_memory_limit(job.max_memory);
  // Beyond twice the limit the exact excess does not matter: stop integrating there.
  const double cap = limit > 0 ? std::max(1e6, 2 * limit / kBytesPerNode) : 2e9;
  const ResourceEstimate e = estimate_resources(surface, query, sizing, cap);
  j["seconds"]["estimate"] = clock.seconds();
  char count[32];  // whole numbers while exact; beyond 2^53 (or non-finite) in scientific form
  if (e.nodes < 9e15) std::snprintf(count, sizeof count, "%.0f", e.nodes);
  else std::snprintf(count, sizeof count, "%.3g", e.nodes);
  const std::string nodes = (e.capped ? "more than " : "~") + std::string(count);
  const std::string limit_text = limit > 0 ? format_bytes(limit) : std::string("none");
  j["estimate"] = {{"nodes", e.nodes}, {"surface_nodes", e.surface_nodes}, {"interior_nodes", e.interior_nodes},
                   {"peak_bytes", e.peak_bytes}, {"capped", e.capped}, {"limit_bytes", limit}};
  log("estimate: " + nodes + " nodes, " + (e.capped ? "more than " : "~") + format_bytes(e.peak_bytes) +
      " peak memory (limit " + limit_text + ")");
  if (limit > 0 && e.peak_bytes > limit)
    throw ResourceError("job '" + job.name + "': needs an estimated " + (e.capped ? "more than " : "") +
                        format_bytes(e.peak_bytes) + " of memory (" + nodes + " nodes) but the limit is " +
                        limit_text + (job.max_memory > 0 ? " (max_memory / --max-memory)" : " (the machine's memory)") +
                        "; use a larger size, or raise the limit with --max-memory (none = no limit)");
}

/// The automatic terms of a job, derived from its tolerances and its surface.
struct AutoTerms {
  double feature_angle = 0;      ///< degrees: the sharp angle, lowered to the crease angle
  double chordal_deviation = 0;  ///< model units (0 = off)
};

AutoTerms automatic_terms(const MeshJob& job, const PreparedSurface& surface) {
  AutoTerms t;
  t.feature_angle = job.sharp_angle;
  if (job.auto_creases && job.sharp_angle > 0) {
    // A boundary face of length L across a crease of deviation a lies (L/4) sin a from the
    // surface at the crease. With L up to 1.3 h and the mesher's own margin (0.8 x the
    // tolerance), creases bent by more than asin(4 x 0.8 x tol / 1.3) must be kept by nodes.
    const double s = std::min(1.0, 4 * 0.8 * job.check.hausdorff_tolerance / 1.3);
    t.feature_angle = std::min(job.sharp_angle, std::asin(s) * 180 / std::numbers::pi);
  }
  if (job.chordal_deviation > 0) {
    t.chordal_deviation = job.chordal_deviation;
  } else if (job.chordal_deviation < 0) {
    // Half the volume tolerance spread as a mean depth over the whole surface area.
    double area = 0;
    const SurfaceMesh& sm = surface.mesh;
    for (std::size_t f = 0; f < sm.num_tris(); ++f) {
      const double *a = sm.points.p(sm.tri(f)[0]), *b = sm.points.p(sm.tri(f)[1]), *c = sm.points.p(sm.tri(f)[2]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      area += std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / 2;
    }
    if (area > 0 && std::isfinite(area))
      t.chordal_deviation = 0.5 * job.check.volume_tolerance * std::fabs(surface.volume) / area;
  }
  return t;
}

/// The volume mesh of a job, improved and checked, with the sizing field it was made with.
struct Meshed {
  SizingField sizing;
  VolumeMesh mesh;
  MeshCheck check;
};

/// Adds a point zone of half the local size at each place of `where` (3 coordinates each)
/// whose local size is still above min_size; returns how many it added.
std::size_t refine_at(const std::vector<double>& where, const SizingField& sizing, SizingOptions& o) {
  std::size_t added = 0;
  const double floor = sizing.min_size();
  for (std::size_t k = 0; k + 2 < where.size(); k += 3) {
    const double h = sizing(&where[k]);
    if (!(h > floor * (1 + 1e-9))) continue;
    SizingZone z;
    z.kind = SizingZone::Kind::point;
    z.name = "refinement";
    z.size = std::max(floor, h / 2);
    z.coords.assign(where.begin() + std::ptrdiff_t(k), where.begin() + std::ptrdiff_t(k) + 3);
    o.zones.push_back(std::move(z));
    ++added;
  }
  return added;
}

std::string first_place(const std::vector<double>& where) {
  std::ostringstream m;
  m.precision(9);
  if (where.size() >= 3) m << " (e.g. at (" << where[0] << ", " << where[1] << ", " << where[2] << "))";
  return m.str();
}

/// Sizing field, nodes, volume mesh, improvement and mesh check; where the boundary cannot be
/// recovered or the check finds the boundary too far from the surface, the size is halved
/// around those places and everything from the sizing field on is done again (at most
/// job.max_refinements times). Throws what the last attempt threw, or CheckError is left to
/// the caller through Meshed::check.
template <class Notice>
Meshed mesh_with_refinement(const MeshJob& job, const PreparedSurface& surface, const SurfaceQuery& query,
                            const FeatureEdges& features, SizingOptions options, const MeshJobCallbacks& cb,
                            nlohmann::json& j, const Notice& notice) {
  auto log = [&](const std::string& s) {
    if (cb.log) cb.log(s);
  };
  auto progress = [&](const std::string& stage, double f) {
    if (cb.progress) cb.progress(stage, f);
  };
  nlohmann::json& sec = j["seconds"];
  nlohmann::json& counts = j["counts"];
  auto add_seconds = [&](const char* key, double t) { sec[key] = sec.value(key, 0.0) + t; };
  const std::size_t user_zones = options.zones.size();
  for (int attempt = 0;; ++attempt) {
    Stopwatch clock;
    log("sizing field (" + std::to_string(user_zones) + " zones" +
        (attempt ? ", " + std::to_string(options.zones.size() - user_zones) + " refinement points" : std::string()) + ")");
    Meshed m;
    m.sizing = build_sizing_field(surface.mesh, options);
    add_seconds("sizing", clock.seconds());
    if (attempt == 0) {
      const SizingAutoStats& a = m.sizing.auto_stats();
      j["automatic_sizing"] = {{"curvature_angle", options.curvature_angle_deg},
                               {"chordal_deviation", options.chordal_deviation},
                               {"feature_angle", options.feature_angle_deg},
                               {"curvature_places", a.curvature_places},
                               {"min_curvature_size", a.min_curvature_size},
                               {"min_radius", a.min_radius}};
      if (a.curvature_places > 0) {
        std::ostringstream n;
        n.precision(4);
        n << "curvature: the size is reduced to as little as " << a.min_curvature_size << " along "
          << a.curvature_places << " place(s) of the curved surface (radius of curvature down to " << a.min_radius
          << "; curvature_angle " << options.curvature_angle_deg << " deg, chordal deviation "
          << options.chordal_deviation << ")";
        notice(n.str());
      }
    }
    check_memory_estimate(job, surface, query, m.sizing, j, log);

    clock.reset();
    log("placing nodes");
    PlacementOptions po;
    po.seed = job.seed;
    po.progress = progress;
    NodeSet nodes = place_nodes(surface, query, features, m.sizing, po);
    add_seconds("place", clock.seconds());
    counts["placed_nodes"] = nodes.points.size();

    clock.reset();
    log("meshing " + std::to_string(nodes.points.size()) + " nodes (order " +
        std::string(order_kind_name(job.order.kind)) + ")");
    VolumeMeshOptions vo;
    vo.order = job.order;
    vo.order.seed = job.seed;
    vo.progress = progress;
    vo.hausdorff_tolerance = job.check.hausdorff_tolerance;
    try {
      m.mesh = mesh_volume(surface, query, m.sizing, std::move(nodes), vo);
    } catch (const BoundaryRecoveryError& e) {
      add_seconds("mesh", clock.seconds());
      const std::size_t added = attempt < job.max_refinements ? refine_at(e.where(), m.sizing, options) : 0;
      if (added == 0)
        throw GeometryError(std::string(e.what()) +
                            (attempt < job.max_refinements
                                 ? "; the size there is already min_size " + std::to_string(m.sizing.min_size())
                                 : "; after " + std::to_string(attempt) + " local refinement(s)"));
      notice("boundary recovery did not converge at " + std::to_string(e.where().size() / 3) + " place(s)" +
             first_place(e.where()) + ": size halved around " + std::to_string(added) +
             " of them, meshing again (refinement " + std::to_string(attempt + 1) + ")");
      continue;
    }
    add_seconds("mesh", clock.seconds());
    const VolumeMeshStats& ms = m.mesh.stats;
    sec["mesh_stages"] = {{"order", ms.order_seconds},
                          {"delaunay", ms.delaunay_seconds},
                          // the first, full tetrahedralization alone (the "Delaunay time")
                          {"first_delaunay", ms.delaunay.seconds},
                          {"classify", ms.classify_seconds},
                          {"recover", ms.recover_seconds}};
    // What the written mesh holds: counted again after the quality pass, whose splits add
    // interior nodes and whose cap removals change the boundary (the summary had said 274382
    // nodes for a gear box deck of 274384).
    auto count_mesh = [&] {
      std::array<std::size_t, 4> by_kind{};
      for (NodeKind k : m.mesh.nodes.kind) ++by_kind[std::size_t(k) & 3];
      counts["nodes"] = m.mesh.nodes.points.size();
      counts["nodes_by_kind"] = {{"corner", by_kind[0]}, {"edge", by_kind[1]},
                                 {"surface", by_kind[2]}, {"interior", by_kind[3]}};
      counts["tets"] = m.mesh.num_tets();
      counts["boundary_faces"] = m.mesh.boundary.size() / 3;
    };
    count_mesh();
    counts["steiner_points"] = ms.steiner_points;
    counts["dropped_nodes"] = ms.dropped_nodes;
    counts["buried_nodes"] = ms.buried_nodes;
    counts["steiner_rounds"] = ms.rounds;
    counts["refinements"] = attempt;

    if (job.improve) {
      clock.reset();
      log("improving " + std::to_string(m.mesh.num_tets()) + " tets");
      ImproveOptions io;
      io.measure_stages = false;  // the quality block measures the result
      io.progress = progress;
      io.hausdorff_tolerance = job.check.hausdorff_tolerance;
      io.feature_angle = options.feature_angle_deg;
      const ImproveStats imp = improve_mesh(m.mesh, surface, query, m.sizing, io);
      add_seconds("improve", clock.seconds());
      count_mesh();
      j["improve"] = {{"edge_removals", imp.edge_removals}, {"face_removals", imp.face_removals},
                      {"relaxed", imp.relaxed}, {"smoothed", imp.smoothed},
                      {"boundary_changes", imp.boundary_changes}, {"caps_removed", imp.caps_removed}, {"splits", imp.splits},
                      {"boundary_splits", imp.boundary_splits}, {"insertions", imp.insertions},
                      {"rounds", imp.rounds},
                      {"boundary_flips", imp.boundary_flips}};
    }

    clock.reset();
    log("checking the mesh");
    m.check = check_volume_mesh(m.mesh, surface, query, m.sizing, job.check);
    add_seconds("mesh_check", clock.seconds());
    if (m.check.ok() || !m.check.only_sizing_failures()) return m;
    const std::size_t added = attempt < job.max_refinements ? refine_at(m.check.refine_at, m.sizing, options) : 0;
    if (added == 0) return m;  // the caller reports the failed check
    notice("the mesh check found the boundary too far from the surface at " +
           std::to_string(m.check.refine_at.size() / 3) + " place(s)" + first_place(m.check.refine_at) +
           (m.check.volume_off ? " (volume off by " + std::to_string(100 * m.check.volume_error) + "%)" : std::string()) +
           ": size halved around " + std::to_string(added) + " of them, meshing again (refinement " +
           std::to_string(attempt + 1) + ")");
  }
}

/// The pipeline; fills `j` as it goes, so a failure still reports what was measured. Throws.
void run_pipeline(const MeshJob& job, const MeshJobCallbacks& cb, nlohmann::json& j) {
  auto log = [&](const std::string& s) {
    if (cb.log) cb.log(s);
  };
  if (!(job.scale > 0)) throw UsageError("job '" + job.name + "': scale must be > 0");
  if (!(job.sizing.max_size > 0)) throw UsageError("job '" + job.name + "': size must be > 0");
  check_option_ranges(job);  // before any work: numbers in the range the pipeline computes in
  check_job_paths(job);      // outputs may be written, none is an input or shared
  Stopwatch total, clock;
  nlohmann::json& sec = j["seconds"];
  nlohmann::json& counts = j["counts"];
  j["notices"] = nlohmann::json::array();

  log("reading " + job.input);
  SurfaceMesh raw = read_surface(job.input);
  sec["read"] = clock.seconds();
  // Coordinates after scaling, sizes against the model; the default min_size is raised to
  // the smallest the mesher resolves.
  const ModelRanges ranges = check_model_ranges(job, raw);

  clock.reset();
  log("preparing the surface (" + std::to_string(raw.points.size()) + " points, " +
      std::to_string(raw.num_tris()) + " facets)");
  auto notice = [&](const std::string& n) {
    j["notices"].push_back(n);
    log("notice: " + n);
  };
  if (!ranges.note.empty()) notice(ranges.note);
  SurfaceOptions so;
  so.scale = job.scale;
  so.notice = notice;
  if (job.repair.any()) {
    SurfaceRepairReport rep;
    raw = repair_surface(std::move(raw), job.repair, rep);
    j["repairs"] = {{"removed_collapsed", rep.removed_collapsed}, {"split_caps", rep.split_caps},
                    {"removed_duplicates", rep.removed_duplicates}, {"flipped", rep.flipped}};
    for (const std::string& n : rep.notes) so.notice(n);
    if (rep.changed()) so.notice("facet ids in later messages refer to the repaired surface");
  }
  const PreparedSurface surface = prepare_with_hint(std::move(raw), job, so);
  sec["prepare"] = clock.seconds();
  counts["surface_points"] = surface.mesh.points.size();
  counts["surface_facets"] = surface.mesh.num_tris();
  counts["shells"] = surface.shell_body.size();
  counts["bodies"] = surface.num_bodies;
  j["solid_volume"] = surface.volume;
  j["bbox"] = {{"min", {surface.bbox_min[0], surface.bbox_min[1], surface.bbox_min[2]}},
               {"max", {surface.bbox_max[0], surface.bbox_max[1], surface.bbox_max[2]}}};

  clock.reset();
  const AutoTerms terms = automatic_terms(job, surface);
  {
    std::ostringstream m;
    m << "sharp features (angle " << terms.feature_angle << " deg)";
    log(m.str());
  }
  const FeatureEdges features = detect_sharp_edges(surface.mesh, terms.feature_angle);
  sec["features"] = clock.seconds();
  counts["feature_edges"] = features.num_edges();
  counts["feature_corners"] = features.corners.size();
  if (terms.feature_angle < job.sharp_angle) {
    const std::size_t sharp = detect_sharp_edges(surface.mesh, job.sharp_angle).num_edges();
    if (features.num_edges() > sharp) {
      std::ostringstream m;
      m << "creases: " << features.num_edges() - sharp << " surface edge(s) bent by "
        << terms.feature_angle << " to " << job.sharp_angle
        << " deg are kept as feature edges (a boundary face across them would lie farther than "
        << job.check.hausdorff_tolerance << " h from the surface); auto_creases: false turns this off";
      notice(m.str());
    }
  }

  clock.reset();
  const SurfaceQuery query(surface.mesh);
  sec["query"] = clock.seconds();

  SizingOptions sizing_options = job.sizing;
  sizing_options.max_size = ranges.size;
  sizing_options.min_size = ranges.min_size;
  sizing_options.curvature_angle_deg = job.curvature_angle;
  sizing_options.chordal_deviation = terms.chordal_deviation;
  sizing_options.feature_angle_deg = terms.feature_angle;
  if (job.thickness_layers > 0) {
    clock.reset();
    ThicknessOptions to;
    to.layers = job.thickness_layers;
    to.max_size = ranges.size;
    const ThicknessStats ts = add_thickness_sizes(surface, query, to, sizing_options.derived);
    sec["thickness"] = clock.seconds();
    j["thickness"] = {{"walls", ts.walls}, {"gaps", ts.gaps}, {"min_wall", ts.min_wall}, {"min_gap", ts.min_gap}};
    if (ts.walls + ts.gaps > 0) {
      std::ostringstream n;
      n.precision(4);
      n << "thickness: the size is reduced";
      if (ts.walls) n << " across " << ts.walls << " facet(s) of walls thinner than " << job.thickness_layers
                      << " x size (thinnest " << ts.min_wall << ")";
      if (ts.gaps) n << (ts.walls ? " and" : "") << " along " << ts.gaps << " facet(s) facing a gap narrower than the size (narrowest "
                     << ts.min_gap << ")";
      n << "; thickness_layers: 0 turns this off";
      notice(n.str());
    }
  }
  Meshed m = mesh_with_refinement(job, surface, query, features, sizing_options, cb, j, notice);
  VolumeMesh& mesh = m.mesh;
  const MeshCheck& check = m.check;
  const SizingField& sizing = m.sizing;
  j["mesh_check"] = mesh_check_json(check);

  bool delaunay_ok = true;
  if (job.check_tetgen || job.check_delaunay) {
    clock.reset();
    log("checking the Delaunay tetrahedralization of the nodes");
    DelaunayVerification v = check_nodes_delaunay(job, mesh.nodes.points, log);
    delaunay_ok = v.pass;
    j["delaunay_check"] = std::move(v.json);
    j["delaunay_check"]["report"] = v.report;
    sec["delaunay_check"] = clock.seconds();
  }

  clock.reset();
  TetMesh tm = to_tet_mesh(mesh);
  const QualitySummary q = summarize_quality(tm);
  j["quality"] = quality_json(q);
  j["size_fidelity"] = size_fidelity_json(measure_size_fidelity(mesh.nodes.points, mesh.tets, sizing));
  sec["quality"] = clock.seconds();

  if (!check.ok()) {
    std::string what = "job '" + job.name + "': the mesh failed its validity check:";
    for (const std::string& f : check.failures) what += "\n  " + f;
    throw CheckError(what + "\nno output was written");
  }
  if (!delaunay_ok)
    throw CheckError("job '" + job.name +
                     "': the Delaunay tetrahedralization of the nodes failed its check:\n" +
                     j["delaunay_check"]["report"].get<std::string>() + "no output was written");

  // Solver formats: boundary patches and feature curves, named groups, optional quadratic nodes.
  FeMesh fe;
  const bool solver_formats =
      !job.msh.empty() || !job.inp.empty() || !job.medit.empty() || !job.boundary_vtu.empty();
  if (solver_formats) {
    clock.reset();
    log("boundary groups");
    const SurfacePatches patches = segment_surface(surface.mesh, features);
    const BoundaryGroups bg = assign_boundary(mesh, surface.mesh, patches, query);
    counts["patches"] = patches.num_patches;
    counts["curves"] = patches.num_curves();
    counts["mesh_feature_edges"] = bg.edge_curve.size();
    j["boundary"] = {{"pass", bg.ok()}, {"topological_faces", bg.topological_faces},
                     {"geometric_faces", bg.geometric_faces}, {"verified_faces", bg.verified_faces},
                     {"ambiguous_faces", bg.ambiguous_faces.size()},
                     {"missing_curve_edges", bg.missing_curve_edges}, {"stray_patch_edges", bg.stray_patch_edges},
                     {"empty_patches", bg.empty_patches}, {"empty_curves", bg.empty_curves},
                     {"problems", bg.problems}};
    if (!bg.ok()) {
      std::string what = "job '" + job.name + "': the boundary groups are not certain:";
      for (const std::string& p : bg.problems) what += "\n  " + p;
      throw CheckError(what + "\nno output was written");
    }
    fe = make_fe_mesh(mesh, bg, make_groups(job.groups, surface.mesh, patches, job.sizing.zones,
                                            surface.num_bodies, job.group_options));
    j["groups"] = groups_json(fe);
    if (job.element_order == 2) {
      log("quadratic elements");
      const QuadraticStats qs = make_quadratic(fe, surface.mesh, query, patches);
      j["quadratic"] = {{"mid_nodes", qs.mid_nodes}, {"moved", qs.moved_mid_nodes},
                        {"reduced_elements", qs.reduced_elements},
                        {"straightened_elements", qs.straightened_elements},
                        {"far_projections", qs.far_projections}, {"min_jacobian_ratio", qs.min_jacobian_ratio}};
    }
    sec["groups"] = clock.seconds();
  }

  // Outputs: every file to a temporary first; all renamed into place (all or nothing) only once
  // all are written. Errors name the user's path, not the temporary one.
  clock.reset();
  AtomicFileSet files;
  nlohmann::json outputs = nlohmann::json::object();
  auto output = [&](const std::string& path, const char* key, const auto& write) {
    if (path.empty()) return;
    log("writing " + path);
    make_parent_dirs(path);
    const std::string temp = files.add(path);
    outputs[key] = path;
    try {
      write(temp);
    } catch (const OutputError& e) {
      if (e.file() != temp) throw;
      throw OutputError(path, e.reason());
    }
  };
  output(job.vtu, "vtu", [&](const std::string& t) { write_vtu(tm, t); });
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
  if (!job.summary.empty()) outputs["summary"] = job.summary;
  j["outputs"] = outputs;
  j["status"] = "ok";
  sec["write"] = clock.seconds();
  sec["total"] = total.seconds();
  output(job.summary, "summary", [&](const std::string& t) { write_text(t, j.dump(2) + "\n", job.summary); });
  files.commit();
}

}  // namespace

std::vector<std::string> output_paths(const MeshJob& job) {
  std::vector<std::string> paths;
  for (const std::string* p : {&job.vtu, &job.summary, &job.nodes, &job.msh, &job.inp, &job.medit, &job.boundary_vtu})
    if (!p->empty()) paths.push_back(*p);
  return paths;
}

MeshJobResult run_mesh_job(const MeshJob& job, const MeshJobCallbacks& callbacks) {
  MeshJobResult r;
  Stopwatch total;
  try {
    r.summary = {{"job", job.name}, {"input", job.input}, {"status", "running"}};
    if (!job.origin.empty()) r.summary["defined_at"] = job.origin;
    r.summary["options"] = {{"scale", job.scale},
                            {"size", job.sizing.max_size},
                            {"min_size", job.sizing.min_size},
                            {"gradation", job.sizing.gradation},
                            {"zones", job.sizing.zones.size()},
                            {"sharp_angle", job.sharp_angle},
                            {"order", std::string(order_kind_name(job.order.kind))},
                            {"seed", job.seed},
                            {"check_tetgen", job.check_tetgen},
                            {"check_delaunay", job.check_delaunay}};
    run_pipeline(job, callbacks, r.summary);
    return r;
  } catch (const Error& e) {
    r.code = e.code();
    r.summary["error"] = {{"type", dynamic_cast<const SurfaceError*>(&e) ? "surface" : error_type_name(e.code())},
                          {"exit_code", int(e.code())},
                          {"message", e.what()}};
  } catch (const std::bad_alloc&) {
    r.code = ExitCode::failure;
    r.summary["error"] = {{"type", "internal"}, {"exit_code", 1}, {"message", "out of memory"}};
  } catch (const std::exception& e) {
    r.code = ExitCode::failure;
    r.summary["error"] = {{"type", "internal"}, {"exit_code", 1},
                          {"message", std::string("internal error: ") + e.what()}};
  } catch (...) {
    r.code = ExitCode::failure;
    r.summary["error"] = {{"type", "internal"}, {"exit_code", 1}, {"message", "unknown internal error"}};
  }
  // Failed: the summary says so; no output exists (AtomicFile removed every temporary).
  try {
    r.summary["status"] = "failed";
    r.summary.erase("outputs");
    r.summary["seconds"]["total"] = total.seconds();
  } catch (...) {
  }
  return r;
}

}  // namespace kdmesh
