// kdmesh — the front door: the whole pipeline in memory (mesher/mesh_solid.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/mesh_solid.h"

#include <algorithm>
#include <atomic>
#include <array>
#include <cmath>
#include <cstdio>
#include <future>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "core/memory_amount.h"
#include "core/timer.h"
#include "mesher/fe/body_groups.h"
#include "mesher/placement/node_placement.h"
#include "mesher/numeric_ranges.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_bodies.h"
#include "mesher/surface/surface_cells.h"
#include "mesher/surface/surface_query.h"
#include "sizing/features.h"

namespace kdmesh {

namespace {

/// The job's messages, progress and cancellation, and the report it fills as it goes.
class Job {
 public:
  Job(const MeshParams& p, const MeshCallbacks& cb, MeshReport& r)
      : params(p), report(r), cb_(cb), thread_(std::this_thread::get_id()) {}

  /// A stage starts: the message goes to the log; a cancellation stops the job here.
  void log(const std::string& s) const {
    poll();
    if (cb_.log) cb_.log(s);
  }
  void notice(const std::string& n) const {
    report.notices.push_back(n);
    if (cb_.log) cb_.log("notice: " + n);
  }
  /// The progress callback for the stages; a cancellation is raised on the calling thread only
  /// (stages may report from worker threads, where an exception would end the process).
  std::function<void(const std::string&, double)> progress() const {
    if (!cb_.progress && !cb_.cancel) return {};
    return [this](const std::string& stage, double f) {
      if (cb_.progress) cb_.progress(stage, f);
      if (std::this_thread::get_id() == thread_) poll();
    };
  }
  void add_seconds(const char* key, double t) const { report.seconds[key] += t; }

  const MeshParams& params;
  MeshReport& report;

