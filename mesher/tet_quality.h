// kdmesh — tetrahedron shape measures and their summaries.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/tet_mesh.h"

namespace kdmesh {

struct TetQuality {
  double volume = 0;          ///< signed (positive for positively oriented tets)
  double min_dihedral = 0;    ///< degrees
  double max_dihedral = 0;    ///< degrees
  double radius_ratio = 0;    ///< gamma = 3 r_in / R_circ, 1 for the regular tet, 0 degenerate
  double radius_edge = 0;     ///< R_circ / shortest edge (sqrt(6)/4 ~ 0.612 regular)
  double volume_length = 0;   ///< 6 sqrt(2) V / l_rms^3, 1 for the regular tet
};

/// The volume-length ratio 6 sqrt(2) V / l_rms^3 of the tet (a, b, c, d): signed (negative
/// when inverted), 1 for the regular tet, 0 when flat. Cheap (no angles).
double volume_length(const double* a, const double* b, const double* c, const double* d);

/// A tet with |volume_length| below this is flat at rounding level: zero volume for FE use
/// (its vertices are coplanar up to the rounding of their coordinates).
inline constexpr double kZeroVolumeLength = 1e-9;

/// A point this close to the surface, relative to the surface's bounding-box diagonal, counts
/// as on it: boundary vertices in the mesh check, tet centroids in the inside/outside
/// classification. Relative to the extent, so independent of scale; the coordinates' rounding
/// (relative to their magnitude) must stay below it, which bounds how far from the origin a
/// model may lie (mesher/numeric_ranges.h, kMaxMagnitudePerExtent), and legitimate tets must
/// be thicker, which bounds the smallest size (kMinSizePerExtent).
inline constexpr double kOnSurfaceDistance = 1e-9;

/// Measures of the tet (a, b, c, d), each pointing to xyz.
TetQuality tet_quality(const double* a, const double* b, const double* c, const double* d);

/// Summary of one measure over a mesh: min, max, mean and a histogram over [lo, hi).
struct Histogram {
  double lo = 0, hi = 1;
  std::vector<std::uint64_t> counts;  ///< equal-width bins; values outside clamp to the ends
};

struct QualitySummary {
  std::size_t tets = 0;
  std::size_t inverted = 0;           ///< volume <= 0
  double min_dihedral = 0, max_dihedral = 0;  ///< extremes over the mesh (degrees)
  double mean_radius_ratio = 0, min_radius_ratio = 0;
  double max_radius_edge = 0;
  double mean_volume_length = 0, min_volume_length = 0;
  Histogram min_dihedral_hist;        ///< per-tet min dihedral, [0, 90) degrees, 18 bins
  Histogram radius_ratio_hist;        ///< [0, 1], 10 bins
};

/// Called with each tet's index and measures, from several threads (each tet once).
using TetQualityVisitor = std::function<void(std::size_t, const TetQuality&)>;

/// Per-tet measures of the tets (4 ids each into `points`), parallel over tets and handed
/// to `each` if set, and their summary. The sums run over fixed blocks of tets added in
/// order, so the summary does not depend on the number of threads.
QualitySummary summarize_quality(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                 const TetQualityVisitor& each = {});
/// The same for a TetMesh, keeping every tet's measures in *per_tet if not null.
QualitySummary summarize_quality(const TetMesh& mesh, std::vector<TetQuality>* per_tet = nullptr);

}  // namespace kdmesh
