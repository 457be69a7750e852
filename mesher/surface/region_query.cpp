// kdmesh — which body of an assembly holds a point (mesher/surface/region_query.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/surface/region_query.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace kdmesh {

RegionQuery::RegionQuery(const PreparedSurface& surface) : surface_(surface) {
  const BodyInterfaces& ifc = surface.interfaces;
  if (ifc.empty() || ifc.body_surfaces.size() < 2)
    throw UsageError("RegionQuery: the surface has no interfaces between bodies");
  for (const SurfaceMesh& m : ifc.body_surfaces) {
    body_.push_back(std::make_unique<SurfaceQuery>(m));
    std::array<double, 6> b{INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < m.points.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        b[std::size_t(k)] = std::min(b[std::size_t(k)], m.points.p(std::uint32_t(i))[k]);
        b[std::size_t(k) + 3] = std::max(b[std::size_t(k) + 3], m.points.p(std::uint32_t(i))[k]);
      }
    box_.push_back(b);
  }
  interfaces_ = std::make_unique<SurfaceQuery>(ifc.mesh);
}

RegionQuery::~RegionQuery() = default;

int RegionQuery::region(const double* p) const {
  for (std::size_t k = 0; k < body_.size(); ++k) {
    const std::array<double, 6>& b = box_[k];
    if (p[0] < b[0] || p[1] < b[1] || p[2] < b[2] || p[0] > b[3] || p[1] > b[4] || p[2] > b[5]) continue;
    const int s = body_[k]->side(p);
    if (s > 0) return int(k);
    if (s == 0) return kOnSurface;
  }
  return kOutside;
}

bool RegionQuery::in_body(const double* p, std::uint32_t r) const {
  if (r >= body_.size()) return false;
  const std::array<double, 6>& b = box_[r];
  if (p[0] < b[0] || p[1] < b[1] || p[2] < b[2] || p[0] > b[3] || p[1] > b[4] || p[2] > b[5]) return false;
  return body_[r]->side(p) > 0;
}

}  // namespace kdmesh
