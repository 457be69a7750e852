// kdmesh — the ranges of a job's numbers inside which the pipeline is exact and finite; a job
// outside them is refused with an error naming the option, before any work that could trap,
// overflow or loop without bound.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include "core/surface_mesh.h"
#include "mesher/tet_quality.h"
#include "mesher/mesh_solid.h"

namespace kdmesh {

// The pipeline is scale-invariant: scaling a model and its sizes by a power of two gives the
// same mesh, every coordinate scaled exactly (ExtremeNumbers.PowerOfTwoScalesGiveTheSameMesh,
// over the whole range of the length bounds below). Two places were not, up to issue 19: the
// inside/outside test and the thickness rays, which both built rays from directions of
// length 1 (mesher/surface/surface_query.cpp: ray_parity::side, SurfaceQuery::ray_distance); that is what lost a 6e15 cube's
// corner nodes, and why the former bound of 2^50 on coordinates had been measured. The bounds
// on lengths below (kMaxLength, kMinLength, kMaxMagnitudePerExtent, kMinSizePerExtent) are
// derived from the arithmetic, each formula next to its constant.

/// Largest length of a job: |coordinate| of the scaled model and of every zone, and size (zone
/// sizes are clamped to it). Two representations meet at 2^120:
///  - target sizes are stored per node as float (NodeSet::size): below FLT_MAX ~ 2^128;
///  - the highest-degree floating-point expression of the pipeline has degree 8 in lengths:
///    tet_sine (mesher/improve/improve_quality.h) multiplies the four face-normal lengths |n| <= L^2
///    (and det m, L^3 L^5) of tets whose edges L are at most the bounding-box diagonal
///    <= 2 sqrt(3) M. (2 sqrt(3) 2^120)^8 = 2^974.4, 2^49 below DBL_MAX ~ 2^1024 for sums and
///    constant factors. The rest is of lower degree (tet_quality 4, volumes 3, CGAL's
///    constructions at most 4; the kernel's predicates guard their own ranges and fall back
///    to exact arithmetic).
constexpr double kMaxLength = 0x1p120;  // 1.33e36
/// Smallest length: the model's extent (bounding-box diagonal) and min_size. The mirror of
/// kMaxLength: float sizes stay normal (>= FLT_MIN = 2^-126, full precision) and degree-8
/// products of edges >= 0.7 x 2^-120 (surface nodes keep 0.7 h apart) stay >= 2^-965, normal
/// doubles (>= 2^-1022) with 2^57 to spare for flat tets.
constexpr double kMinLength = 0x1p-120;  // 7.5e-37
static_assert(kMaxLength < 0x1p128 && kMinLength >= 0x1p-126, "sizes are stored as float");
/// Largest magnitude M of the coordinates relative to the extent D (the diagonal): how far
/// from the origin a model may lie. A surface node is placed on a facet by a rounded
/// construction, and the mesh check measures its distance by another (CGAL's closest point):
/// each rounds every coordinate to ulp(M)/2 <= 2^-53 M, so a node exactly on the facet in
/// real numbers measures up to 2 ulp(M) = 2^-51 M off it. The check (and the classification
/// of flat surface tets) calls a point on the surface within kOnSurfaceDistance x D
/// (mesher/tet_quality.h), so 2^-51 M <= 1e-9 D: M / D <= 1e-9 x 2^51 = 2.25e6; the power of two
/// below is 2^21 = 2.10e6. (The block, D = 173, moved by 1e8 meshes; moved by 1e9,
/// M / D = 5.8e6, its check found nodes 2 ulp = 2.4e-7 > 1.7e-7 off the surface.)
constexpr double kMaxMagnitudePerExtent = 0x1p21;
static_assert(kMaxMagnitudePerExtent * 0x1p-51 <= kOnSurfaceDistance);
/// Smallest min_size relative to the extent D. The classification takes a tet whose four
/// vertices are surface nodes for a flat sliver, outside, when its centroid lies within
/// kOnSurfaceDistance x D of the surface (mesher/volume/volume_mesh.cpp). A tet inside the solid has
/// its centroid at least min_i height_i / 4 >= r_in / 2 deep (no face has more than half the
/// tet's area), r_in = rho R / 3 for radius ratio rho, R >= L_max / 2, and L_max >= 0.7 h
/// (surface node spacing): depth >= rho 0.7 h / 12. The one choice is the radius ratio to
/// protect, 1/8: below the smallest in the shipped models' meshes (0.139, the gear box at size
/// 12). For no tet of radius ratio >= 1/8 to be taken for flat: h >= 1e-9 D x 12 x 8 / 0.7 =
/// 1.37e-7 D; the power of two above is 2^-22 = 2.38e-7. (A cube with point zones of size h
/// at two corners meshes at h = 45 x 1e-9 D and fails its boundary recovery at 5.6 x 1e-9 D,
/// where every tet there is thinner.) With M <= 2^21 D it also keeps h_min >= 2^-43 M =
/// 2^9 ulp(M) or more. This replaces the former bound 2^-40 x M, which was chosen, not
/// derived, and let such jobs through (exit 4 after 18 s instead of a usage error).
constexpr double kMinSizePerExtent = 0x1p-22;
static_assert(kMinSizePerExtent * 0.7 / (12 * 8) >= kOnSurfaceDistance);
/// Gradations must be below this, derived from what the field asks of a mesh. The size is
/// s + g d at distance d from a zone of size s, and a mesh follows it when an edge's length
/// is the size at its midpoint (mesher/quality/size_fidelity.h). An edge of length L leaving the zone
/// has the size s + g L / 2 at its midpoint: L = s + g L / 2 has the solution
/// L = s / (1 - g / 2) only for g < 2. At g >= 2 every such edge is shorter than its size,
/// whatever its length (the ratio L / (s + g L / 2) stays below 2 / g <= 1), so no mesh follows
/// the field. Below 2 the work stays bounded by the node count: the surface sweep bisects
/// only where the size's lower bound over a piece is under half its centre's
/// (mesher/placement/surface_sampling.cpp), and the spacing grid skips levels of cell size below
/// h (1 - g beta / 2) / (2 (1 + g beta / 2)), at least h (1 - beta) / (2 (1 + beta)) for
/// beta < 1 (1/18 of h at the surface's beta 0.8; mesher/placement/spacing_grid.h). (This replaced "at most 2", a chosen bound, issue 19; the sweep's
/// former split grew its work as g^2 and took minutes at g = 50.)
constexpr double kMaxGradation = 2;

/// Checks the job's option values alone (before reading anything): size, min_size, gradation,
/// scale and sharp_angle finite and in range; zone sizes, coordinates and radii finite, the
/// coordinates within kMaxLength. UsageError (exit 2) naming the option.
void check_option_ranges(const MeshParams& job);

/// Checks the model once read, after scaling (before it is prepared): every coordinate times
/// job.scale within kMaxLength, the extent at least kMinLength, the coordinates within
/// kMaxMagnitudePerExtent times the extent, size within kMaxLength, and a given min_size at
/// least kMinLength and kMinSizePerExtent times the extent. A size above the extent (the
/// bounding-box diagonal) is the extent: no element can be larger than the model, so the
/// job is meshed at the extent, the coarsest, with a note (this replaced a refusal above 1e3
/// times the extent, a bound that had been chosen, not derived: issue 19).
/// InputError (exit 3) naming the file for coordinates, UsageError (exit 2) naming the option
/// for sizes. The default min_size (size / 1000, also when a batch job sets no min_size) is
/// not the user's number: below that floor it is raised to it, with a note.
struct ModelRanges {
  double size = 0;      ///< the size to mesh with (the job's, at most the extent)
  double min_size = 0;  ///< the min_size to mesh with
  std::string note;     ///< a notice when the size was lowered or the default min_size raised, else empty
};
ModelRanges check_model_ranges(const MeshParams& job, const SurfaceMesh& raw);

}  // namespace kdmesh
