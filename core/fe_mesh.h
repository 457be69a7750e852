// kdmesh — a finite-element mesh with named groups: what the solver-format writers consume.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_set.h"

namespace kdmesh {

/// A named group of entities of one dimension (a Gmsh physical group, an Abaqus ELSET /
/// SURFACE / NSET, a MEDIT reference set). `entities` are entity ids of that dimension:
/// dim 3 volumes (tet_entity values), dim 2 surface patches (face_entity values), dim 1
/// feature curves (edge_entity values).
struct FeGroup {
  std::string name;                   ///< unique per dimension; [A-Za-z0-9_-] only
  int dim = 3;                        ///< 3, 2 or 1
  std::vector<std::uint32_t> entities;
};

/// Linear (order 1) or quadratic (order 2) tetrahedra with their boundary triangles and feature
/// edges, each element tagged with the entity (volume, surface patch, curve) it belongs to.
///
/// Node order within an element is VTK's, which is also Abaqus's (C3D4 / C3D10):
///  - tet:  c0 c1 c2 c3, then for order 2 the mid-edge nodes of (0,1) (1,2) (2,0) (0,3) (1,3) (2,3);
///    positively oriented: c3 lies on the side (c1-c0)x(c2-c0) points to (core/tet_mesh.h);
///  - face: c0 c1 c2, then for order 2 the mid-edge nodes of (0,1) (1,2) (2,0); the normal
///    (c1-c0)x(c2-c0) points out of the solid;
///  - edge: c0 c1, then for order 2 the mid-edge node.
/// Writers convert to their format's order where it differs (e.g. Gmsh's tet10).
struct FeMesh {
  PointSet points;
  int order = 1;                          ///< 1 or 2
  std::vector<std::uint32_t> tets;        ///< 4 (order 1) or 10 (order 2) node ids per tet
  std::vector<std::uint32_t> tet_entity;  ///< volume entity per tet (e.g. the body id)
  std::vector<std::uint32_t> faces;       ///< 3 or 6 node ids per boundary triangle
  std::vector<std::uint32_t> face_entity; ///< surface patch per boundary triangle
  std::vector<std::uint32_t> edges;       ///< 2 or 3 node ids per feature-edge segment
  std::vector<std::uint32_t> edge_entity; ///< feature curve per segment
  std::vector<FeGroup> groups;            ///< named groups, any dimension

  int tet_nodes() const { return order == 2 ? 10 : 4; }
  int face_nodes() const { return order == 2 ? 6 : 3; }
  int edge_nodes() const { return order == 2 ? 3 : 2; }
  std::size_t num_tets() const { return tets.size() / tet_nodes(); }
  std::size_t num_faces() const { return faces.size() / face_nodes(); }
  std::size_t num_edges() const { return edges.size() / edge_nodes(); }
};

}  // namespace kdmesh
