// kdmesh — FeMesh validation and the entity / group indexes the solver-format writers share
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/fe_mesh.h"

namespace kdmesh {

/// The distinct entity ids of one dimension and, for each, the elements and groups it has.
struct EntityTable {
  std::vector<std::uint32_t> ids;  ///< distinct entity ids, ascending
  /// Elements of entity ids[k]: element_of[start[k] .. start[k+1]), ascending element index.
  std::vector<std::size_t> start;
  std::vector<std::uint32_t> element_of;
  /// Groups listing entity ids[k]: group_of[gstart[k] .. gstart[k+1]), ascending mesh.groups index.
  std::vector<std::size_t> gstart;
  std::vector<std::uint32_t> group_of;

  std::size_t size() const { return ids.size(); }
  /// Position of `id` in ids, or size() if absent.
  std::size_t find(std::uint32_t id) const;
  std::size_t num_elements(std::size_t k) const { return start[k + 1] - start[k]; }
};

/// Entity tables of dimensions 1 (edges), 2 (faces) and 3 (tets); index 0 is unused.
struct FeIndex {
  std::array<EntityTable, 4> dim;
};

/// Checks that `mesh` is consistent and indexes it. Throws UsageError("<who>: ...") naming the
/// first defect: order not 1 or 2; an element array whose length is not a multiple of its
/// node count, or whose entity array has another length; a node id out of range; a non-finite
/// coordinate; a group with dim outside 1..3, an empty or non-[A-Za-z0-9_-] name, a name used
/// twice in one dimension, no entities, or an entity without elements of the group's dimension.
FeIndex index_fe_mesh(const FeMesh& mesh, const char* who);

/// Node count per element of dimension d (1: edges, 2: faces, 3: tets).
inline int nodes_per_element(const FeMesh& m, int d) {
  return d == 3 ? m.tet_nodes() : d == 2 ? m.face_nodes() : m.edge_nodes();
}
/// Connectivity and entity arrays of dimension d.
inline const std::vector<std::uint32_t>& connectivity(const FeMesh& m, int d) {
  return d == 3 ? m.tets : d == 2 ? m.faces : m.edges;
}
inline const std::vector<std::uint32_t>& entity_array(const FeMesh& m, int d) {
  return d == 3 ? m.tet_entity : d == 2 ? m.face_entity : m.edge_entity;
}

/// The sorted distinct node ids used by the elements of group `g` (mesh.groups[g]).
std::vector<std::uint32_t> group_nodes(const FeMesh& mesh, const FeIndex& index, std::size_t g);

}  // namespace kdmesh
