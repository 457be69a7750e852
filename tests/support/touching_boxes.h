// kdmesh tests — two touching bodies, the boxes [0,1]^3 and [1,2]x[0,1]^2 joined with their
// interface x = 1, with the queries and a uniform field of size 0.1 a Domain needs.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <utility>
#include <vector>

#include "mesher/domain.h"
#include "mesher/surface/region_query.h"
#include "mesher/surface/surface_bodies.h"
#include "mesher/surface/surface_prepare.h"
#include "mesher/surface/surface_query.h"
#include "sizing/sizing_field.h"
#include "tests/support/box_surface.h"

namespace kdmesh::test {

struct TouchingBoxes {
  PreparedSurface surface;
  SurfaceQuery query;
  RegionQuery regions;
  SizingField sizing;
  TouchingBoxes() : surface(join()), query(surface.mesh), regions(surface), sizing(field(surface)) {}
  Domain domain() const { return {surface, query, sizing, &regions}; }

 private:
  static PreparedSurface join() {
    std::vector<PreparedSurface> parts;
    parts.push_back(prepare_surface(box_surface({0, 0, 0}, {1, 1, 1}), "a.stl"));
    parts.push_back(prepare_surface(box_surface({1, 0, 0}, {2, 1, 1}), "b.stl"));
    return join_bodies(std::move(parts), {"a", "b"}, {"a.stl", "b.stl"});
  }
  static SizingField field(const PreparedSurface& s) {
    SizingOptions so;
    so.max_size = 0.1;
    return build_sizing_field(s.mesh, so);
  }
};

}  // namespace kdmesh::test
