// kdmesh — the facet groups of named bodies: each body's exterior and, where bodies touch,
// the interfaces between them (pipeline stage: FeMesh -> FeMesh, after make_fe_mesh).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/fe_mesh.h"
#include "mesher/volume/volume_mesh.h"

namespace kdmesh {

struct BodyGroupStats {
  std::size_t interface_faces = 0;  ///< faces between two regions, added to the FeMesh
  std::size_t interfaces = 0;       ///< pairs of bodies that share faces
};

/// Adds to `fe` (from make_fe_mesh on `mesh`, whose faces are its boundary faces with their
/// patch ids below num_patches):
///  - per body b with boundary faces, the dim-2 group `<name>-exterior`: the patches of its
///    boundary faces (a patch never spans two bodies: where an interface meets the outer
///    surface is a feature curve);
///  - per pair of bodies a < b sharing faces (touching bodies), those faces, each once and
///    oriented out of a, as the new surface entity num_patches + k (k: the pairs in order),
///    and the dim-2 group `<name a>-<name b>`.
/// `names` has one name per region. Throws UsageError when a name is missing, or when such a
/// group's name is already a dim-2 group's (e.g. a user group named like it).
BodyGroupStats add_body_groups(FeMesh& fe, const VolumeMesh& mesh, std::uint32_t num_patches,
                               const std::vector<std::string>& names);

}  // namespace kdmesh
