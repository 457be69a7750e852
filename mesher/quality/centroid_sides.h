// kdmesh — the side of the surface of every tet's centroid, exact, with one inside test per
// connected set of tets instead of one per tet.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/point_set.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_query.h"

namespace kdmesh {

/// Two tets that share a face. (Trivial: arrays of them can be left unwritten until filled.)
struct TetPair {
  std::uint32_t first, second;
};

/// +1 strictly inside, -1 strictly outside, 0 on the surface, for the centroid of every tet
/// (4 ids each into `points`); the same answers as SurfaceQuery::side on each centroid.
/// Two tets that share a face (a pair of `neighbours`) carry one side when the closed
/// segment between their centroids meets no facet (SurfaceQuery::segment_clear, exact): the
/// side of a closed surface changes only across it. So the tets fall into sets joined by
/// clear segments, and each set costs one inside test, of its lowest tet. The result does not
/// depend on the order of `neighbours` or on the thread count.
std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        std::span<const TetPair> neighbours,
                                        const SurfaceQuery& query);

/// The same for touching bodies: per tet, 1 when its centroid lies in the body of its region
/// (tet_region, RegionQuery::in_body), 2 when strictly inside the solid but in another body
/// (across an interface), else SurfaceQuery::side (0 or -1). Neighbours of one region carry
/// the answer along a segment that meets neither the surface nor an interface.
std::vector<std::int8_t> centroid_sides(const PointSet& points, const std::vector<std::uint32_t>& tets,
                                        std::span<const TetPair> neighbours,
                                        const SurfaceQuery& query, const RegionQuery& regions,
                                        const std::vector<std::uint32_t>& tet_region);

}  // namespace kdmesh
