// kdmesh — cross-section of a closed surface's solid with a plane, and a point-in-section test.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/surface_mesh.h"

namespace kdmesh {

/// The boundary curve of (plane ∩ solid) for a closed, outward-oriented surface: one segment per
/// surface triangle the plane cuts.
///
/// Classification is per surface point, by the sign of s = (p - origin)·normal computed once per
/// point; s >= 0 counts as above (a symbolic shift of the plane by an infinitesimal amount along
/// -normal), so every point is on exactly one side and no tolerance is involved. A triangle whose
/// points are not all on one side contributes the segment joining the crossing points of its two
/// mixed edges. The crossing point of an edge is computed once per edge from its endpoints in id
/// order (it is the point itself when s = 0), so segments of neighbouring triangles share exact
/// coordinates and a closed 2-manifold surface yields closed loops. Facets lying in the plane
/// contribute nothing themselves; their edges do, through the neighbouring facets. When that cut
/// is empty, the cut is redone with s = 0 counted as below (the opposite shift), so a plane
/// through a face of a cube gives that face whichever way its normal points. Empty only when the
/// plane does not meet the surface.
struct PlaneSection {
  double origin[3] = {0, 0, 0};
  double normal[3] = {0, 0, 1};  ///< unit
  double u[3] = {1, 0, 0};       ///< unit, ⟂ normal: first in-plane axis
  double v[3] = {0, 1, 0};       ///< unit, normal × u: second in-plane axis
  std::vector<double> xyz;       ///< 3 per crossing point (model units)
  std::vector<double> uv;        ///< 2 per crossing point: ((p-origin)·u, (p-origin)·v)
  std::vector<std::uint32_t> segs;  ///< 2 crossing-point ids per segment; zero-length ones dropped

  std::size_t num_segments() const { return segs.size() / 2; }
  bool empty() const { return segs.empty(); }
};

/// Cuts `surface` with the plane through `origin` with normal `normal` (any non-zero length;
/// the caller checks it is non-zero and finite). Facets with out-of-range point ids are skipped.
PlaneSection cut_with_plane(const SurfaceMesh& surface, const double origin[3],
                            const double normal[3]);

/// Point-in-region test in the section's (u, v) coordinates by crossing parity of a +u ray with
/// the section segments (half-open rule on v, so shared loop vertices are counted once).
/// Accelerated by slabs in v: each query scans only the segments whose v-range meets its slab.
/// Immutable after construction; const queries are thread-safe.
class SectionLocator {
 public:
  SectionLocator() = default;
  explicit SectionLocator(const PlaneSection& section);
  /// True if (pu, pv) is inside the region bounded by the section loops (odd crossing count).
  bool contains(double pu, double pv) const;
  /// Bounding box of the section in (u, v): {umin, umax, vmin, vmax}.
  const double* bbox() const { return bbox_; }

 private:
  double bbox_[4] = {0, -1, 0, -1};  // empty
  double inv_slab_ = 0;
  std::uint32_t num_slabs_ = 0;
  std::vector<double> seg_uv_;              // 4 per segment: ua, va, ub, vb
  std::vector<std::uint32_t> slab_start_;   // num_slabs_ + 1 offsets into slab_segs_
  std::vector<std::uint32_t> slab_segs_;    // segment ids, slab by slab
  std::uint32_t slab_of(double pv) const;
};

}  // namespace kdmesh
