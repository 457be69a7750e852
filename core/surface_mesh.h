// kdmesh — triangulated surfaces as plain flat arrays (pipeline input).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

inline constexpr std::uint32_t kNoFacet = std::numeric_limits<std::uint32_t>::max();

/// A triangle surface: points plus 3 point ids per triangle ("facet").
/// tris[3f+0..2] are the corners of facet f; for a prepared surface (mesher/surface/surface_prepare.h)
/// every facet is counter-clockwise seen from outside the solid, i.e. its normal
/// (b-a)x(c-a) points out.
struct SurfaceMesh {
  PointSet points;
  std::vector<std::uint32_t> tris;  ///< 3 per facet

  std::size_t num_tris() const { return tris.size() / 3; }
  const std::uint32_t* tri(std::size_t f) const { return tris.data() + 3 * f; }
};

}  // namespace kdmesh
