// kdmesh — the front door: one in-memory call for the whole pipeline (issue 20).
//   surface -> prepared surface -> features -> sizing field -> nodes -> volume mesh ->
//   quality improvement -> mesh check -> quality figures -> [boundary groups, quadratic nodes]
// No files, no JSON, no exit codes: the CLI, the batch runner and the Python module are thin
// layers over mesh_solid (tools/app/mesh_job.h reads and writes the files around it).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/fe_mesh.h"
#include "core/surface_mesh.h"
#include "core/tet_mesh.h"
#include "mesher/fe/boundary_groups.h"
#include "mesher/fe/fe_assembly.h"
#include "mesher/quality/mesh_check.h"
#include "mesher/improve/mesh_improve.h"
#include "mesher/order/order.h"
#include "mesher/tet_quality.h"
#include "mesher/resource_estimate.h"
#include "mesher/quality/size_fidelity.h"
#include "mesher/surface/surface_bodies.h"
#include "mesher/surface/surface_repair.h"
#include "mesher/surface/thickness_sizes.h"
#include "mesher/volume/volume_mesh.h"
#include "sizing/sizing_field.h"

namespace kdmesh {

/// Everything the pipeline needs besides the surface (the `kdmesh mesh` options; one entry of
/// a batch file; tools/app/job_config.h has the YAML schema, key for key).
struct MeshParams {
  std::string name = "mesh";   ///< job name (messages)
  /// Where the surface came from (a file path when it was read from one): messages and
  /// surface errors name it. The front door never opens it.
  std::string input = "surface";
  double scale = 1;            ///< coordinates are multiplied by it (> 0)
  double sharp_angle = 30;     ///< degrees; feature edges kept in the mesh; 0 = none
  SizingOptions sizing;        ///< max_size (> 0) is the job's `size`
  OrderOptions order;          ///< insertion order; order.seed == seed
  std::uint64_t seed = 1;      ///< node placement and order seed
  bool check_tetgen = false;   ///< compare the nodes' Delaunay with TetGen 1.5 and CGAL 5.5 (tools layer)
  bool check_delaunay = false; ///< exact validity check of the nodes' Delaunay (tools layer)
  /// Memory limit in bytes: the job is refused (ResourceError, exit 7) before node placement
  /// when its estimated peak memory exceeds it. 0 = the machine's physical memory; < 0 = none.
  double max_memory = 0;
  SurfaceRepairOptions repair; ///< opt-in safe surface repairs, reported as notices
  /// Automatic sizing terms, on by default; each is announced by a notice when it shrinks the
  /// size below what the job asks (never below sizing.min_size):
  ///  - curvature: h <= curvature_angle (degrees, as radians) x the local radius of curvature
  ///    of the smooth surface; 0 = off;
  ///  - chordal deviation: the boundary facets' mean depth below the curved surface stays within
  ///    a share of the volume tolerance (chordal_deviation < 0: derived from
  ///    check.volume_tolerance; 0 = off; > 0: that depth in model units);
  ///  - creases: surface edges bent by more than the angle at which a boundary face across
  ///    them would leave the distance tolerance become feature edges (kept by nodes), even
  ///    below sharp_angle.
  ///  - thickness: walls get at least thickness_layers tets across, and gaps (slots, holes,
  ///    close sheets) boundary nodes no farther apart than the gap; 0 = off.
  double curvature_angle = 15;
  double chordal_deviation = -1;
  bool auto_creases = true;
  double thickness_layers = 2;
  /// The mesh check's tolerances (mesher/quality/mesh_check.h); the sizing aims inside them.
  MeshCheckOptions check;
  /// Local refinement: when the boundary cannot be recovered, or the check finds faces too far
  /// from the surface or the volume off, the size is halved around those places and the job
  /// meshed again, at most this many times (and never below sizing.min_size). The same budget
  /// covers quality refinement: up to 2 rounds around isolated tets the quality pass left below
  /// its 12 deg target, keeping the better mesh (mesher/mesh_solid.cpp); 0 turns both off.
  int max_refinements = 8;
  bool improve = true;         ///< quality improvement after meshing (mesher/improve/mesh_improve.h)
  /// Boundary groups (patches, feature curves, named groups) and the FE mesh (MeshResult::fe):
  /// what the solver formats need. Off: MeshResult::fe stays empty.
  bool fe_groups = false;
  int element_order = 1;       ///< 1 (tet4) or 2 (tet10, mid-edge nodes on the surface) in fe
  std::vector<GroupSpec> groups;  ///< named boundary groups (mesher/fe/boundary_groups.h)
  GroupOptions group_options;     ///< automatic patch_<i> / curve_<i> groups
};

/// Thrown when MeshCallbacks::cancel asked the job to stop. No state is left behind: the job's
/// data are all local to the call.
class CancelledError : public Error {
 public:
  explicit CancelledError(const std::string& msg) : Error(msg, ExitCode::cancelled) {}
};

/// Callbacks of a running job; each may be empty. They are called from the calling thread.
struct MeshCallbacks {
  /// A stage starts or a notice is emitted (one line, no trailing newline).
  std::function<void(const std::string& message)> log;
  /// Progress inside a long stage: stage name ("interior", "delaunay", ...) and fraction in [0, 1].
  std::function<void(const std::string& stage, double fraction)> progress;
  /// Asked at every stage and progress step; true stops the job with CancelledError.
  std::function<bool()> cancel;
};

/// The boundary groups' verification (mesher/fe/boundary_groups.h), without the per-face arrays.
struct BoundaryGroupsSummary {
  bool pass = false;
  std::size_t topological_faces = 0, geometric_faces = 0, verified_faces = 0, ambiguous_faces = 0;
  std::size_t missing_curve_edges = 0, stray_patch_edges = 0, empty_patches = 0, empty_curves = 0;
  std::vector<std::string> problems;
};

/// What the pipeline measured. Stages the job never reached keep their `has_` flag false.
struct MeshReport {
  struct Counts {
    std::size_t surface_points = 0, surface_facets = 0, shells = 0, bodies = 0;
    std::size_t interface_facets = 0;  ///< touching bodies: facets between two (imprinted, once each)
    std::size_t feature_edges = 0, feature_corners = 0, placed_nodes = 0, nodes = 0;
    std::array<std::size_t, 4> nodes_by_kind{};  ///< corner, edge, surface, interior
    std::size_t steiner_points = 0, dropped_nodes = 0, buried_nodes = 0, tets = 0, boundary_faces = 0;
    std::size_t interface_slivers = 0;  ///< flat tets on interfaces split by a Steiner point
    int steiner_rounds = 0, refinements = 0;
    std::size_t patches = 0, curves = 0, mesh_feature_edges = 0;  ///< with fe_groups
  };
  /// The stages reached, in order ("prepare", "features", "mesh", "improve", "check",
  /// "quality", "groups"): which figures below are meaningful.
  bool has_surface = false, has_features = false, has_estimate = false, has_mesh = false;
  bool has_check = false, has_quality = false, has_groups = false;
  Counts counts;
  double solid_volume = 0;
  std::array<double, 3> bbox_min{}, bbox_max{};
  std::optional<SurfaceRepairReport> repairs;  ///< when a repair was asked
  ResourceEstimate estimate;
  double memory_limit = 0;                     ///< bytes; 0 = none
  /// The automatic sizing terms as used (first attempt).
  double curvature_angle = 0, chordal_deviation = 0, feature_angle = 0;
  SizingAutoStats auto_sizing;
  bool has_auto_sizing = false;
  std::optional<ThicknessStats> thickness;
  std::optional<ImproveStats> improve;
  MeshCheck check;
  QualitySummary quality;
  SizeFidelity size_fidelity;
  std::optional<BoundaryGroupsSummary> boundary;  ///< with fe_groups
  std::optional<QuadraticStats> quadratic;        ///< with fe_groups and element_order 2
  /// Seconds per stage: read (by the caller), prepare, features, sizing, query, estimate,
  /// thickness, place, mesh, improve, mesh_check, quality, groups, ...; summed over attempts.
  std::map<std::string, double> seconds;
  /// The volume mesher's own stages (order, delaunay, first_delaunay, classify, recover).
  std::map<std::string, double> mesh_stages;
  /// Touching bodies: the seconds of the work interfaces add, inside the stages above, summed
  /// over attempts: imprint (joining the bodies, in prepare), place (sampling the interfaces and
  /// the fill's combined surface), regions (tet regions and the faces between them judged, in
  /// mesh), check (the interface faces' checks, in mesh_check) and groups (body groups).
  std::map<std::string, double> interface_stages;
  std::vector<std::string> notices;
  /// Named bodies (mesh_solid on a list of them), one per region, in region order: the solid's
  /// volume, the mesh's volume and tets in that region (filled with the mesh check), and the
  /// smallest and largest dihedral angle of its tets (degrees; with the quality figures).
  struct Body {
    std::string name, input;
    double solid_volume = 0, mesh_volume = 0, volume_error = 0;  ///< error: |mesh - solid| / solid
    std::size_t tets = 0;
    double min_dihedral = 0, max_dihedral = 0;
  };
  std::vector<Body> bodies;
};

struct MeshResult {
  /// Nodes (with kind, facet and target size), tets, their regions (body ids), and the
  /// boundary faces (outward) with their tets.
  VolumeMesh mesh;
  /// The same nodes and tets with their point data (node_kind, target_size) and cell data
  /// (region, min_dihedral, radius_ratio): what write_vtu writes.
  TetMesh tet_mesh;
  /// The FE view (with fe_groups): tets and faces by entity, feature-edge segments, named
  /// groups, and with element_order 2 the mid-edge nodes.
  FeMesh fe;
  MeshReport report;
};

/// The checks mesh_solid makes of `params` before any work (scale, size, element_order, and
/// every number within the range the pipeline computes in, mesher/numeric_ranges.h): for
/// callers that want the usage errors before they read a file. UsageError naming the option.
void check_mesh_params(const MeshParams& params);

/// Meshes the solid bounded by `surface`. Throws kdmesh::Error subclasses (UsageError for bad
/// params, SurfaceError for a surface that bounds no solid, GeometryError, ResourceError,
/// CheckError when the mesh check or the boundary groups fail, CancelledError); when `report`
/// is given it is filled as the job goes, so that after an exception it holds what was
/// measured up to the failure (on success it equals the result's report).
MeshResult mesh_solid(SurfaceMesh surface, const MeshParams& params,
                      const MeshCallbacks& callbacks = {}, MeshReport* report = nullptr);

/// Meshes several named solids together (a job's `bodies`): region k of the mesh is bodies[k].
/// Each body's surface is repaired (opt-in) and prepared on its own, so that its errors name
/// its own input and facet ids; then they are joined (join_bodies): bodies whose surfaces meet
/// or that overlap are refused with a BodyContactError naming both and a point. Besides the
/// whole mesh's check, each region's volume must match its body's within
/// params.check.volume_tolerance (else CheckError); MeshReport::bodies has the figures, and with
/// fe_groups the volume groups carry the bodies' names. Throws UsageError for an empty list,
/// or a body name that is empty, repeated or not [A-Za-z0-9_-]+.
MeshResult mesh_solid(std::vector<NamedSurface> bodies, const MeshParams& params,
                      const MeshCallbacks& callbacks = {}, MeshReport* report = nullptr);

}  // namespace kdmesh
