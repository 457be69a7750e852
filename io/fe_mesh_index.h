// kdmesh — FeMesh validation and the entity / group indexes the solver-format writers share
// (internal to io/).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <algorithm>
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

/// {a, b, c} in ascending order (the key of a triangle whatever its orientation).
inline std::array<std::uint32_t, 3> sorted3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::array<std::uint32_t, 3> k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The local face l (0..3) of the tet `tet[0..3]` whose corners local_faces[l] are {a, b, c},
/// or -1 if the three are not all corners of it.
inline int local_face_of(const std::uint32_t* tet, const int (&local_faces)[4][3], std::uint32_t a,
                         std::uint32_t b, std::uint32_t c) {
  const auto want = sorted3(a, b, c);
  for (int l = 0; l < 4; ++l)
    if (sorted3(tet[local_faces[l][0]], tet[local_faces[l][1]], tet[local_faces[l][2]]) == want) return l;
  return -1;
}

/// The owning tet and local face of every face of a dim-2 group (for formats that give a
/// surface as element + local side: Abaqus *SURFACE, Exodus side sets).
struct GroupFaceOwners {
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;
  /// Per face of mesh.faces: its slot (faces with the same corners share one), kNoSlot if the
  /// face is in no group of dim 2.
  std::vector<std::uint32_t> slot_of_face;
  std::vector<std::uint32_t> tet;   ///< per slot: the owning tet
  std::vector<std::uint8_t> face;   ///< per slot: its local face, 0..3, an index into local_faces
};

/// Matches every face of a group of dim 2 to a tet with the same three corners and gives the
/// tet's local face index l (local_faces[l] lists that face's corner positions 0..3, turning so
/// that its right-hand normal points INTO a positively oriented tet). When two tets share the
/// face (an interface), the one the face's normal points out of is taken. Throws
/// UsageError("<who>: face ... is not a face of any tet, so it cannot be part of <purpose>")
/// for a group face that no tet has.
GroupFaceOwners match_group_faces(const FeMesh& mesh, const FeIndex& index, const int (&local_faces)[4][3],
                                  const char* who, const char* purpose);

}  // namespace kdmesh