 private:
  void poll() const {
    if (cb_.cancel && cb_.cancel()) throw CancelledError("job '" + params.name + "': cancelled");
  }
  const MeshCallbacks& cb_;
  std::thread::id thread_;
};

/// prepare_surface, with a hint in the error when an opt-in repair would fix the defect.
PreparedSurface prepare_with_hint(SurfaceMesh raw, const std::string& input, const MeshParams& params,
                                  const SurfaceOptions& so) {
  try {
    return prepare_surface(std::move(raw), input, so);
  } catch (const SurfaceError& e) {
    const char* repair = nullptr;
    switch (e.defect()) {
      case SurfaceError::Defect::degenerate: repair = params.repair.degenerate ? nullptr : "degenerate"; break;
      case SurfaceError::Defect::duplicates: repair = params.repair.duplicates ? nullptr : "duplicates"; break;
      case SurfaceError::Defect::orientation: repair = params.repair.orientation ? nullptr : "orientation"; break;
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
void check_memory_estimate(const Job& job, const PreparedSurface& surface, const SurfaceQuery& query,
                           const SizingField& sizing) {
  Stopwatch clock;
  const MeshParams& params = job.params;
  const double limit = effective_memory_limit(params.max_memory);
  // Beyond twice the limit the exact excess does not matter: stop integrating there.
  const double cap = limit > 0 ? std::max(1e6, 2 * limit / kBytesPerNode) : 2e9;
  const ResourceEstimate e = estimate_resources({surface, query, sizing}, cap);
  job.report.seconds["estimate"] = clock.seconds();  // the last attempt's
  char count[32];  // whole numbers while exact; beyond 2^53 (or non-finite) in scientific form
  if (e.nodes < 9e15) std::snprintf(count, sizeof count, "%.0f", e.nodes);
  else std::snprintf(count, sizeof count, "%.3g", e.nodes);
  const std::string nodes = (e.capped ? "more than " : "~") + std::string(count);
  const std::string limit_text = limit > 0 ? format_bytes(limit) : std::string("none");
  job.report.estimate = e;
  job.report.memory_limit = limit;
  job.report.has_estimate = true;
  job.log("estimate: " + nodes + " nodes, " + (e.capped ? "more than " : "~") + format_bytes(e.peak_bytes) +
          " peak memory (limit " + limit_text + ")");
  if (limit > 0 && e.peak_bytes > limit)
    throw ResourceError("job '" + params.name + "': needs an estimated " + (e.capped ? "more than " : "") +
                        format_bytes(e.peak_bytes) + " of memory (" + nodes + " nodes) but the limit is " +
                        limit_text + (params.max_memory > 0 ? " (max_memory / --max-memory)" : " (the machine's memory)") +
                        "; use a larger size, or raise the limit with --max-memory (none = no limit)");
}

/// The automatic terms of a job, derived from its tolerances and its surface.
struct AutoTerms {
  double feature_angle = 0;      ///< degrees: the sharp angle, lowered to the crease angle
  double chordal_deviation = 0;  ///< model units (0 = off)
};

AutoTerms automatic_terms(const MeshParams& params, const PreparedSurface& surface) {
  AutoTerms t;
  t.feature_angle = params.sharp_angle;
  if (params.auto_creases && params.sharp_angle > 0) {
    // A boundary face of length L across a crease of deviation a lies (L/4) sin a from the
    // surface at the crease. With L up to 1.3 h and the mesher's own margin (0.8 x the
    // tolerance), creases bent by more than asin(4 x 0.8 x tol / 1.3) must be kept by nodes.
    const double s = std::min(1.0, 4 * 0.8 * params.check.hausdorff_tolerance / 1.3);
    t.feature_angle = std::min(params.sharp_angle, std::asin(s) * 180 / std::numbers::pi);
  }
  if (params.chordal_deviation > 0) {
    t.chordal_deviation = params.chordal_deviation;
  } else if (params.chordal_deviation < 0) {
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
      t.chordal_deviation = 0.5 * params.check.volume_tolerance * std::fabs(surface.volume) / area;
  }
  return t;
}

/// The volume mesh of a job, improved and checked, with the sizing field it was made with.
struct Meshed {
  SizingField sizing;
  VolumeMesh mesh;
  MeshCheck check;
};

/// Quality refinement: when the quality pass leaves a few tets below its target angle (isolated
/// places, not whole sharp edges of the input: at most kQualityRefinementPlaces tets), and the
/// worst is below the input's own smallest edge angle (smallest_edge_angle: no mesh does better
/// than that), the size is halved around them and the job meshed again, at most
/// kQualityRefinements times within max_refinements; the mesh with the better worst tet is
/// kept. (triceratops.ply at diag/20: one tet at 11.89 deg on an input facet with a 156 deg
/// angle between three feature edges, which no local operation of the pass improved; 12.69 deg
/// after one refinement.)
constexpr std::size_t kQualityRefinementPlaces = 32;
constexpr int kQualityRefinements = 2;

std::string format_deg(double deg) {
  std::ostringstream m;
  m.precision(4);
  m << deg << " deg";
  return m.str();
}

/// The angle whose sine is s, in degrees (tet_sine's scale: the min dihedral equivalent).
double sine_deg(double s) { return std::asin(std::clamp(s, -1.0, 1.0)) * 180 / std::numbers::pi; }
std::string format_sine_deg(double s) { return format_deg(sine_deg(s)); }

/// Whether the quality pass's result a is better than b: a worst tet better by more than
/// rounding (1e-6 in sine), or as bad and fewer tets below the target.
bool better_quality(const ImproveStats& a, const ImproveStats& b) {
  constexpr double kSame = 1e-6;
  if (a.worst_sine > b.worst_sine + kSame) return true;
  return a.worst_sine >= b.worst_sine - kSame && a.below_target < b.below_target;
}

/// A checked mesh kept while a quality refinement runs, with the report's figures that
/// describe it (the refinement overwrites them).
struct QualityKept {
  Meshed m;
  MeshReport::Counts counts;
  std::map<std::string, double> mesh_stages;
  ImproveStats improve;
  /// Puts the figures back, says why, and returns the kept mesh.
  Meshed restore(const Job& job, const std::string& why) {
    job.report.counts = counts;
    job.report.mesh_stages = mesh_stages;
    job.report.improve = improve;
    job.notice("quality refinement: the mesh made again is not kept (" + why + "); the earlier mesh (worst tet " +
               format_sine_deg(improve.worst_sine) + ") is");
    return std::move(m);
  }
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

void count_mesh(const VolumeMesh& mesh, MeshReport::Counts& counts) {
  counts.nodes_by_kind = {};
  for (NodeKind k : mesh.nodes.kind) ++counts.nodes_by_kind[std::size_t(k) & 3];
  counts.nodes = mesh.nodes.points.size();
  counts.tets = mesh.num_tets();
  counts.boundary_faces = mesh.boundary.size() / 3;
}

/// The notice of the curvature term, when it shrank the size anywhere.
void announce_curvature(const Job& job, const SizingOptions& options, const SizingField& sizing) {
  const SizingAutoStats& a = sizing.auto_stats();
  job.report.curvature_angle = options.curvature_angle_deg;
  job.report.chordal_deviation = options.chordal_deviation;
  job.report.feature_angle = options.feature_angle_deg;
  job.report.auto_sizing = a;
  job.report.has_auto_sizing = true;
  if (a.curvature_places == 0) return;
  std::ostringstream n;
  n.precision(4);
  n << "curvature: the size is reduced to as little as " << a.min_curvature_size << " along "
    << a.curvature_places << " place(s) of the curved surface (radius of curvature down to " << a.min_radius
    << "; curvature_angle " << options.curvature_angle_deg << " deg, chordal deviation "
    << options.chordal_deviation << ")";
  job.notice(n.str());
}

/// Sizing field, nodes, volume mesh, improvement and mesh check; where the boundary cannot be
/// recovered or the check finds the boundary too far from the surface, the size is halved
/// around those places and everything from the sizing field on is done again (at most
/// max_refinements times). Throws what the last attempt threw; a failed check is left to the
/// caller through Meshed::check.
Meshed mesh_with_refinement(const Job& job, const PreparedSurface& surface, const SurfaceQuery& query,
                            const RegionQuery* regions, const FeatureEdges& features, SizingOptions options) {
  const MeshParams& params = job.params;
  MeshReport& report = job.report;
  const std::size_t user_zones = options.zones.size();
  std::optional<QualityKept> kept;  // the best checked mesh while quality refinements run
  int quality_tries = 0;
  const double input_angle = smallest_edge_angle(surface.mesh);
  for (int attempt = 0;; ++attempt) {
    Stopwatch clock;
    job.log("sizing field (" + std::to_string(user_zones) + " zones" +
            (attempt ? ", " + std::to_string(options.zones.size() - user_zones) + " refinement points" : std::string()) + ")");
    Meshed m;
    m.sizing = build_sizing_field(surface.mesh, options);
    job.add_seconds("sizing", clock.seconds());
    if (attempt == 0) announce_curvature(job, options, m.sizing);
    check_memory_estimate(job, surface, query, m.sizing);

    clock.reset();
    job.log("placing nodes");
    PlacementOptions po;
    po.seed = params.seed;
    po.interface_feature_angle = options.feature_angle_deg;
    po.progress = job.progress();
    PlacementStats ps;
    NodeSet nodes = place_nodes({surface, query, m.sizing, regions}, features, po, &ps);
    if (regions) report.interface_stages["place"] += ps.interface_seconds;
    job.add_seconds("place", clock.seconds());
    report.counts.placed_nodes = nodes.points.size();

    clock.reset();
    job.log("meshing " + std::to_string(nodes.points.size()) + " nodes (order " +
            std::string(order_kind_name(params.order.kind)) + ")");
    VolumeMeshOptions vo;
    vo.order = params.order;
    vo.order.seed = params.seed;
    vo.progress = job.progress();
    vo.hausdorff_tolerance = params.check.hausdorff_tolerance;
    try {
      m.mesh = mesh_volume({surface, query, m.sizing, regions}, std::move(nodes), vo);
    } catch (const BoundaryRecoveryError& e) {
      job.add_seconds("mesh", clock.seconds());
      if (kept) return kept->restore(job, "the boundary was not recovered (" + std::string(e.what()) + ")");
      const std::size_t added = attempt < params.max_refinements ? refine_at(e.where(), m.sizing, options) : 0;
      if (added == 0)
        throw GeometryError(std::string(e.what()) +
                            (attempt < params.max_refinements
                                 ? "; the size there is already min_size " + std::to_string(m.sizing.min_size())
                                 : "; after " + std::to_string(attempt) + " local refinement(s)"));
      job.notice("boundary recovery did not converge at " + std::to_string(e.where().size() / 3) + " place(s)" +
                 first_place(e.where()) + ": size halved around " + std::to_string(added) +
                 " of them, meshing again (refinement " + std::to_string(attempt + 1) + ")");
      continue;
    }
    job.add_seconds("mesh", clock.seconds());
    const VolumeMeshStats& ms = m.mesh.stats;
    report.mesh_stages["order"] = ms.order_seconds;
    report.mesh_stages["delaunay"] = ms.delaunay_seconds;
    report.mesh_stages["first_delaunay"] = ms.delaunay.seconds;
    report.mesh_stages["classify"] = ms.classify_seconds;
    report.mesh_stages["recover"] = ms.recover_seconds;
    if (regions) {
      report.mesh_stages["interfaces"] = ms.interface_seconds;
      report.interface_stages["regions"] += ms.interface_seconds;
    }
    MeshReport::Counts& counts = report.counts;
    count_mesh(m.mesh, counts);
    counts.steiner_points = ms.steiner_points;
    counts.dropped_nodes = ms.dropped_nodes;
    counts.buried_nodes = ms.buried_nodes;
    counts.interface_slivers = ms.interface_slivers;
    counts.steiner_rounds = ms.rounds;
    counts.refinements = attempt;
    report.has_mesh = true;

    if (params.improve) {
      clock.reset();
      job.log("improving " + std::to_string(m.mesh.num_tets()) + " tets");
      ImproveOptions io;
      io.measure_stages = false;  // the quality block measures the result
      io.progress = job.progress();
      io.hausdorff_tolerance = params.check.hausdorff_tolerance;
      io.feature_angle = options.feature_angle_deg;
      report.improve = improve_mesh(m.mesh, {surface, query, m.sizing, regions}, io);
      job.add_seconds("improve", clock.seconds());
      count_mesh(m.mesh, counts);
    }

    clock.reset();
    job.log("checking the mesh");
    m.check = check_volume_mesh(m.mesh, {surface, query, m.sizing, regions}, params.check);
    job.add_seconds("mesh_check", clock.seconds());
    if (regions) report.interface_stages["check"] += m.check.interface_seconds;
    if (kept && !m.check.ok() && (!m.check.only_sizing_failures() || attempt >= params.max_refinements))
      return kept->restore(job, "its mesh check failed");
    if (m.check.ok() && report.improve) {
      const ImproveStats& st = *report.improve;
      if (kept && !better_quality(st, kept->improve))
        return kept->restore(job, "its worst tet is " + format_sine_deg(st.worst_sine) + " with " +
                                      std::to_string(st.below_target) + " tet(s) below the target, not better");
      if (st.below_target == 0 || st.below_target > kQualityRefinementPlaces || quality_tries == kQualityRefinements ||
          attempt >= params.max_refinements || sine_deg(st.worst_sine) >= input_angle - 1e-6)
        return m;
      const std::size_t added = refine_at(st.below_target_at, m.sizing, options);
      if (added == 0) return m;
      ++quality_tries;
      job.notice("quality: " + std::to_string(st.below_target) + " tet(s) below " +
                 format_deg(ImproveOptions{}.target_angle) + " after the quality pass, the worst " +
                 format_sine_deg(st.worst_sine) + first_place(st.below_target_at) + ": size halved around " +
                 std::to_string(added) + " of them, meshing again (refinement " + std::to_string(attempt + 1) + ")");
      kept = QualityKept{std::move(m), report.counts, report.mesh_stages, st};
      continue;
    }
    if (m.check.ok() || !m.check.only_sizing_failures()) return m;
    const std::size_t added = attempt < params.max_refinements ? refine_at(m.check.refine_at, m.sizing, options) : 0;
    if (added == 0 && kept) return kept->restore(job, "its mesh check failed");
    if (added == 0) return m;  // the caller reports the failed check
    job.notice("the mesh check found the boundary too far from the surface at " +
               std::to_string(m.check.refine_at.size() / 3) + " place(s)" + first_place(m.check.refine_at) +
               (m.check.volume_off ? " (volume off by " + std::to_string(100 * m.check.volume_error) + "%)" : std::string()) +
               ": size halved around " + std::to_string(added) + " of them, meshing again (refinement " +
               std::to_string(attempt + 1) + ")");
  }
}

/// Repairs (opt-in) and prepares one surface, read from `input`.
PreparedSurface prepare_one(const Job& job, SurfaceMesh raw, const std::string& input, const SurfaceOptions& so) {
  const MeshParams& params = job.params;
  MeshReport& report = job.report;
  if (params.repair.any()) {
    SurfaceRepairReport rep;
    raw = repair_surface(std::move(raw), params.repair, rep);
    for (const std::string& n : rep.notes) so.notice(n);
    if (rep.changed()) so.notice("facet ids in later messages about " + input + " refer to the repaired surface");
    if (!report.repairs) report.repairs = SurfaceRepairReport{};
    report.repairs->add(rep);  // summed over the bodies
  }
  return prepare_with_hint(std::move(raw), input, params, so);
}

/// Repairs (opt-in) and prepares the surface, or each named body's and joins them; fills the
/// surface figures of the report.
PreparedSurface prepare(const Job& job, std::vector<NamedSurface> bodies, bool named, const ModelRanges& ranges) {
  const MeshParams& params = job.params;
  MeshReport& report = job.report;
  Stopwatch clock;
  std::size_t points = 0, facets = 0;
  for (const NamedSurface& b : bodies) points += b.surface.points.size(), facets += b.surface.num_tris();
  job.log("preparing the surface (" + std::to_string(points) + " points, " + std::to_string(facets) + " facets" +
          (named ? ", " + std::to_string(bodies.size()) + " named bodies)" : ")"));
  if (!ranges.note.empty()) job.notice(ranges.note);
  SurfaceOptions so;
  so.scale = params.scale;
  so.notice = [&job](const std::string& n) { job.notice(n); };
  PreparedSurface surface;
  if (!named) {
    surface = prepare_one(job, std::move(bodies[0].surface), params.input, so);
  } else {
    std::vector<PreparedSurface> parts;
    std::vector<std::string> names, inputs;
    for (NamedSurface& b : bodies) {
      parts.push_back(prepare_one(job, std::move(b.surface), b.input, so));
      report.bodies.push_back({b.name, b.input, parts.back().volume, 0, 0, 0});
      names.push_back(b.name);
      inputs.push_back(b.input);
    }
    Stopwatch imprint;
    surface = join_bodies(std::move(parts), names, inputs);
    if (!surface.interfaces.empty()) report.interface_stages["imprint"] = imprint.seconds();
  }
  report.seconds["prepare"] = clock.seconds();
  report.counts.surface_points = surface.mesh.points.size();
  report.counts.surface_facets = surface.mesh.num_tris();
  report.counts.shells = surface.shell_body.size();
  report.counts.bodies = surface.num_bodies;
  report.counts.interface_facets = surface.interfaces.mesh.num_tris();
  report.solid_volume = surface.volume;
  for (int k = 0; k < 3; ++k) report.bbox_min[k] = surface.bbox_min[k], report.bbox_max[k] = surface.bbox_max[k];
  report.has_surface = true;
  return surface;
}

/// Each named body's region against its solid: the check's volume of the region and its tet
/// count into the report; a region whose volume is off beyond the check's tolerance is a
/// failure of the check.
void check_body_volumes(const Job& job, const VolumeMesh& mesh, MeshCheck& check) {
  std::vector<MeshReport::Body>& bodies = job.report.bodies;
  if (bodies.empty()) return;
  for (MeshReport::Body& b : bodies) b.mesh_volume = 0, b.tets = 0;
  for (const std::uint32_t r : mesh.tet_region) {
    if (r >= bodies.size()) throw Error("internal error: a tet in region " + std::to_string(r));
    ++bodies[r].tets;
  }
  for (std::size_t r = 0; r < bodies.size() && r < check.region_volume.size(); ++r)
    bodies[r].mesh_volume = check.region_volume[r];
  for (MeshReport::Body& b : bodies) {
    b.volume_error = std::abs(b.mesh_volume - b.solid_volume) / b.solid_volume;
    if (!(b.volume_error <= job.params.check.volume_tolerance)) {
      std::ostringstream s;
      s << "body '" << b.name << "': its region's volume " << b.mesh_volume << " is off its solid's "
        << b.solid_volume << " by " << b.volume_error << " (tolerance " << job.params.check.volume_tolerance
        << "), in " << b.tets << " tets";
      check.failures.push_back(s.str());
    }
  }
}

/// The sharp features at the job's (crease-lowered) angle, with the creases' notice.
FeatureEdges find_features(const Job& job, const PreparedSurface& surface, const AutoTerms& terms) {
  const MeshParams& params = job.params;
  Stopwatch clock;
  {
    std::ostringstream m;
    m << "sharp features (angle " << terms.feature_angle << " deg)";
    job.log(m.str());
  }
  const std::vector<std::uint32_t> rims = interface_rim_edges(surface);
  FeatureEdges features = detect_sharp_edges(surface.mesh, terms.feature_angle, rims);
  job.report.seconds["features"] = clock.seconds();
  job.report.counts.feature_edges = features.num_edges();
  job.report.counts.feature_corners = features.corners.size();
  job.report.has_features = true;
  if (terms.feature_angle < params.sharp_angle) {
    const std::size_t sharp = detect_sharp_edges(surface.mesh, params.sharp_angle, rims).num_edges();
    if (features.num_edges() > sharp) {
      std::ostringstream m;
      m << "creases: " << features.num_edges() - sharp << " surface edge(s) bent by "
        << terms.feature_angle << " to " << params.sharp_angle
        << " deg are kept as feature edges (a boundary face across them would lie farther than "
        << params.check.hausdorff_tolerance << " h from the surface); auto_creases: false turns this off";
      job.notice(m.str());
    }
  }
  return features;
}

/// The thickness term's sizes (walls and gaps), appended to the derived zones.
void thickness_sizes(const Job& job, const PreparedSurface& surface, const SurfaceQuery& query,
                     double size, SizingOptions& sizing_options) {
  const MeshParams& params = job.params;
  if (!(params.thickness_layers > 0)) return;
  Stopwatch clock;
  ThicknessOptions to;
  to.layers = params.thickness_layers;
  to.max_size = size;
  const ThicknessStats ts = add_thickness_sizes(surface, query, to, sizing_options.derived);
  job.report.seconds["thickness"] = clock.seconds();
  job.report.thickness = ts;
  if (ts.walls + ts.gaps == 0) return;
  std::ostringstream n;
  n.precision(4);
  n << "thickness: the size is reduced";
  if (ts.walls) n << " across " << ts.walls << " facet(s) of walls thinner than " << params.thickness_layers
                  << " x size (thinnest " << ts.min_wall << ")";
  if (ts.gaps) n << (ts.walls ? " and" : "") << " along " << ts.gaps << " facet(s) facing a gap narrower than the size (narrowest "
                 << ts.min_gap << ")";
  n << "; thickness_layers: 0 turns this off";
  job.notice(n.str());
}

/// Boundary patches and feature curves, named groups, and the optional quadratic nodes.
FeMesh fe_groups(const Job& job, const PreparedSurface& surface, const SurfaceQuery& query,
                 const FeatureEdges& features, const VolumeMesh& mesh) {
  const MeshParams& params = job.params;
  MeshReport& report = job.report;
  Stopwatch clock;
  job.log("boundary groups");
  const SurfacePatches patches = segment_surface(surface.mesh, features);
  const BoundaryGroups bg = assign_boundary(mesh, surface.mesh, patches, query);
  report.counts.patches = patches.num_patches;
  report.counts.curves = patches.num_curves();
  report.counts.mesh_feature_edges = bg.edge_curve.size();
  report.boundary = BoundaryGroupsSummary{bg.ok(), bg.topological_faces, bg.geometric_faces, bg.verified_faces,
                                          bg.ambiguous_faces.size(), bg.missing_curve_edges, bg.stray_patch_edges,
                                          bg.empty_patches, bg.empty_curves, bg.problems};
  if (!bg.ok()) {
    std::string what = "job '" + params.name + "': the boundary groups are not certain:";
    for (const std::string& p : bg.problems) what += "\n  " + p;
    throw CheckError(what + "\nno output was written");
  }
  GroupOptions go = params.group_options;
  for (const MeshReport::Body& b : report.bodies) go.body_names.push_back(b.name);
  FeMesh fe = make_fe_mesh(mesh, bg, make_groups(params.groups, surface.mesh, patches, params.sizing.zones,
                                                 surface.num_bodies, go));
  if (!go.body_names.empty()) {  // named bodies: their exteriors and interfaces
    Stopwatch bg_clock;
    add_body_groups(fe, mesh, std::uint32_t(patches.num_patches), go.body_names);
    if (!surface.interfaces.empty()) report.interface_stages["groups"] = bg_clock.seconds();
  }
  if (params.element_order == 2) {
    job.log("quadratic elements");
    report.quadratic = make_quadratic(fe, surface.mesh, query, patches);
  }
  report.seconds["groups"] = clock.seconds();
  report.has_groups = true;
  return fe;
}

MeshResult run(const Job& job, std::vector<NamedSurface> bodies, bool named) {
  const MeshParams& params = job.params;
  MeshReport& report = job.report;
  check_mesh_params(params);  // before any work: numbers in the range the pipeline computes in
  Stopwatch clock;
  // Coordinates after scaling, sizes against the model; the default min_size is raised to
  // the smallest the mesher resolves.
  ModelRanges ranges;
  if (bodies.size() == 1) {
    ranges = check_model_ranges(params, bodies[0].surface);
  } else {
    SurfaceMesh all;  // the points are what counts
    for (const NamedSurface& b : bodies)
      all.points.xyz.insert(all.points.xyz.end(), b.surface.points.xyz.begin(), b.surface.points.xyz.end());
    ranges = check_model_ranges(params, all);
  }
  if (!named && has_nonmanifold_edges(bodies[0].surface)) {
    // Internal walls: one region per cell, joined like touching bodies. Duplicated facets are
    // left to the surface check below (its message, and the repair that removes them).
    std::vector<SurfaceMesh> cells;
    try {
      cells = split_cells(bodies[0].surface, params.input);
    } catch (const SurfaceError& e) {
      if (e.defect() != SurfaceError::Defect::duplicates) throw;
    }
    if (cells.size() > 1) {
      std::vector<NamedSurface> regions;
      for (std::size_t k = 0; k < cells.size(); ++k)
        regions.push_back({"region_" + std::to_string(k + 1), params.input, std::move(cells[k])});
      job.notice("internal walls: the surface bounds " + std::to_string(regions.size()) +
                 " cells, meshed as the regions region_1 to region_" + std::to_string(regions.size()) +
                 " with conforming interfaces");
      bodies = std::move(regions);
      named = true;
    }
  }
  const PreparedSurface surface = prepare(job, std::move(bodies), named, ranges);
  const AutoTerms terms = automatic_terms(params, surface);
  const FeatureEdges features = find_features(job, surface, terms);

  clock.reset();
  const SurfaceQuery query(surface.mesh);
  std::unique_ptr<const RegionQuery> regions;
  if (!surface.interfaces.empty()) regions = std::make_unique<const RegionQuery>(surface);
  report.seconds["query"] = clock.seconds();

  SizingOptions sizing_options = params.sizing;
  sizing_options.max_size = ranges.size;
  sizing_options.min_size = ranges.min_size;
  sizing_options.curvature_angle_deg = params.curvature_angle;
  sizing_options.chordal_deviation = terms.chordal_deviation;
  sizing_options.feature_angle_deg = terms.feature_angle;
  thickness_sizes(job, surface, query, ranges.size, sizing_options);
  Meshed m = mesh_with_refinement(job, surface, query, regions.get(), features, sizing_options);
  check_body_volumes(job, m.mesh, m.check);
  report.check = m.check;
  report.has_check = true;

  clock.reset();
  // The size fidelity reads the mesh only: it runs beside the per-tet measures (both passes
  // leave a core idle much of their time; the paper gear box's quality stage took 8.3 s in a
  // row). Its figures do not depend on the threads.
  // (async | deferred: where no thread can be started, it runs at get(), not throw.)
  std::future<SizeFidelity> fidelity = std::async(std::launch::async | std::launch::deferred, [&m] {
    return measure_size_fidelity(m.mesh.nodes.points, m.mesh.tets, m.sizing);
  });
  // One pass of per-tet measures: the writers' cell data, the summary and each body's extremes
  // (a minimum and a maximum, the same whichever thread meets a tet first; kept as they go,
  // where an array of both for every tet took 16 bytes a tet and a serial pass).
  for (MeshReport::Body& b : report.bodies) b.min_dihedral = 180, b.max_dihedral = 0;
  auto extremes = [&](std::size_t t, const TetQuality& q) {
    if (t >= m.mesh.tet_region.size()) return;
    MeshReport::Body& b = report.bodies[m.mesh.tet_region[t]];
    std::atomic_ref<double> lo(b.min_dihedral), hi(b.max_dihedral);
    for (double now = lo.load(std::memory_order_relaxed);
         q.min_dihedral < now && !lo.compare_exchange_weak(now, q.min_dihedral, std::memory_order_relaxed);) {
    }
    for (double now = hi.load(std::memory_order_relaxed);
         q.max_dihedral > now && !hi.compare_exchange_weak(now, q.max_dihedral, std::memory_order_relaxed);) {
    }
  };
  TetMesh tm = to_tet_mesh(m.mesh, &report.quality, report.bodies.empty() ? TetQualityVisitor() : TetQualityVisitor(extremes));
  report.size_fidelity = fidelity.get();
  report.seconds["quality"] = clock.seconds();
  report.has_quality = true;
  if (!m.check.ok()) {
    std::string what = "job '" + params.name + "': the mesh failed its validity check:";
    for (const std::string& f : m.check.failures) what += "\n  " + f;
    throw CheckError(what + "\nno output was written");
  }
  MeshResult result;
  if (params.fe_groups) result.fe = fe_groups(job, surface, query, features, m.mesh);
  result.mesh = std::move(m.mesh);
  result.tet_mesh = std::move(tm);
  return result;
}

}  // namespace

void check_mesh_params(const MeshParams& params) {
  if (!(params.scale > 0)) throw UsageError("job '" + params.name + "': scale must be > 0");
  if (!(params.sizing.max_size > 0)) throw UsageError("job '" + params.name + "': size must be > 0");
  if (params.element_order != 1 && params.element_order != 2)
    throw UsageError("job '" + params.name + "': element_order must be 1 or 2");
  check_option_ranges(params);
}

MeshResult mesh_solid(SurfaceMesh surface, const MeshParams& params, const MeshCallbacks& callbacks,
                      MeshReport* report) {
  MeshReport local;
  MeshReport& r = report ? *report : local;
  r = MeshReport{};
  const Job job(params, callbacks, r);
  std::vector<NamedSurface> one(1);
  one[0].surface = std::move(surface);
  MeshResult result = run(job, std::move(one), false);
  result.report = r;
  return result;
}

MeshResult mesh_solid(std::vector<NamedSurface> bodies, const MeshParams& params, const MeshCallbacks& callbacks,
                      MeshReport* report) {
  if (bodies.empty()) throw UsageError("job '" + params.name + "': no bodies to mesh");
  for (const NamedSurface& b : bodies)
    if (b.name.empty() || b.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-") !=
                              std::string::npos)
      throw UsageError("job '" + params.name + "': body name '" + b.name + "' must be [A-Za-z0-9_-]+");
  for (std::size_t i = 0; i < bodies.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (bodies[i].name == bodies[k].name)
        throw UsageError("job '" + params.name + "': body '" + bodies[i].name + "' is listed twice");
  MeshReport local;
  MeshReport& r = report ? *report : local;
  r = MeshReport{};
  const Job job(params, callbacks, r);
  MeshResult result = run(job, std::move(bodies), true);
  result.report = r;
  return result;
}

}  // namespace kdmesh
