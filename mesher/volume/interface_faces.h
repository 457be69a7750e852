// kdmesh — the faces between regions of touching bodies, the region of every tet, and the
// judgement of those faces against the interfaces (used by the volume mesher when bodies touch).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/tet_mesh.h"
#include "mesher/domain.h"
#include "mesher/node_set.h"
#include "mesher/volume/tet_memo.h"

namespace kdmesh {

inline constexpr std::uint32_t kNoRegion = 0xFFFFFFFFu;

/// The body of every inside tet of `tri` (kNoRegion for the others), decided exactly: each
/// interior node's body (domain.regions), each tet with interior nodes of one body takes it,
/// every other inside tet and every tet next to one of another body asks for its own centroid,
/// and a tet whose answer differs exposes its neighbours to the same test, until nothing
/// changes. `queries` (optional) counts the region queries made.
/// Optional memos, valid while the node ids are (the caller clears them when they change):
/// `memo` holds the tets' answers of earlier calls, and `asked` takes the tets asked now with
/// their answers; `node_regions` holds the regions of the nodes below its size (-1: not
/// interior) and is extended to all nodes.
std::vector<std::uint32_t> label_regions(const Triangulation& tri, const NodeSet& nodes, const Domain& domain,
                                         const std::vector<std::uint8_t>& inside, std::size_t* queries = nullptr,
                                         const TetMemo* memo = nullptr, std::vector<TetMemo::Asked>* asked = nullptr,
                                         std::vector<std::int32_t>* node_regions = nullptr);

/// Faces between inside tets of two different regions, each once: the face of `tet` (the tet
/// of the lower region) opposite its vertex `face`, normal pointing out of it.
struct InterfaceFaces {
  std::vector<std::uint32_t> verts;  ///< 3F point ids
  std::vector<std::uint32_t> tet;    ///< F
  std::vector<std::uint8_t> face;    ///< F
  std::size_t size() const { return tet.size(); }
};
InterfaceFaces interface_faces(const Triangulation& tri, const std::vector<std::uint32_t>& label);

/// Judges one face between regions ra and rb: bad (bits of judge_face, mesher/volume/
/// boundary_faces.h) if a vertex is interior-kind, if a vertex is off the interfaces (farther
/// than kOnSurfaceDistance x the bounding box diagonal, the mesh check's rule) or its centroid
/// or an edge midpoint farther than tolerance * h(centroid) from them (kFaceFar), or if the
/// interface closest to its centroid lies between other bodies (kFaceAgainst).
std::uint8_t judge_interface_face(const std::uint32_t* fv, std::uint32_t ra, std::uint32_t rb, const NodeSet& nodes,
                                  const Domain& domain, double tolerance);

/// The faces of `faces` judge_interface_face finds bad (indices), with a reason each.
struct InterfaceJudgement {
  std::vector<std::uint32_t> bad_faces;
  std::vector<std::string> reasons;
};
InterfaceJudgement judge_interfaces(const InterfaceFaces& faces, const Triangulation& tri,
                                    const std::vector<std::uint32_t>& label, const NodeSet& nodes,
                                    const Domain& domain, double tolerance);

}  // namespace kdmesh
